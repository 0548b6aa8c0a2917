"""Ctrl-C and SIGTERM: acted on between compiled calls, never inside one (springsim/signals.py).

Oracles: a signal received inside ``deferred()`` is raised as the block ends and not before (a
step's state is whole: time, step count and positions agree); outside it, at once; in Numba's
compiler at once, in a Numba call-back never. Then every long command, started for real and sent
SIGINT or SIGTERM at a random moment, ends with the one line "interrupted" or "terminated",
exit 130 or 143, no traceback and no half-written file (tests/signal_trials.py;
benchmarks/signals.py runs the issue's full count). Before signals.py, a Ctrl-C landing in a
kernel's call-back ended `springsim run` in a SystemError traceback or a segmentation fault.
"""
import os
import signal
import sys

import pytest

import springsim
from springsim import signals

sys.path.insert(0, os.path.dirname(__file__))
import signal_trials


def send_to_self(signum):
    os.kill(os.getpid(), signum)


@pytest.mark.parametrize("signum, raised", [(signal.SIGINT, KeyboardInterrupt),
                                            (signal.SIGTERM, signals.Terminated)])
def test_a_signal_inside_deferred_waits_for_the_block_to_end(signum, raised):
    reached = []
    with signals.handled(), pytest.raises(raised), signals.deferred():
        send_to_self(signum)
        for _ in range(1000):   # bytecodes run here: a raising handler would stop them
            pass
        reached.append("end of block")
    assert reached == ["end of block"]


OUTSIDE_DEFERRED = """
import os, signal
from springsim import signals
reached = []
try:
    with signals.handled():
        os.kill(os.getpid(), signal.SIGTERM)
        for _ in range(1000):
            pass
        reached.append("after")
except signals.Terminated:
    print("raised", reached)
"""


def test_a_signal_outside_deferred_is_raised_at_once():
    """In a process of its own: a pytest-xdist worker runs the tests under code execnet runs
    from a string, which on_signal takes for an extension's PyRun_String (not safe to raise)."""
    import subprocess

    done = subprocess.run([sys.executable, "-c", OUTSIDE_DEFERRED], capture_output=True,
                          text=True, timeout=60)
    assert done.stdout.strip() == "raised []", done.stderr


def frame_in(module: str, function: str, action):
    """Run ``action(frame)`` in a function ``function`` of a module named ``module``, as the
    handler would find it called from there."""
    namespace = {"__name__": module, "action": action, "sys": sys}
    source = f"def {function}():\n    return action(sys._getframe())"
    exec(compile(source, f"<{module}>", "exec"), namespace)
    return namespace[function]()


def test_numba_compiling_raises_at_once_and_a_numba_call_back_waits():
    reached = []
    with pytest.raises(signals.Terminated), signals.deferred():
        with pytest.raises(KeyboardInterrupt):   # the dispatcher passes it on to its caller
            frame_in("numba.core.dispatcher", "_compile_for_args",
                     lambda frame: signals.on_signal(signal.SIGINT, frame))
        # called back from compiled code: recorded, raised when the block ends
        frame_in("numba.core.serialize", "_numba_unpickle",
                 lambda frame: signals.on_signal(signal.SIGTERM, frame))
        reached.append("end of block")
    assert reached == ["end of block"]


def test_code_run_from_c_never_gets_the_interrupt():
    """LLVM's callbacks (llvmlite), strings an extension runs (PyRun_String) and finalizers
    drop or mishandle an exception: inside a compile too, the signal waits."""
    reached = []
    with pytest.raises(KeyboardInterrupt), signals.deferred():
        frame_in("numba.core.dispatcher", "_compile_for_args", lambda frame: frame_in(
            "llvmlite.binding.executionengine", "_raw_object_cache_notify",
            lambda inner: signals.on_signal(signal.SIGINT, inner)))
        exec("import sys\nsignals.on_signal(signal.SIGINT, sys._getframe())",
             {"signals": signals, "signal": signal})
        frame_in("weakref", "__call__", lambda frame: signals.on_signal(signal.SIGINT, frame))
        reached.append("end of block")
    assert reached == ["end of block"]


def test_ctrl_c_during_a_step_from_python_leaves_the_state_whole(monkeypatch):
    """springsim used from Python, with Python's own Ctrl-C handler: the step finishes and its
    state is consistent, then KeyboardInterrupt."""
    sim = springsim.Simulation(springsim.load_scene(
        "jelly-plane", ["bodies.0.particles_per_edge=3"]), dt=0.001)
    sim.step(1)
    advance = sim.integrator.advance

    def advance_with_ctrl_c(*args):
        send_to_self(signal.SIGINT)   # as if pressed while the kernel runs
        return advance(*args)

    monkeypatch.setattr(sim.integrator, "advance", advance_with_ctrl_c)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    with pytest.raises(KeyboardInterrupt):
        sim.step(5)
    assert (sim.steps_taken, sim.time) == (6, 6 * 0.001)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("signals")
    signal_trials.prepare(folder, seconds=4)
    return folder


# A few trials a command, each signal, kept affordable; benchmarks/signals.py runs 50 + 50 on
# `run` and 10 + 10 on every other command.
TRIALS = [(command, signum, delay)
          for command in signal_trials.LONG_COMMANDS
          for signum in (signal.SIGINT, signal.SIGTERM)
          for delay in signal_trials.random_delays(
              command, 2 if command == "run" else 1, seed=f"{command}-{signum}",
              latest=1.0 if command == "export" else None)]   # a 4 s take exports in 1.5 s or more


@pytest.mark.parametrize("command, signum, delay", TRIALS,
                         ids=[f"{c}-{signal.Signals(s).name}-{d:.2f}s" for c, s, d in TRIALS])
def test_a_signal_at_a_random_moment_ends_a_command_in_one_line(folder, command, signum, delay):
    result = signal_trials.trial(command, signum, folder, delay)
    # before springsim's first line (the interpreter's own start) only the signal's default can
    # act; in_interpreter_start says it is that and nothing else (no springsim frame, no file)
    assert result.problems() == [] or (result.in_interpreter_start() and result.left == [])


def test_every_long_command_is_tried():
    from springsim.cli import command_modules

    commands = {module.NAME for module in command_modules()}
    # the others print and end, or open a window or a server and wait on the user
    short = {"scenes", "docs", "play", "view", "blender-addon"}
    assert set(signal_trials.LONG_COMMANDS) == commands - short


def test_springsim_takes_the_signals_before_anything_slow_loads():
    """The window before the handlers are in place is the interpreter's own start: importing
    the command line loads springsim's package, cli and signals and nothing else (before, it
    loaded argparse, typing, importlib.metadata and signal's enums: 60 ms, 0.4 s on a busy
    machine, where a signal ended in a traceback)."""
    import subprocess

    code = ("import sys; before = set(sys.modules); import springsim.cli; "
            "print(sorted(set(sys.modules) - before))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.strip() == "['springsim', 'springsim.cli', 'springsim.signals']"
