"""A step longer than a frame: frames at the steps' own times, said once (issue 28, item 3).

Oracle: `springsim run` at dt = 1/30 s and the default 60 fps used to keep 2 frames a step, the
second a copy (times 0, 1/30, 1/30, 2/30, ...), and a USD take stuttered; now every frame is a
step later than the one before, the recording's fps is 1/dt, and stderr says so.
"""
import numpy as np

from springsim.cli import main

SMALL = ["--set", "bodies.0.particles_per_edge=3", "--integrator", "implicit_euler"]


def test_a_step_longer_than_a_frame_records_a_frame_a_step(tmp_path, capsys):
    out = tmp_path / "take.npz"
    dt = 0.03   # not a frame's step written short (test_time_base.py): kept as given
    assert main(["run", "jelly-plane", *SMALL, "--dt", str(dt), "--duration", "0.31",
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert ("springsim run: dt = 0.03 s is longer than 1/fps = 0.0166667 s: recording a "
            "frame at every step, at the steps' own times (33.3333 fps)") in err.splitlines()
    with np.load(out) as take:
        assert np.array_equal(take["time"][:-1], np.arange(10) * dt)
        assert float(take["fps"]) == 1 / dt
        # the run ends at its duration, 0.31 s, not 10 dt = 0.3 s: a last, shorter step
        assert abs(take["time"][-1] - 0.31) < 1e-15 and int(take["steps"]) == 11


def test_a_run_ends_exactly_at_its_duration_when_dt_does_not_divide_it(tmp_path, capsys):
    """Issue 28, item 3: `--dt 0.033333 --duration 8` said "7.99992 s"; a ball falling freely
    (no terrain) under symplectic Euler ends at t = 0.1 s after 3 steps of 0.03 s and one of
    0.01 s, where the same steps taken by hand put it."""
    import springsim

    scene = tmp_path / "ball.toml"
    scene.write_text('duration = 0.1\ndt = 0.03\nintegrator = "symplectic_euler"\n'
                     'terrains = []\n[[bodies]]\ntype = "balls"\ndrag = 0.0\n[[bodies.balls]]\n'
                     'position = [0.0, 1.0, 0.0]\n')
    out = tmp_path / "ball.npz"
    assert main(["run", str(scene), "--fps", "20", "--out", str(out)]) == 0
    assert "0.1 s" in capsys.readouterr().out
    by_hand = springsim.Simulation(springsim.load_scene(str(scene)))
    by_hand.step(3)
    by_hand.step_shorter(0.1 - 3 * 0.03)
    with np.load(out) as take:
        assert take["time"][-1] == 0.1
        np.testing.assert_array_equal(take["positions"][-1], by_hand.positions)
        v = -9.8 * 0.1            # symplectic Euler: v = g t exactly under constant gravity
        assert abs(take["velocities"][-1][0, 1] - v) < 1e-12


def test_a_step_as_long_as_a_frame_keeps_the_fps_asked_for(tmp_path, capsys):
    out = tmp_path / "take.npz"
    assert main(["run", "jelly-plane", *SMALL, "--dt", "0.02", "--fps", "50", "--duration",
                 "0.2", "--out", str(out)]) == 0
    assert "recording a frame at every step" not in capsys.readouterr().err
    with np.load(out) as take:
        assert float(take["fps"]) == 50 and len(take["time"]) == 11
