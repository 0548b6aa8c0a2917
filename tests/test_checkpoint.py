"""The state is the whole state: a copied, saved or checkpointed run continues bit for bit.

Oracles: a run continued from a copy of its state, from a state file, or from a checkpoint of an
interrupted `springsim run` (interrupted in process, or killed with SIGKILL) ends with exactly the
arrays of the run that never stopped; the caller's scene is never changed; wrong or foreign files
are refused with one line naming the argument.
"""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import springsim
from springsim import checkpoint
from springsim.cli import main
from springsim.errors import SceneError
from springsim.collision.pair_lists import POINTS, PairList
from springsim.state import ContactMemory

# The jelly cube thrown sideways onto the plane: it lands, bounces and slides against friction.
SIDEWAYS = ["bodies.0.velocity=[3.0, 0.0, 0.0]", "bodies.0.particles_per_edge=5",
            "bodies.0.position.1=1.5"]
SIDEWAYS_SET = [arg for item in SIDEWAYS for arg in ("--set", item)]
# wall-clock timings: the only arrays two runs of the same scene may differ in
TIMINGS = {"step_seconds", "wall_seconds"}


def sideways_simulation(integrator, dt):
    return springsim.Simulation(springsim.load_scene("jelly-plane", SIDEWAYS),
                                integrator=integrator, dt=dt)


def assert_same_state(a, b):
    assert a.time == b.time and a.steps == b.steps
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.velocities, b.velocities)
    for name, x, y in zip(ContactMemory._fields, a.contacts, b.contacts):
        assert np.array_equal(x, y), name
    assert_same_pairs(a, b)


def assert_same_pairs(a, b):
    for name, x, y in zip(PairList._fields, a.pairs, b.pairs):
        assert np.array_equal(x, y, equal_nan=name == "found_at"), name
    assert (a.solve_pairs is None) == (b.solve_pairs is None)
    if a.solve_pairs is not None:
        for x, y in zip((*a.solve_pairs.pairs, a.solve_pairs.found_at, a.solve_pairs.reach),
                        (*b.solve_pairs.pairs, b.solve_pairs.found_at, b.solve_pairs.reach)):
            assert np.array_equal(x, y)


@pytest.mark.parametrize("integrator, dt", [("implicit_euler", 0.01), ("rk4", 0.001)])
def test_a_run_continued_from_a_copy_or_a_file_of_its_state_is_bit_identical(tmp_path,
                                                                             integrator, dt):
    first = sideways_simulation(integrator, dt)
    first.advance(1.0)    # landed (at 0.45 s), sliding on the plane
    if integrator == "implicit_euler":
        assert np.count_nonzero(first.state.contacts.kind) > 0   # contact memory in use
        assert np.any(first.state.contacts.friction_damping > 0)
    copied = sideways_simulation(integrator, dt)
    copied.state = first.state.copy()
    first.save_state(tmp_path / "state.npz")
    loaded = sideways_simulation(integrator, dt)
    loaded.load_state(tmp_path / "state.npz")
    for simulation in (first, copied, loaded):
        simulation.advance(0.3)
    assert_same_state(copied.state, first.state)
    assert_same_state(loaded.state, first.state)
    assert loaded.steps_taken == first.steps_taken == round(1.3 / dt)


def test_the_pair_lists_travel_with_the_state_and_a_resumed_run_keeps_them(tmp_path):
    """Two cubes piled on a folded cloth under backward Euler: the state carries the post-step
    pass's surface pair list and the solve's, so a copy and a saved state hold the same lists
    (their own arrays, not the run's), and the run continued from either steps on bit for bit,
    keeping (not searching again) the lists it was given."""
    def pile():
        return springsim.Simulation(springsim.load_scene("jelly-stack"),
                                    integrator="implicit_euler", dt=1 / 60)
    first = pile()
    first.advance(1.2)   # the cubes have landed on each other: pairs in reach
    assert len(first.state.pairs.points) > 0 and first.state.solve_pairs is not None
    assert len(first.state.solve_pairs.pairs[POINTS]) > 0
    copied = first.state.copy()
    assert copied.pairs.points is not first.state.pairs.points
    assert copied.solve_pairs.found_at is not first.state.solve_pairs.found_at
    assert_same_pairs(copied, first.state)
    first.save_state(tmp_path / "state.npz")
    loaded = pile()
    loaded.load_state(tmp_path / "state.npz")
    assert_same_pairs(loaded.state, first.state)
    resumed = pile()
    resumed.state = copied
    for simulation in (first, loaded, resumed):
        simulation.step(1)
    assert_same_state(loaded.state, first.state)
    assert_same_state(resumed.state, first.state)


