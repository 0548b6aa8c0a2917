"""Run and fit share one time base (issue 56, item 4).

`springsim run ... --dt 0.016667 --fps 30` wrote a take whose last frame, at the duration, came
after a shorter step, and `fit` with the same options refused it ("is not a whole number of
steps"); `--dt 0.016667` at the default 60 fps said "longer than 1/fps" on every run. Oracles: a
dt written as a frame's step to its own digits is that step exactly (1/60 s is 1/60 s), the
frames lie at the exact frame times k/fps, and the take `run` writes is accepted by `fit` with
the same options, whose loss at the starting values is zero (the same motion, compared with
itself).
"""
import json

import numpy as np
import pytest

from springsim.cli import main
from springsim.sampling import frame_step

SMALL = ["cloth-hang", "--integrator", "implicit_euler", "--dt", "0.016667",
         "--set", "bodies.0.particles_per_edge=4"]


@pytest.mark.parametrize("dt, fps, exact", [
    (0.016667, 60, 1 / 60), (0.016667, 30, 1 / 60), (0.033333, 30, 1 / 30),
    (0.033333, 60, 2 / 60), (0.0167, 60, 1 / 60), (0.008333, 60, 1 / 120),
    (1 / 60, 60, 1 / 60),
    # not a frame's step written short: kept as given
    (0.02, 60, 0.02), (0.017, 60, 0.017), (0.001, 60, 0.001), (0.000125, 60, 0.000125),
])
def test_a_dt_that_rounds_a_frames_step_is_that_step(dt, fps, exact):
    assert frame_step(dt, fps) == exact


def test_a_take_that_run_writes_is_fitted_with_the_same_options(tmp_path, capsys):
    take, fitted = tmp_path / "take.npz", tmp_path / "fitted.toml"
    assert main(["run", *SMALL, "--duration", "0.2", "--fps", "30", "--quiet",
                 "--out", str(take)]) == 0
    with np.load(take) as arrays:
        np.testing.assert_allclose(arrays["time"], np.arange(7) / 30, rtol=0, atol=1e-15)
        assert int(arrays["steps"]) == 12   # 12 steps of 1/60 s: no shorter last step
        assert float(arrays["dt"]) == 1 / 60 and float(arrays["fps"]) == 30
    capsys.readouterr()
    assert main(["fit", *SMALL, "--observed", str(take), "--fit", "bodies.0.structural.ks",
                 "--max-iterations", "1", "--out", str(fitted)]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["loss"] < 1e-20   # the same motion: the take is compared with itself


def test_a_frames_step_written_short_runs_without_a_warning_at_60_fps(tmp_path, capsys):
    out = tmp_path / "take.npz"
    assert main(["run", *SMALL, "--duration", "0.1", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "longer than 1/fps" not in captured.err
    assert "0.1 s in 6 steps (7 frames at 60 fps)" in captured.out
    with np.load(out) as arrays:
        np.testing.assert_allclose(arrays["time"], np.arange(7) / 60, rtol=0, atol=1e-15)


def test_two_frames_written_short_record_at_half_the_rate(tmp_path, capsys):
    """`--dt 0.033333` at the default 60 fps: "1 s in 31 steps (31 frames at 30.0003 fps)"
    before; now a step of 1/30 s exactly, a frame a step at 30 fps, and no shorter last step."""
    out = tmp_path / "take.npz"
    assert main(["run", *SMALL[:4], "0.033333", *SMALL[5:], "--duration", "0.2",
                 "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "0.2 s in 6 steps (7 frames at 30 fps)" in captured.out
    assert "(30 fps)" in captured.err   # still said: 60 fps were asked for


def test_a_take_whose_duration_dt_does_not_divide_is_fitted_with_the_same_options(tmp_path,
                                                                                 capsys):
    """`run --dt 0.007 --duration 0.25` ends after a shorter step (frame 0.25 s, 35 steps of
    0.007 s and one of 0.005 s), which `fit` refused with the same options ("time 0.25 s is not
    a whole number of steps"). The fit takes whole steps only: it compares the frames on them,
    leaving out the last, and says so in one line."""
    options = [*SMALL[:4], "0.007", *SMALL[5:]]
    take, fitted = tmp_path / "take.npz", tmp_path / "fitted.toml"
    assert main(["run", *options, "--duration", "0.25", "--fps", "30", "--quiet",
                 "--out", str(take)]) == 0
    with np.load(take) as arrays:
        assert arrays["time"][-1] == pytest.approx(0.25, abs=1e-12)
        frames = len(arrays["time"])
    capsys.readouterr()
    assert main(["fit", *options, "--observed", str(take), "--fit", "bodies.0.structural.ks",
                 "--max-iterations", "1", "--out", str(fitted),
                 "--plot", str(tmp_path / "fit.png")]) == 0
    assert (tmp_path / "fit.png").stat().st_size > 0   # the fitted frames are one fewer
    captured = capsys.readouterr()
    result = json.loads(captured.out.strip().splitlines()[-1])
    assert result["loss"] < 1e-20   # the frames before the last: the same motion
    said = [line for line in captured.err.splitlines() if "shorter" in line]
    assert said == [f"springsim fit: warning: {take}: the last frame, at 0.25 s, follows a step "
                    f"shorter than dt = 0.007 s (the run ended at its duration): compared at "
                    f"the {frames - 1} frames before it, on whole steps"], captured.err


def test_a_take_of_another_time_base_is_still_refused_without_a_warning(tmp_path, capsys):
    """Only a last frame after a shorter step is left out: frames off the step grid before it
    are refused as before, in one line, and nothing is said of the last."""
    take = tmp_path / "take.npz"
    assert main(["run", *SMALL[:4], "0.01", *SMALL[5:], "--duration", "0.25", "--fps", "100",
                 "--quiet", "--out", str(take)]) == 0
    capsys.readouterr()
    assert main(["fit", *SMALL[:4], "0.007", *SMALL[5:], "--observed", str(take),
                 "--fit", "bodies.0.structural.ks", "--max-iterations", "1",
                 "--out", str(tmp_path / "fitted.toml")]) == 2
    err = capsys.readouterr().err
    assert "is not a whole number of steps of dt = 0.007 s" in err and "shorter" not in err


def test_a_sweeps_saved_run_is_a_take_fit_accepts_with_the_same_dt(tmp_path, capsys):
    """A sweep reads `dt = 0.016667` as `run` does, 1/60 s exactly: its saved runs lie on the
    step grid `fit --dt 0.016667` compares on (they were 0.016667 s apart, 3e-7 s a frame off
    1/60 s, and fit refused them from the second frame on)."""
    import springsim

    out = tmp_path / "sweep"
    table = springsim.sweep("cloth-hang", vary={"bodies.0.structural.ks": [25000.0]},
                            overrides=["integrator=implicit_euler", "dt=0.016667",
                                       "bodies.0.particles_per_edge=4", "duration=0.2"],
                            workers=1, out=str(out), save="npz")
    take = out / table[0]["npz"]
    with np.load(take) as arrays:
        assert float(arrays["dt"]) == 1 / 60
        np.testing.assert_allclose(arrays["time"], np.arange(13) / 60, rtol=0, atol=1e-15)
    capsys.readouterr()
    assert main(["fit", *SMALL, "--observed", str(take), "--fit", "bodies.0.structural.ks",
                 "--max-iterations", "1", "--out", str(tmp_path / "fitted.toml")]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["loss"] < 1e-20
