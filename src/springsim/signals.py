"""Ctrl-C (SIGINT) and SIGTERM, acted on between compiled calls, never inside one.

A Python signal handler runs at the next bytecode the main thread executes. While a Numba
kernel runs that is usually the first bytecode after it returns, but a kernel that boxes its
result (a tuple of arrays, a named tuple) or raises calls back into Python (Numba's
unpickling), and a handler that raises there leaves an exception set under native code that
ignores it: the process ends in ``SystemError: CPUDispatcher(...) returned a result with an
exception set``, or a segmentation fault. So while ``deferred()`` is held (around each
``Simulation.step``, whose state must change as a whole anyway) the handler only records the
signal, and the block raises it as it ends. Everywhere else the handler raises at once, so a
command waiting on workers, a file or ffmpeg stops as before. Compiling a kernel is Python
called by Numba's dispatcher, which passes an exception on, so Ctrl-C during the first
compile (minutes) stops it at once, inside ``deferred()`` too.

SIGINT raises ``KeyboardInterrupt`` and SIGTERM raises ``Terminated`` (a KeyboardInterrupt), so
that every half-written file is removed on the way out (safe_files.py) and the command line
prints one line and exits with 128 + the signal's number.

The command line takes the signals over as the first thing it does, so this module imports
nothing that takes time (contextlib, threading and signal's enums bring enum, functools and
collections, 10 to 40 ms on a busy machine): it calls ``_signal``, the C module under
``signal``, the blocks are plain classes, and threading is imported where it is used, by then
long loaded.
"""
import _signal as signal   # signal.py's functions without its enums (the module doc)
import os
import sys

