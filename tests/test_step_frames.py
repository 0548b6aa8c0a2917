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
    dt = 0.033333
    assert main(["run", "jelly-plane", *SMALL, "--dt", str(dt), "--duration", "0.3",
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert ("springsim run: dt = 0.033333 s is longer than 1/fps = 0.0166667 s: recording a "
            "frame at every step, at the steps' own times (30.0003 fps)") in err.splitlines()
    with np.load(out) as take:
        assert np.array_equal(take["time"], np.arange(10) * dt)
        assert float(take["fps"]) == 1 / dt


def test_a_step_as_long_as_a_frame_keeps_the_fps_asked_for(tmp_path, capsys):
    out = tmp_path / "take.npz"
    assert main(["run", "jelly-plane", *SMALL, "--dt", "0.02", "--fps", "50", "--duration",
                 "0.2", "--out", str(out)]) == 0
    assert "recording a frame at every step" not in capsys.readouterr().err
    with np.load(out) as take:
        assert float(take["fps"]) == 50 and len(take["time"]) == 11
