"""The issue's bar for Ctrl-C and SIGTERM: 50 SIGINT and 50 SIGTERM sent at random moments to
`springsim run`, and 10 of each to every other long command (render, sweep, export, stability,
convergence, fit, bench, and warmup in an empty kernel cache); every one must end with the one
line "interrupted" or "terminated", exit 130 or 143, no traceback and no half-written file
(tests/signal_trials.py says what is checked). The moments are drawn from the process's start (0 s) to a few seconds into the command.

    .venv/bin/python benchmarks/signals.py [--run 50] [--others 10] [--seed 1] [--commands ...]

Prints a line per command and signal (trials; how many ended in the one line; how many landed in
the interpreter's own start, before springsim's first line ran, and how; how many failed), each
failure, and the totals; exits 1 if any trial failed. It takes about half an hour (a trial is a
few seconds); tests/test_signals.py runs a few trials of each command.
"""
import argparse
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import signal_trials


def warm(folder: Path) -> None:
    """Compile what the commands use before timing anything (a first compile takes minutes,
    and each trial would land in it): `run` (prepare) and `fit`'s gradient kernels."""
    signal_trials.prepare(folder)
    subprocess.run(signal_trials.SPRINGSIM + [
        "run", "jelly-plane", "--duration", "0.05", "--quiet", "--out", "short.npz"],
        cwd=folder, check=True)
    subprocess.run(signal_trials.SPRINGSIM + [
        "fit", "jelly-plane", "--set", "bodies.0.structural.ks=1500", "--observed", "short.npz",
        "--fit", "bodies.0.structural.ks", "--max-iterations", "1", "--out", "warm.toml"],
        cwd=folder, check=True, stdout=subprocess.DEVNULL)
    for name in ("short.npz", "warm.toml"):
        (folder / name).unlink()


def clear(result) -> None:
    """Each trial starts from the same folder: remove what the last one left (whole files)."""
    for left in result.left:
        path = Path(left)
        if path.is_file():
            path.unlink()
    for left in sorted(result.left, reverse=True):
        if Path(left).is_dir():
            Path(left).rmdir()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=int, default=50, help="trials of each signal on run")
    parser.add_argument("--others", type=int, default=10,
                        help="trials of each signal on every other command")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--commands", nargs="+", choices=list(signal_trials.LONG_COMMANDS),
                        default=list(signal_trials.LONG_COMMANDS))
    args = parser.parse_args()
    began = time.time()
    totals = {"trials": 0, "one line": 0, "interpreter start": 0, "failed": 0}
    start_delays = []
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        warm(folder)
        print(f"{'command':<12} {'signal':<8} {'trials':>6} {'one line':>9} "
              f"{'in start':>9} {'failed':>7}", flush=True)
        for command in args.commands:
            for signum in (signal.SIGINT, signal.SIGTERM):
                count = args.run if command == "run" else args.others
                ok, start, bad = 0, [], []
                for delay in signal_trials.random_delays(command, count, args.seed + signum):
                    result = signal_trials.trial(command, signum, folder, delay)
                    if not result.problems():
                        ok += 1
                    elif result.in_interpreter_start():
                        start.append(result)
                    else:
                        bad.append(result)
                    clear(result)
                print(f"{command:<12} {signal.Signals(signum).name:<8} {count:>6} {ok:>9} "
                      f"{len(start):>9} {len(bad):>7}", flush=True)
                for result in start:
                    start_delays.append(result.delay)
                    print(f"    in the interpreter's start at {result.delay:.3f} s: exit "
                          f"{result.returncode}, {len(result.stderr.splitlines())} lines",
                          flush=True)
                for result in bad:
                    print(f"    FAILED at {result.delay:.3f} s: {'; '.join(result.problems())}",
                          flush=True)
                totals["trials"] += count
                totals["one line"] += ok
                totals["interpreter start"] += len(start)
                totals["failed"] += len(bad)
    print("total: " + ", ".join(f"{value} {key}" for key, value in totals.items())
          + (f"; the latest moment that landed in the interpreter's start: "
             f"{max(start_delays):.3f} s" if start_delays else "")
          + f"; {(time.time() - began) / 60:.0f} minutes", flush=True)
    return 1 if totals["failed"] else 0


if __name__ == "__main__":
    sys.exit(main())