SIGINT, SIGTERM = signal.SIGINT, signal.SIGTERM
SIGNALS = (SIGINT, SIGTERM)
RESEND_AFTER = 0.02   # s: a signal that landed in a Numba call-back outside deferred() is sent again


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every half-written file is removed on the way out."""


_depth = 0          # how many deferred() blocks the main thread is in
_pending = None     # the signal received inside them, acted on as the outermost one ends


def exception_for(signum: int) -> KeyboardInterrupt:
    return Terminated() if signum == signal.SIGTERM else KeyboardInterrupt()


def on_signal(signum, frame):
    """The handler: raise, unless the main thread is inside a compiled call (module doc)."""
    global _pending
    safe = _safe_to_raise(frame)
    if safe:
        raise _acted_on(signum)
    if safe is False:
        # called back from C code: try again when it has returned. Inside deferred() too: a
        # compile calls back from LLVM (llvmlite.binding) too, and only a signal sent again
        # finds it back in Numba's own code, where it stops the compile at once; recorded
        # only, it waited for the minutes the compile takes.
        import threading   # loaded already: code called back from C is NumPy's or Numba's

        threading.Timer(RESEND_AFTER, _send_again, (signum, _generation)).start()
        if _depth == 0:   # a block begun before the resend comes takes it over (deferred)
            global _unanswered
            _unanswered = signum
    if _depth > 0:
        _pending = _pending or signum
    elif safe is None:
        raise _acted_on(signum)


_generation = 0   # counts signals acted on and blocks begun: a resend from before is stale
_unanswered = None   # a signal received outside a block, waiting for its resend


def _acted_on(signum: int) -> KeyboardInterrupt:
    global _generation, _unanswered
    _generation += 1
    _unanswered = None
    return exception_for(signum)


def _send_again(signum: int, generation: int) -> None:
    """Send the signal again, unless it has been acted on, a new block has begun since, or
    on_signal no longer handles it (the default action would end the process)."""
    if generation == _generation and signal.getsignal(signum) is on_signal:
        os.kill(os.getpid(), signum)


def _frames(frame):
    while frame is not None:
        yield frame
        frame = frame.f_back


def _module(frame) -> str:
    return frame.f_globals.get("__name__", "") or ""


def _run_from_c(frame) -> bool:
    """A string an extension runs with PyRun_String, under other Python code (``python -c``'s
    own program is a "<string>" module too, but the outermost frame; its functions are not
    modules)."""
    code = frame.f_code
    return (code.co_filename == "<string>" and code.co_name == "<module>"
            and frame.f_back is not None)


def _ignores_exceptions(frame) -> bool:
    """A weakref callback or finalizer, or ``__del__``: Python prints "Exception ignored" and
    goes on, so the signal would be lost (the import lock's weakref callback, for one)."""
    code = frame.f_code
    return (code.co_name == "__del__" or _module(frame) == "weakref"
            or (code.co_name == "cb" and "importlib._bootstrap" in code.co_filename))


def _imported_from_c(frame) -> bool:
    """Python that an extension module's initialisation runs (an import it makes, as NumPy's
    imports datetime): importlib calls the extension's C code through
    ``_call_with_frames_removed``, so a Python frame right under that which is neither a
    module's own code (``exec``) nor importlib's ``_gcd_import`` was entered from C. An
    exception raised there comes out as the extension's ImportError ("PyCapsule_Import could
    not import module "datetime"", with NumPy's page of advice)."""
    back = frame.f_back
    return (back is not None and back.f_code.co_name == "_call_with_frames_removed"
            and "importlib._bootstrap" in back.f_code.co_filename
            and frame.f_code.co_name not in ("<module>", "_gcd_import"))


def _safe_to_raise(frame) -> bool | None:
    """False where the innermost code that matters was called back from code that drops an
    exception: a finalizer, Numba's unpickling for a compiled kernel, LLVM's callbacks through
    llvmlite.binding (raising there hung the compile; llvmlite.ir is plain Python under Numba's
    compile), a string run with PyRun_String by an extension
    (NumPy's lazy imports under Numba: CPython then kills itself with SIGINT at exit), or an
    import made by an extension's initialisation. True where it is Numba's dispatcher compiling
    a kernel, which passes an exception on to its caller. None elsewhere: plain Python."""
    for each in _frames(frame):
        module = _module(each)
        if (module == "numba.core.serialize" or module.startswith("llvmlite.binding")
                or _run_from_c(each) or _ignores_exceptions(each) or _imported_from_c(each)):
            return False
        if each.f_code.co_name == "_compile_for_args" and module.startswith("numba"):
            return True
    return None


def _in_main_thread() -> bool:
    """Whether this is the main thread, without importing threading where it is not loaded
    yet (then no other thread has been started from Python)."""
    threading = sys.modules.get("threading")
    return threading is None or threading.current_thread() is threading.main_thread()


class handled:
    """While the block runs (a command), SIGINT and SIGTERM go to ``on_signal`` (in the main
    thread only: elsewhere Python cannot install handlers, and the caller keeps its own)."""

    def __enter__(self):
        self.previous = {}
        if _in_main_thread():
            for signum in SIGNALS:
                try:
                    self.previous[signum] = signal.signal(signum, on_signal)
                except ValueError:   # a thread Python did not start (threading not loaded)
                    break
        return self

    def __exit__(self, *raised):
        for signum, handler in self.previous.items():
            signal.signal(signum, handler)
        return False


def take_over_unanswered() -> None:
    """A signal that landed outside a block where raising was not safe waits for its resend; a
    block begun before the resend comes makes it stale, so the block takes the signal as its own
    (a SIGTERM that landed in an extension's import was lost so, and the command ran on)."""
    global _pending, _unanswered
    if _unanswered is not None:
        _pending = _pending or _unanswered
        _unanswered = None


class deferred:
    """A block of compiled calls: a signal received in it is raised as it ends (module doc).

    Outside ``handled()`` (springsim used from Python), Python's own Ctrl-C handler is swapped
    for ``on_signal`` for the block, so Ctrl-C in a session stops a long ``advance`` cleanly too.
    """

    def __enter__(self):
        global _depth, _generation
        self.main = _in_main_thread()
        if self.main:
            if _depth == 0:
                _generation += 1   # a new block: resends from before it are stale, and the
                take_over_unanswered()   # block acts on their signal as it ends
            self.swapped = (_depth == 0
                            and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
            if self.swapped:
                signal.signal(signal.SIGINT, on_signal)
            _depth += 1
        return self

    def __exit__(self, *raised):
        global _depth, _pending
        if self.main:
            _depth -= 1
            if self.swapped:
                signal.signal(signal.SIGINT, signal.default_int_handler)
            if _depth == 0 and _pending is not None:
                signum, _pending = _pending, None
                raise _acted_on(signum)
        return False
