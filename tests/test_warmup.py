"""A compile is said when it happens, wherever it happens (issues: the first run was silent for
100 s; a threaded model for 15 minutes and the viewer's Start for 3.5, under a mark kept per
integrator name).

Oracles: Numba's own compile, on a function Numba has not seen (a fresh function, or new
argument types), is announced once with the notice and a kernel it has already compiled or
cached is not; Numba's cache on disk, read by a fresh process, agrees with ``is_compiled``;
`springsim warmup` makes every variant of an integrator (serial, threaded, the gradient's tape)
compiled, so a threaded step afterwards compiles nothing; the viewer's controls compile a step
on a thread, the window's message saying so, and step once it is done;
scripts/ensure-venv.sh says what each stage does before it starts it (a fake python3 and pip
record when they run), and that it still runs after every quiet SETUP_TICK seconds.
"""
import io
import os
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numba
import pytest

from springsim import compile_notice, warmup
from springsim.cli import main
from springsim.integrators.base import KernelCall

ROOT = Path(__file__).resolve().parent.parent
SMALL = ["--set", "bodies.0.particles_per_edge=3", "--duration", "0.01"]


def fresh_kernel():
    """A function Numba has never compiled: calling it compiles (not cached, so every time)."""
    def add_one(x):
        return x + 1

    return numba.njit(add_one)


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_compile_is_announced_once_and_a_compiled_kernel_not_at_all():
    kernel, log = fresh_kernel(), io.StringIO()
    with compile_notice.announced("the test's kernels", log) as announcer:
        assert kernel(1.0) == 2.0
        assert kernel(2.0) == 3.0       # compiled: no second compile
        fresh_kernel()(1)               # another compile in the block: no second notice
    assert log.getvalue() == compile_notice.NOTICE.format(what="the test's kernels") + "\n"
    assert announcer.compiled
    log = io.StringIO()
    with compile_notice.announced("the test's kernels", log) as announcer:
        kernel(5.0)
    assert log.getvalue() == "" and not announcer.compiled


def test_new_argument_types_are_a_new_compile_and_announced():
    """What compiles is a kernel for types, not a name: the same kernel with an int compiles
    again (as a threaded model's kernel did, under an integrator already marked warm)."""
    kernel, log = fresh_kernel(), io.StringIO()
    kernel(1.0)
    assert warmup.is_compiled(KernelCall(kernel, (1.0,)))
    assert not warmup.is_compiled(KernelCall(kernel, (1,)))
    with compile_notice.announced("the int kernels", log):
        kernel(1)
    assert log.getvalue() == compile_notice.NOTICE.format(what="the int kernels") + "\n"
    assert warmup.is_compiled(KernelCall(kernel, (1,)))


def test_a_terminal_gets_a_ticker_while_compiling_and_a_log_none(monkeypatch):
    monkeypatch.setattr(compile_notice, "SPIN_EVERY", 0.01)
    terminal = Terminal()
    with compile_notice.announced("the test's kernels", terminal) as announcer:
        announcer.depth += 1            # a compile under way, as Numba's event says
        announcer.compile_started()
        time.sleep(0.1)
        announcer.depth -= 1
    shown = terminal.getvalue()
    assert shown.startswith(compile_notice.NOTICE.format(what="the test's kernels") + "\n")
    assert "\r| compiling, 0 s" in shown and shown.endswith("\r")


def test_an_inner_block_names_what_compiles_and_the_outer_says_it_once():
    log = io.StringIO()
    with compile_notice.announced("the kernels `springsim run` needs", log):
        with compile_notice.announced("the rk4 kernels (threaded)"):
            fresh_kernel()(1.0)
        fresh_kernel()(1.0)
    assert log.getvalue() == compile_notice.NOTICE.format(what="the rk4 kernels (threaded)") + "\n"


def test_another_threads_compile_is_not_this_blocks():
    import threading

    log = io.StringIO()
    with compile_notice.announced("the test's kernels", log):
        other = threading.Thread(target=fresh_kernel(), args=(1.0,))
        other.start()
        other.join()
    assert log.getvalue() == ""


