"""A compile said when it happens: the notice and ticker of every kernel that compiles.

Numba compiles a kernel at its first call with argument types it has not seen (minutes for an
integrator's step on two cores) and caches it on disk (``springsim._jit``); later runs load it
in a second or two. A compile that says nothing for minutes looks hung, so ``announced``
listens to Numba's own compile events, which Numba sends only when a kernel is not in its cache
(not when it loads one): at the first compile in its block, whatever kernel it is, it prints
NOTICE on stderr, and while kernels compile a terminal gets a ticker (a spinner and the
seconds). The command line wraps every command in it (``cli.main``), a Simulation its first
compiled call of each kind, and the viewer compiles a simulation's step on a thread and says so
in its window (viewer/controls.py). What compiles ahead of time is warmup.py's.
"""
import contextlib
import itertools
import sys
import threading
import time

from numba.core import event

NOTICE = ("springsim: compiling {what} once (minutes on two cores; cached after, so later "
          "runs start in seconds)")
SPIN_EVERY = 0.1   # s between spinner frames
SPINNER = "|/-\\"
COMPILE_EVENT = "numba:compile"   # sent by Numba around a compile it could not load


def kernels_of(simulation) -> str:
    """What a simulation's step compiles, for NOTICE: "the rk4 kernels (threaded)"."""
    from .spring_runs import partition_count

    threaded = (getattr(simulation.integrator, "parallel_kernel", None) is not None
                and partition_count(simulation.model.particle_count,
                                    simulation.model.arrays.spring_partition) > 1)
    return f"the {simulation.integrator.name} kernels" + (" (threaded)" if threaded else "")


class Announcer:
    """What ``announced`` says, and where: NOTICE once on ``stream``, then a ticker while
    kernels compile where ``stream`` is a terminal; ``on_compile(seconds)``, when given, hears
    of each compile as it starts and then every SPIN_EVERY while compiles go on (the viewer
    shows it in its window)."""

    def __init__(self, what: str, stream=None, say: bool = True, on_compile=None):
        self.what, self.stream, self.say = what, stream or sys.stderr, say
        self.on_compile = on_compile
        self.compiled = False       # whether anything compiled in the block
        self.started = None         # time.monotonic() at the first compile
        self.depth = 0              # compiles under way (a kernel compiles those it calls)
        self._stop = threading.Event()
        self._ticker = None

    def compile_started(self) -> None:
        if not self.compiled:
            self.compiled, self.started = True, time.monotonic()
            if self.say:
                print(NOTICE.format(what=self.what), file=self.stream, flush=True)
            if self.on_compile is not None or (self.say and _is_terminal(self.stream)):
                self._ticker = threading.Thread(target=self._tick, daemon=True)
                self._ticker.start()
        if self.on_compile is not None:
            self.on_compile(self.seconds())

    def seconds(self) -> float:
        return time.monotonic() - self.started if self.started is not None else 0.0

    def close(self) -> None:
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()

    def _tick(self) -> None:
        spinning = self.say and _is_terminal(self.stream)
        shown = False
        for frame in itertools.cycle(SPINNER):
            if self._stop.wait(SPIN_EVERY):
                break
            if self.depth > 0:
                if self.on_compile is not None:
                    self.on_compile(self.seconds())
                if spinning:
                    self.stream.write(f"\r{frame} compiling, {self.seconds():.0f} s ")
                    self.stream.flush()
                    shown = True
            elif shown:   # between compiles (the run's own steps): no spinner over its output
                _erase(self.stream)
                shown = False
        if shown:
            _erase(self.stream)


def _erase(stream) -> None:
    stream.write("\r" + " " * 24 + "\r")
    stream.flush()


_watching = threading.local()   # the Announcer of this thread's outermost ``announced`` block


@contextlib.contextmanager
def announced(what: str, stream=None, say: bool = True, on_compile=None):
    """Say NOTICE (naming ``what``: "the rk4 kernels") at the first kernel that compiles in the
    block, in this thread, and tick while kernels compile (Announcer). Inside another block of
    this thread, the outer one says it, naming this block's ``what`` (and says nothing where
    this block's ``say`` is false)."""
    outer = getattr(_watching, "announcer", None)
    if outer is not None:
        kept = outer.what, outer.say
        outer.what, outer.say = what, outer.say and say
        try:
            yield outer
        finally:
            outer.what, outer.say = kept
        return
    announcer = Announcer(what, stream, say, on_compile)
    listener = _Listener(announcer, threading.get_ident())
    _watching.announcer = announcer
    event.register(COMPILE_EVENT, listener)
    try:
        yield announcer
    finally:
        event.unregister(COMPILE_EVENT, listener)
        _watching.announcer = None
        announcer.close()


class _Listener(event.Listener):
    """Numba's compile events of one thread, passed on to an Announcer."""

    def __init__(self, announcer: Announcer, thread: int):
        self.announcer, self.thread = announcer, thread

    def on_start(self, event) -> None:
        if threading.get_ident() == self.thread:
            self.announcer.depth += 1
            self.announcer.compile_started()

    def on_end(self, event) -> None:
        if threading.get_ident() == self.thread:
            self.announcer.depth -= 1


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
