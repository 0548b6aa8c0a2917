"""Ctrl-C (SIGINT) and SIGTERM sent to a long `springsim` command at a random moment, and what
must follow (README, "The command line"): one line on stderr ("interrupted" or "terminated"),
exit code 130 or 143, no traceback, and no file left half-written.

Used by tests/test_signals.py (a few trials a command) and by benchmarks/signals.py (the
issue's count: 50 + 50 on `run`, 10 + 10 on every other long command).
"""
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

SPRINGSIM = [sys.executable, "-m", "springsim"]
# Each command runs far longer than the latest moment a signal is sent, so every trial lands
# in it: start-up, loading or compiling, simulating, rendering or writing.
LONG_COMMANDS = {
    "run": ["run", "jelly-plane", "--duration", "600", "--out", "out.npz"],
    "render": ["render", "jelly-plane", "--duration", "600", "--width", "64", "--height", "48",
               "--out", "out.mp4"],
    "sweep": ["sweep", "jelly-plane", "--vary", "bodies.0.structural.ks=1000,2000",
              "--duration", "600", "--workers", "1", "--out", "sweep"],
    "export": ["export", "take.npz", "out.usda", "out.mdd", "out.pc2"],
    "stability": ["stability", "jelly-plane", "--integrators", "rk4", "--seconds", "600",
                  "--workers", "1", "--csv", "s.csv", "--png", "s.png"],
    "convergence": ["convergence", "--integrators", "rk4", "--final-time", "60",
                    "--workers", "1", "--png", "c.png"],
    "fit": ["fit", "jelly-plane", "--set", "bodies.0.structural.ks=1500", "--observed", "take.npz", "--fit", "bodies.0.structural.ks",
            "--max-iterations", "1000", "--out", "fit.toml", "--plot", "fit.png"],
    "bench": ["bench", "jelly-plane", "--seconds", "600", "--json"],
    # long on a first install: it compiles, in an empty kernel cache of its own (FRESH_CACHE)
    "warmup": ["warmup"],
}
FRESH_CACHE = {"warmup"}
# The earliest moment (s after starting the process) a signal is sent: at once. springsim's
# handlers are its first act (cli.py); only the interpreter's own start comes before them (about
# 30 ms on an idle machine), where no springsim code has run and no file is open: there SIGTERM
# ends the process by its default action (a shell reports 143 and prints "Terminated") and
# SIGINT meets Python's own handler. Trials that land there are told apart
# (Trial.in_interpreter_start) and counted apart (benchmarks/signals.py).
EARLIEST = 0.0
START_WINDOW = 0.5   # s: a trial counts as landing in the interpreter's start only this early
# The latest moment (s) a signal is sent to each, well before it could end: a signal after a
# command's end, as the interpreter shuts down, finds Python's own handlers back.
LATEST = {"run": 4.0, "render": 4.0, "sweep": 6.0, "export": 3.0, "stability": 4.0,
          "convergence": 4.0, "fit": 4.0, "bench": 4.0, "warmup": 4.0}


@dataclass
class Trial:
    command: str
    signum: int
    delay: float
    returncode: int
    stderr: str
    left: list     # files in the folder afterwards that were not there before

    def in_interpreter_start(self) -> bool:
        """Whether the signal landed before any springsim code ran (EARLIEST): the process ended
        by the signal's default action with nothing said, or (SIGINT) in a KeyboardInterrupt
        traceback of Python's own start-up or runpy, with no springsim frame in it."""
        if self.delay >= START_WINDOW:
            return False
        if self.returncode == -self.signum and not self.stderr.strip():
            return True
        text = self.stderr.strip()
        # "Traceback ...", or "Could not import runpy module" first (python -m's own imports)
        return (self.signum == signal.SIGINT and self.returncode in (1, -signal.SIGINT)
                and text.endswith("KeyboardInterrupt") and "Traceback" in text
                and "/springsim/" not in text)

    def problems(self) -> list:
        expected = 128 + self.signum
        word = "terminated" if self.signum == signal.SIGTERM else "interrupted"
        found = []
        if self.returncode != expected:
            found.append(f"exit {self.returncode}, not {expected}")
        # the one line a first run says before compiling may come first (springsim.warmup)
        lines = [line for line in self.stderr.strip().splitlines()
                 if not line.startswith("springsim: compiling the ")]
        if lines != [word]:
            found.append(f"stderr is not the one line {word!r}: {self.stderr[-600:]!r}")
        half = [name for name in self.left if not whole(name)]
        if half:
            found.append(f"half-written files left: {half}")
        return found


def whole(name: str) -> bool:
    """Whether a file a command left is one it writes whole (its name: no staging file), and
    whole inside: an NPZ opens and reads."""
    base = os.path.basename(name)
    if base.startswith(".") or "tmp" in base or "partial" in base:
        return False
    if name.endswith(".npz"):
        import numpy as np
        try:
            with np.load(name) as arrays:
                for key in arrays.files:
                    arrays[key]
        except Exception:   # noqa: BLE001 - any failure to read means it is not whole
            return False
    return True


def files_in(folder: Path) -> set:
    return {str(path.relative_to(folder)) for path in folder.rglob("*")}


def trial(command: str, signum: int, folder: Path, delay: float, env=None,
          timeout: float = 120) -> Trial:
    """Start ``command`` (a key of LONG_COMMANDS) in ``folder``, send ``signum`` after
    ``delay`` s, and wait for it to end."""
    before = files_in(folder)
    cache = None
    if command in FRESH_CACHE:   # an empty kernel cache, outside the folder, removed after
        cache = tempfile.mkdtemp(prefix="springsim-signal-cache-")
        env = {**(env if env is not None else os.environ), "NUMBA_CACHE_DIR": cache}
    process = subprocess.Popen(
        SPRINGSIM + LONG_COMMANDS[command], cwd=folder, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, text=True, env=env,
        # a shell's background job ignores SIGINT; a user's terminal does not
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(delay)
    process.send_signal(signum)
    try:
        _, err = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        process.kill()
        _, err = process.communicate()
        err += f"\n(still running {timeout} s after the signal)"
    if cache is not None:
        shutil.rmtree(cache, ignore_errors=True)
    left = sorted(folder / name for name in files_in(folder) - before)
    return Trial(command, signum, delay, process.returncode, err, [str(p) for p in left])


def prepare(folder: Path, env=None, seconds: float = 20) -> None:
    """What the commands read: a recording for `export` (``seconds`` of jelly-plane; 20 s:
    1201 frames, some seconds to export)."""
    subprocess.run(SPRINGSIM + ["run", "jelly-plane", "--duration", str(seconds), "--quiet",
                                "--out", "take.npz"], cwd=folder, env=env, check=True)


def random_delays(command: str, count: int, seed, latest: float | None = None) -> list:
    generator = random.Random(seed)
    return [generator.uniform(EARLIEST, latest or LATEST[command]) for _ in range(count)]