def test_is_compiled_reads_numbas_cache_on_disk(tmp_path):
    """A fresh process sees a kernel cached by another as compiled for the types it was called
    with and for no other, without compiling it; a process that compiles it agrees."""
    (tmp_path / "cached_kernel.py").write_text(textwrap.dedent("""\
        from numba import njit

        @njit(cache=True)
        def double(x):
            return 2 * x
        """))
    probe = textwrap.dedent("""\
        import sys
        from cached_kernel import double
        from springsim.integrators.base import KernelCall
        from springsim.warmup import is_compiled
        print(is_compiled(KernelCall(double, (1.0,))), is_compiled(KernelCall(double, (1,))))
        if sys.argv[1:] == ["call"]:
            double(1.0)
        """)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path]),
           "NUMBA_CACHE_DIR": str(tmp_path / "cache")}

    def run(*args):
        done = subprocess.run([sys.executable, "-c", probe, *args], env=env, cwd=tmp_path,
                              capture_output=True, text=True, check=True)
        return done.stdout.split()

    assert run("call") == ["False", "False"]
    assert run() == ["True", "False"]


def test_warmup_lists_every_variant_of_each_method():
    """The threaded kernel and the gradient's are compiled by warmup, not only the serial."""
    from springsim.integrators import rk4
    from springsim.plain import plain_twin

    calls = warmup.variant_calls("rk4")
    kernels = {label.split()[1]: call.kernel for label, call in calls.items()}
    assert kernels == {"serial": rk4.advance, "plain": plain_twin(rk4.advance),
                       "threaded": rk4.parallel_advance, "keeping": rk4.advance_keeping}
    assert {label.split()[1] for label in warmup.variant_calls("implicit_euler")} == {"serial"}


def test_warmup_compiles_each_part_of_the_steps_once_the_costliest_first(monkeypatch):
    """The kernels every serial step calls (Integrator.parts) are compiled before the steps,
    each once however many integrators and scenes call it with the same types (the plain
    model's plain twins, the other's whole kernels), the force evaluation (the longest) first,
    then each scene's recording; the steps follow, one task per integrator with every scene."""
    monkeypatch.setattr(warmup, "is_compiled", lambda call: False)   # as on a clean machine
    plain_scene, whole_scene = scenes = warmup.warmup_scenes()   # a cube, a cloth on balls
    tasks = warmup.part_tasks(["rk4", "midpoint", "implicit_euler"], scenes)
    parts = [(task.scenes[0].name, task.parts[0]) for task in tasks]
    names = ["accelerations", "force_columns", "pairs_now", "collide", "start_step",
             "step_start", "copy_positions"]
    # the cube's plain parts (pairs_now is no kernel to compile there: kept, as force_columns
    # and the copies, which have no twin), implicit_euler's whole ones (it has no plain step),
    # then the cloth's whole force evaluation, which no step of the cube calls
    assert parts[:7] == [(plain_scene.name, name) for name in names]
    assert parts[7:10] == [(plain_scene.name, name) for name in ("pairs_now", "collide",
                                                                 "start_step")]
    assert parts[10:] == [(whole_scene.name, "accelerations")] + [
        (scene.name, warmup.RECORDING) for scene in scenes]
    steps = warmup.step_tasks(["rk4", "implicit_euler"], scenes, None)
    assert [task.integrator for task in steps] == ["implicit_euler", "rk4"]
    assert all(task.scenes == tuple(scenes) and task.variants is None for task in steps)


def test_the_steps_load_the_parts_warmup_compiled_apart():
    """The parts are compiled apart for the types the serial steps call them with: after
    warmup (test.sh's, of every step), each part's cache holds the part's one signature. A
    second one would be a step's own compile of it, the parallel work done twice."""
    from springsim.simulation import Simulation

    simulation = Simulation(warmup.warmup_scenes()[0], integrator="rk4")
    calls = simulation.integrator.parts(simulation.model, simulation.state, simulation.dt)
    for name, call in calls.items():
        cache = call.kernel._cache
        signatures = [key[0] for key in cache._cache_file._load_index()]
        assert signatures == [warmup._types(call)], name