def test_state_files_refuse_a_wrong_model_or_a_foreign_file(tmp_path):
    simulation = sideways_simulation("rk4", 1e-3)
    simulation.save_state(tmp_path / "state.npz")
    other = springsim.Simulation(springsim.load_scene("jelly-plane"))
    with pytest.raises(SceneError, match="holds a state of 125 particles; this model has 1000"):
        other.load_state(tmp_path / "state.npz")
    (tmp_path / "text.npz").write_text("not numbers\n")
    np.savez(tmp_path / "recording.npz", positions=np.zeros((2, 125, 3)))
    np.savez(tmp_path / "newer.npz", format="springsim-state", version=99)
    cases = {"missing.npz": "no such file", "text.npz": "not an NPZ file",
             "recording.npz": "has no springsim format name",
             "newer.npz": "format version 99"}
    for name, problem in cases.items():
        with pytest.raises(SceneError, match=problem) as caught:
            simulation.load_state(tmp_path / name)
        assert caught.value.key == "path" and "\n" not in str(caught.value)
    assert simulation.steps_taken == 0   # nothing was half-loaded


def test_save_state_is_whole_or_not_at_all(tmp_path, monkeypatch):
    simulation = sideways_simulation("rk4", 1e-3)
    simulation.save_state(tmp_path / "state.npz")
    before = (tmp_path / "state.npz").read_bytes()

    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")
    monkeypatch.setattr(np, "savez", fail)
    simulation.step(3)
    with pytest.raises(OSError):
        simulation.save_state(tmp_path / "state.npz")
    assert (tmp_path / "state.npz").read_bytes() == before
    assert os.listdir(tmp_path) == ["state.npz"]


def test_the_simulation_never_changes_the_callers_scene():
    scene = springsim.load_scene("jelly-plane")
    simulation = springsim.Simulation(scene, integrator="implicit_euler", dt=0.02)
    assert (scene.integrator, scene.dt) == ("rk4", 0.001)
    assert (simulation.scene.integrator, simulation.scene.dt) == ("implicit_euler", 0.02)
    simulation.scene.bodies[0].particle_mass = 2.0
    assert scene.bodies[0].particle_mass == 1.0


# --- springsim run --checkpoint-every / --resume ------------------------------------------------

RUN = ["run", "jelly-plane", *SIDEWAYS_SET, "--integrator", "implicit_euler", "--dt", "0.01",
       "--duration", "1.0", "--fps", "30", "--quiet"]


def assert_same_recording(path_a, path_b):
    with np.load(path_a) as a, np.load(path_b) as b:
        assert sorted(a.files) == sorted(b.files)
        for name in set(a.files) - TIMINGS:
            assert a[name].dtype == b[name].dtype and np.array_equal(a[name], b[name]), name


def test_a_resumed_run_writes_the_npz_of_the_run_that_never_stopped(tmp_path, monkeypatch,
                                                                    capsys):
    assert main([*RUN, "--out", str(tmp_path / "whole.npz")]) == 0
    stop_after = 12
    original = interrupted_after_frame(monkeypatch, stop_after)
    out = tmp_path / "part.npz"
    assert main([*RUN, "--out", str(out), "--checkpoint-every", "0"]) == 130
    assert not out.exists()
    saved = tmp_path / "part.checkpoint.npz"
    with np.load(saved) as data:
        assert int(data["frames_done"]) == stop_after + 1
    monkeypatch.setattr(checkpoint, "write_checkpoint", original)
    assert main(["run", "--resume", str(saved), "--quiet"]) == 0   # to the --out it was given
    assert_same_recording(tmp_path / "whole.npz", out)
    capsys.readouterr()


@pytest.mark.parametrize("scene, stop_after", [("cloth-sweep", 18), ("jelly-conveyor", 12)])
def test_a_resumed_run_of_a_moving_world_writes_the_npz_of_the_run_that_never_stopped(
        tmp_path, monkeypatch, capsys, scene, stop_after):
    """Stopped mid-motion (frame 18, 0.6 s: the sphere in the curtain, carrying it; frame 12,
    0.4 s: the platform turning under the cubes) and resumed from its checkpoint: the motions
    are functions of time, so the recording is the uninterrupted one's, bit for bit."""
    run = ["run", scene, "--duration", "1.0", "--fps", "30", "--quiet"]
    assert main([*run, "--out", str(tmp_path / "whole.npz")]) == 0
    original = interrupted_after_frame(monkeypatch, stop_after)
    out = tmp_path / "part.npz"
    assert main([*run, "--out", str(out), "--checkpoint-every", "0"]) == 130
    monkeypatch.setattr(checkpoint, "write_checkpoint", original)
    assert main(["run", "--resume", str(tmp_path / "part.checkpoint.npz"), "--quiet"]) == 0
    assert_same_recording(tmp_path / "whole.npz", out)
    capsys.readouterr()


def frames_done(path) -> int:
    try:
        with np.load(path) as data:
            return int(data["frames_done"])
    except FileNotFoundError:
        return 0


