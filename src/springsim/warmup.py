"""The kernels' first compile: said before it happens, and done ahead of time by `springsim warmup`.

Numba compiles an integrator's kernels at their first call (about two minutes for the first
integrator on a laptop, less for each next one, which shares the force and contact kernels) and
caches them on disk (``springsim._jit``); later runs load them in a second or two. A first run
that says nothing for two minutes looks hung, so the first step of each integrator is announced
on stderr while no mark says its kernels are in this cache, with a spinner where stderr is a
terminal. The mark (an empty file ``warm-<integrator>`` in the cache folder) is written after
that step, so a compile stopped by Ctrl-C is announced again next time.
"""
import contextlib
import itertools
import os
import sys
import threading
import time
from pathlib import Path

NOTICE = ("springsim: compiling the {integrator} kernels once (minutes: about 5 on two "
          "cores; later runs start in seconds)")
SPIN_EVERY = 0.1   # s between spinner frames
SPINNER = "|/-\\"


def cache_folder() -> Path:
    import numba

    from . import _jit  # noqa: F401 - sets Numba's cache folder (versioned by the kernel sources)

    return Path(os.environ.get("NUMBA_CACHE_DIR") or numba.config.CACHE_DIR)


def mark(integrator: str) -> Path:
    return cache_folder() / f"warm-{integrator}"


def is_warm(integrator: str) -> bool:
    return mark(integrator).exists()


@contextlib.contextmanager
def announced(integrator: str, stream=None, say: bool = True):
    """Around a simulation's first step: say that the kernels compile when no mark says they
    are cached (and spin while they do, where ``stream`` is a terminal); mark them after."""
    stream = stream or sys.stderr
    if is_warm(integrator):
        yield
        return
    if say:
        print(NOTICE.format(integrator=integrator), file=stream, flush=True)
    stop = threading.Event()
    spinner = None
    if say and _is_terminal(stream):
        spinner = threading.Thread(target=_spin, args=(stream, stop), daemon=True)
        spinner.start()
    try:
        yield
    finally:
        stop.set()
        if spinner is not None:
            spinner.join()
    with contextlib.suppress(OSError):   # an unwritable cache: announced again next time
        mark(integrator).touch()


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def _spin(stream, stop: threading.Event) -> None:
    started = time.monotonic()
    for frame in itertools.cycle(SPINNER):
        if stop.wait(SPIN_EVERY):
            break
        stream.write(f"\r{frame} compiling, {time.monotonic() - started:.0f} s ")
        stream.flush()
    stream.write("\r" + " " * 24 + "\r")
    stream.flush()