@pytest.mark.slow   # explicit Euler's threaded step: minutes to compile where it is not cached
def test_warmup_compiles_the_threaded_variant_so_a_threaded_step_compiles_nothing(capsys):
    """After `springsim warmup --variants threaded` (test.sh runs it first, for the thread tests:
    then this loads the cache), the threaded variant is compiled, and a threaded step announces
    nothing."""
    from springsim.scenefile import load_scene
    from springsim.simulation import Simulation

    assert main(["warmup", "--integrators", "explicit_euler", "--variants", "threaded"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("springsim warmup: compiling the threaded variant of the kernels "
                             "of 1 integrator once")
    timings = [line.split() for line in out[1:] if not line.startswith("  compiled ")]
    assert [line[0] for line in timings] == ["the", "explicit_euler"]
    assert warmup.is_warm("explicit_euler", ["threaded"])
    simulation = Simulation(load_scene("jelly-plane", ["bodies.0.particles_per_edge=3"]),
                            integrator="explicit_euler")
    call = simulation.integrator.kernel_call(simulation.model, simulation.state,
                                             simulation.dt, 0, threaded=True)
    log = io.StringIO()
    with compile_notice.announced("the threaded kernels", log) as announcer:
        call.kernel(*call.arguments)
    assert not announcer.compiled and log.getvalue() == ""


def test_warmup_refuses_variants_with_a_scene_in_one_line(capsys):
    assert main(["warmup", "--scene", "jelly-plane", "--variants", "threaded"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["springsim warmup: --variants = ['threaded']: goes without --scene (a "
                   "scene's run takes the variant its model needs)"]


def test_warmup_refuses_an_unknown_variant_in_one_line(capsys):
    assert main(["warmup", "--variants", "fast"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["springsim warmup: --variants = 'fast': must be one of serial, plain, "
                   "threaded, keeping"]


def test_a_run_says_it_compiles_before_the_first_step(tmp_path, capsys, monkeypatch):
    """The run's first step, its kernel not compiled for these types, is said before it."""
    from springsim.integrators import base

    kernel_call = base.KernelIntegrator.kernel_call
    seen = []

    def call_compiling(self, model, state, dt, steps, threaded=None):
        call = kernel_call(self, model, state, dt, steps, threaded)
        fresh = fresh_kernel()

        def compiling(*arguments):
            fresh(1.0)   # a compile, as a new variant's first call
            return call.kernel(*arguments)

        seen.append(capsys.readouterr().err)
        return KernelCall(compiling, call.arguments)

    monkeypatch.setattr(base.KernelIntegrator, "kernel_call", call_compiling)
    assert main(["run", "jelly-plane", *SMALL, "--out", str(tmp_path / "a.npz")]) == 0
    err = "".join(seen) + capsys.readouterr().err
    assert compile_notice.NOTICE.format(what="the rk4 kernels") + "\n" in err
    assert err.count("springsim: compiling") == 1


def test_warmup_refuses_an_unknown_integrator_in_one_line(capsys):
    assert main(["warmup", "--integrators", "rk5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("springsim warmup: --integrators = 'rk5': must be one of ")
    assert len(err.splitlines()) == 1


def test_the_viewer_compiles_on_a_thread_and_says_so_in_its_window(monkeypatch, capsys):
    """While the step's kernel compiles, frames take no steps and the window's message is the
    notice with the seconds; then the steps go on and the message is gone."""
    from springsim.bodies.cube import Cube
    from springsim.scene import Scene
    from springsim.viewer import controls as viewer_controls

    kernel = fresh_kernel()
    compiles = []
    real_compile = kernel.compile

    def compile_slowly(types):
        compiles.append(types)
        time.sleep(0.3)
        return real_compile(types)

    monkeypatch.setattr(kernel, "compile", compile_slowly)
    monkeypatch.setattr(viewer_controls, "step_call", lambda sim: KernelCall(kernel, (1.0,)))
    scene = Scene(name="small", bodies=[Cube(particles_per_edge=3)], terrains=[], dt=1e-3)
    controls = viewer_controls.Controls(scene)
    controls.compile_in_background = True   # as the window sets it
    stepped = []
    controls.sim.step = stepped.append   # the steps themselves are not what is tested here
    controls.start()
    controls.advance_frame(now=0.0)
    assert stepped == []
    assert controls.compiling is not None
    deadline = time.monotonic() + 30
    while controls.compiling is not None and controls.compiling.thread.is_alive():
        assert time.monotonic() < deadline
        time.sleep(0.02)
    notice = compile_notice.NOTICE.format(what=compile_notice.kernels_of(controls.sim))
    assert controls.message.startswith(notice + ": ") and controls.message.endswith(" s")
    assert notice + "\n" in capsys.readouterr().err
    controls.advance_frame(now=0.1)
    assert stepped == [controls.steps_per_frame]
    assert controls.message == "" and len(compiles) == 1


def test_ensure_venv_says_what_each_stage_does_before_it_starts(tmp_path):
    """Every command the setup runs (the fake python3, pip, springsim write a line to the same
    log as they start) comes after a line saying what it is for."""
    fake = tmp_path / "bin"
    fake.mkdir()
    log = tmp_path / "log"
    recorder = textwrap.dedent(f"""\
        #!/bin/sh
        echo "RAN $(basename "$0") $*" >> {log}
        """)
    python = recorder + textwrap.dedent("""\
        if [ "$1 $2" = "-m venv" ]; then
          mkdir -p "$3/bin"
          for tool in pip springsim pytest; do
            cp "$0" "$3/bin/$tool"
          done
        fi
        """)
    # the install says nothing for 2.5 s (as pip installing numba and scipy for a minute)
    python += 'case "$*" in *" -e "*) sleep 2.5;; esac\n'
    (fake / "python3").write_text(python)
    (fake / "python3").chmod(stat.S_IRWXU)
    repo = tmp_path / "clone"
    repo.mkdir()
    (repo / "pyproject.toml").write_text("")
    script = (ROOT / "scripts" / "ensure-venv.sh").read_text()
    subprocess.run(["bash", "-c", f"source /dev/stdin 2>>{log}"], input=script, text=True,
                   cwd=repo, check=True, env={**os.environ, "PATH": f"{fake}:{os.environ['PATH']}",
                                              "SETUP_TICK": "1"})
    lines = log.read_text().splitlines()
    # no quiet stretch longer than SETUP_TICK: the silent install is said to go on each second
    install = next(i for i, line in enumerate(lines) if line.startswith("RAN pip install")
                   and " -e " in line)
    assert lines[install + 1:install + 3] == ["setup: ... still installing, 1 s",
                                              "setup: ... still installing, 2 s"], lines
    lines = [line for line in lines if not line.startswith("setup: ... still ")]
    assert [line.split()[1] for line in lines if line.startswith("RAN")] == [
        "python3", "pip", "pip", "springsim", "pip"]
    for index, line in enumerate(lines):
        if line.startswith("RAN"):
            assert lines[index - 1].startswith("setup: "), lines
    assert "RAN springsim warmup --scene jelly-plane" in lines


def test_ctrl_c_during_a_parallel_warmup_ends_every_worker_in_one_line(tmp_path):
    """Ctrl-C, which a terminal sends to every process of the command, stops a warmup that
    compiles on worker processes at once: one line, exit 130, no traceback, no worker left
    compiling (they ignore it; the main process ends them)."""
    import signal

    environment = {**os.environ, "XDG_CACHE_HOME": str(tmp_path)}   # an empty cache
    process = subprocess.Popen([sys.executable, "-m", "springsim", "warmup", "--scene",
                                "jelly-plane", "--jobs", "2"], env=environment, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               start_new_session=True)
    for line in process.stdout:   # the workers have begun: one of them has ended a part
        if line.startswith("  compiled "):
            break
    os.killpg(process.pid, signal.SIGINT)
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130 and err.strip().splitlines()[-1] == "interrupted", err
    assert "Traceback" not in err
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            os.killpg(process.pid, 0)   # anyone of the command's group still there?
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        raise AssertionError("a worker outlived the warmup")