def test_a_run_killed_after_a_checkpoint_resumes_to_the_same_npz(tmp_path):
    """A real interruption: SIGKILL once a checkpoint holds the cube on the plane (frame 20 of
    91, 0.67 s; it lands at 0.45 s), or later: whatever frame it holds, the result is the same."""
    command = [sys.executable, "-m", "springsim", *RUN, "--duration", "3"]
    subprocess.run([*command, "--out", "whole.npz"], cwd=tmp_path, check=True, timeout=300)
    run = subprocess.Popen([*command, "--out", "part.npz", "--checkpoint-every", "0"],
                           cwd=tmp_path)
    try:
        deadline = time.monotonic() + 300
        while frames_done(tmp_path / "part.checkpoint.npz") < 20 and run.poll() is None:
            assert time.monotonic() < deadline
            time.sleep(0.002)
    finally:
        os.kill(run.pid, signal.SIGKILL)
        run.wait()
    assert not (tmp_path / "part.npz").exists() or run.returncode == 0
    (tmp_path / "part.npz").unlink(missing_ok=True)
    print("killed after frame", frames_done(tmp_path / "part.checkpoint.npz"))
    resumed = subprocess.run([*command[:3], "run", "--resume", "part.checkpoint.npz", "--quiet"],
                             cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert_same_recording(tmp_path / "whole.npz", tmp_path / "part.npz")


def interrupted_after_first_checkpoint(monkeypatch):
    return interrupted_after_frame(monkeypatch, None)


def interrupted_after_frame(monkeypatch, stop_after):
    """Make a run stop, as at Ctrl+C, once it has written the checkpoint of frame
    ``stop_after`` (None: the first); returns the writer to put back for a resume."""
    original = checkpoint.write_checkpoint

    def write_then_stop(path, simulation, recording, frame, *rest):
        original(path, simulation, recording, frame, *rest)
        if stop_after is None or frame == stop_after:
            raise KeyboardInterrupt   # as Ctrl+C between two frames
    monkeypatch.setattr(checkpoint, "write_checkpoint", write_then_stop)
    return original


def test_a_completed_run_removes_its_checkpoint_and_an_interrupted_one_keeps_it(
        tmp_path, monkeypatch, capsys):
    out = tmp_path / "x.npz"
    assert main([*RUN, "--duration", "0.1", "--out", str(out), "--checkpoint-every", "0"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.npz"]
    original = interrupted_after_first_checkpoint(monkeypatch)
    assert main([*RUN, "--duration", "0.1", "--out", str(out), "--checkpoint-every", "0"]) == 130
    assert (tmp_path / "x.checkpoint.npz").exists()
    monkeypatch.setattr(checkpoint, "write_checkpoint", original)
    assert main(["run", "--resume", str(tmp_path / "x.checkpoint.npz"), "--quiet"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.npz"]
    capsys.readouterr()


def test_resume_refuses_options_that_would_change_the_run_and_foreign_files(tmp_path, capsys,
                                                                            monkeypatch):
    out = tmp_path / "x.npz"
    assert main([*RUN, "--duration", "0.1", "--out", str(out)]) == 0
    interrupted_after_first_checkpoint(monkeypatch)    # the run's checkpoint, its NPZ kept
    assert main([*RUN, "--duration", "0.1", "--out", str(out), "--checkpoint-every", "0"]) == 130
    capsys.readouterr()
    saved = str(tmp_path / "x.checkpoint.npz")
    cases = [(["jelly-plane"], "give no scene"), (["--dt", "0.02"], "give no --dt"),
             (["--fps", "60"], "give no --fps"), (["--set", "drag=1"], "give no --set")]
    for extra, problem in cases:
        code, err = main(["run", "--resume", saved, *extra]), capsys.readouterr().err
        assert code == 2 and problem in err and len(err.splitlines()) == 1, err
    for path, problem in [(str(out), "is not a springsim-checkpoint file"),
                          (str(tmp_path / "none.npz"), "no such file")]:
        code, err = main(["run", "--resume", path]), capsys.readouterr().err
        assert code == 2 and problem in err and len(err.splitlines()) == 1, err
    code, err = main(["run"]), capsys.readouterr().err
    assert code == 2 and "--resume CHECKPOINT" in err
    code, err = main([*RUN, "--checkpoint-every", "nan"]), capsys.readouterr().err
    assert code == 2 and err.startswith("springsim run: --checkpoint-every = nan")


def test_a_resumed_runs_wall_time_includes_the_time_before_it_stopped(tmp_path, monkeypatch):
    """Issue 28, item 8: after --resume the summary said "6.69 s stepping, 4.01 s with
    recording": the checkpoint kept the stepping time so far but not the wall time. The wall
    time (stepping and recording) is never less than the stepping time."""
    out = tmp_path / "x.npz"
    original = interrupted_after_frame(monkeypatch, 10)
    assert main([*RUN, "--duration", "0.5", "--out", str(out), "--checkpoint-every", "0"]) == 130
    with np.load(tmp_path / "x.checkpoint.npz") as data:
        before = float(data["recording.step_seconds"]), float(data["recording.wall_seconds"])
    assert 0 < before[0] <= before[1]
    monkeypatch.setattr(checkpoint, "write_checkpoint", original)
    assert main(["run", "--resume", str(tmp_path / "x.checkpoint.npz"), "--quiet"]) == 0
    with np.load(out) as data:
        step, wall = float(data["step_seconds"]), float(data["wall_seconds"])
    assert before[0] < step <= wall and before[1] < wall
