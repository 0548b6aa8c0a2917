"""The command line as a user meets it: `springsim scenes`, `run` and `bench`.

Oracles: a printed scene file reads back to the same scene; the run's NPZ has duration * fps + 1
frames and the summary's centre of mass is that of its last frame; a diverging run exits 3 with
one line and writes nothing; a bad scene exits 2 with one line naming the key; the video gets the
recorded frames; bench's figures agree with each other and with the cube's analytic spring count.
"""
import json
import os
import re
import subprocess
import sys
import types

import numpy as np
import pytest

import springsim
from springsim.cli import main
from springsim.presets import PRESETS

N = 4
SMALL = ["--set", f"bodies.0.particles_per_edge={N}", "--set", "bodies.0.position.1=2"]
SPRINGS = 3 * N ** 2 * (N - 1) + 6 * N * (N - 1) ** 2 + 4 * (N - 1) ** 3 + 3 * N ** 2 * (N - 2)
DIVERGING = ["--integrator", "explicit_euler", "--dt", "0.01"]  # unstable on the jelly cube


def run_cli(capsys, *argv):
    code = main(list(argv))
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_scenes_lists_every_preset_on_a_line_of_its_own(capsys):
    code, out, _ = run_cli(capsys, "scenes")
    lines = out.splitlines()
    assert code == 0 and len(lines) == len(PRESETS)
    assert sorted(line.split()[0] for line in lines) == sorted(PRESETS)


def test_a_printed_scene_reads_back_to_the_same_scene(capsys, tmp_path):
    override = "bodies.0.particles_per_edge=5"
    code, out, _ = run_cli(capsys, "scenes", "jelly-bowl", "--set", override)
    path = tmp_path / "bowl.toml"
    path.write_text(out)
    assert code == 0
    assert springsim.load_scene(path) == springsim.load_scene("jelly-bowl", [override])


def test_run_writes_the_frames_and_a_summary_that_agrees_with_them(capsys, tmp_path,
                                                                   monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "run", "jelly-plane", *SMALL, "--duration", "0.5",
                             "--fps", "20", "--set", "dt=0.002", "--dt", "0.0005",
                             "--plot", "energy.png")
    assert (code, err) == (0, "")
    assert sorted(os.listdir(tmp_path)) == ["energy.png", "jelly-plane.npz"]
    with np.load(tmp_path / "jelly-plane.npz") as data:
        assert data["positions"].shape == (0.5 * 20 + 1, N ** 3, 3)
        assert float(data["dt"]) == 0.0005              # --dt comes after --set
        centre = data["mass"] @ data["positions"][-1] / data["mass"].sum()
    printed = re.search(r"final centre of mass\s+\(([^)]*)\)", out).group(1)
    np.testing.assert_allclose([float(value) for value in printed.split(",")], centre,
                               rtol=1e-3, atol=1e-3)


def test_a_diverging_run_exits_3_with_one_line_and_writes_nothing(capsys, tmp_path):
    out_path = tmp_path / "diverged.npz"
    code, out, err = run_cli(capsys, "run", "jelly-plane", *SMALL, *DIVERGING,
                             "--out", str(out_path), "--plot", str(tmp_path / "energy.png"))
    assert code == 3 and out == ""
    assert len(err.splitlines()) == 1 and "diverged" in err and "explicit_euler" in err
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("argv, key", [
    (["--set", "bodies.0.particle_mass=-1"], "bodies.0.particle_mass"),
    (["--set", "bodies.0.position=[0, -3, 0]"], "bodies.0.position"),   # inside the plane
    (["--set", "bodies.0.nope=1"], "bodies.0.nope"),
    (["--integrator", "leapfrog"], "integrator"),
    (["--out", "no/such/folder/x.npz"], "--out"),
    (["--plot", "energy.jpeg"], "plot"),
])
def test_a_bad_scene_exits_2_with_one_line_naming_the_key(capsys, tmp_path, monkeypatch,
                                                          argv, key):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(capsys, "run", "jelly-plane", *argv)
    assert (code, out, os.listdir(tmp_path)) == (2, "", [])
    assert len(err.splitlines()) == 1 and err.startswith(f"springsim run: {key} = ")


def test_video_gets_the_recorded_frames(capsys, tmp_path, monkeypatch):
    calls = []

    def write_video(model, times, positions, path, *, fps=60, width=960, height=540):
        calls.append((model.particle_count, np.array(times), np.array(positions), path, fps))

    fake = types.ModuleType("springsim.render")
    fake.write_video = write_video
    monkeypatch.setitem(sys.modules, "springsim.render", fake)
    monkeypatch.setattr(springsim, "render", fake, raising=False)
    out_path, video = tmp_path / "frames.npz", str(tmp_path / "movie.mp4")
    code, _, _ = run_cli(capsys, "run", "jelly-plane", *SMALL, "--duration", "0.25",
                         "--fps", "20", "--out", str(out_path), "--video", video, "--quiet")
    assert code == 0 and len(calls) == 1
    particles, times, positions, path, fps = calls[0]
    with np.load(out_path) as data:
        np.testing.assert_array_equal(times, data["time"])
        np.testing.assert_array_equal(positions, data["positions"])
    assert (particles, path, fps) == (N ** 3, video, 20.0)


def test_bench_json_is_one_object_whose_figures_agree(capsys):
    code, out, _ = run_cli(capsys, "bench", "jelly-plane", *SMALL, "--integrator", "rk4",
                           "--steps", "300", "--json")
    assert code == 0 and len(out.strip().splitlines()) == 1
    result = json.loads(out)
    assert result["steps_per_second"] > 0 and result["steps"] == 300
    assert (result["particles"], result["springs"]) == (N ** 3, SPRINGS)
    assert (result["integrator"], result["dt"], result["scene"]) == ("rk4", 0.001, "jelly-plane")
    assert result["ms_per_step"] * result["steps_per_second"] == pytest.approx(1000)
    assert result["real_time_factor"] == pytest.approx(result["steps_per_second"] * 0.001)
    assert result["build_seconds"] >= 0 and result["peak_memory_mb"] > 0


def test_bench_refuses_a_step_count_below_one(capsys):
    code, _, err = run_cli(capsys, "bench", "jelly-plane", *SMALL, "--steps", "0")
    assert code == 2 and err.startswith("springsim bench: steps = 0")


def test_python_dash_m_shows_a_user_one_line_and_no_traceback_on_divergence(tmp_path):
    result = subprocess.run([sys.executable, "-m", "springsim", "run", "jelly-plane", *SMALL,
                             *DIVERGING], cwd=tmp_path, capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 3 and result.stdout == ""
    assert len(result.stderr.splitlines()) == 1 and "Traceback" not in result.stderr
    assert os.listdir(tmp_path) == []
