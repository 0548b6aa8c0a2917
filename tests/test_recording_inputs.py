"""`springsim render` and `springsim export` take a recording (the NPZ of `springsim run`) as well
as a scene, a recording of any size; a file that is neither gets one line saying so (issue 28,
item 4).

Oracle: the frames the renderer is handed are the recording's own (at its rate) or the linear
interpolation between its two frames around each new time; a scene exported directly gives the
same cache, byte for byte, as its recording exported."""
import numpy as np
import pytest

import springsim.render
from springsim.cli import main
from springsim.export import load_take
from springsim.recording import write_npz

SMALL = ["--set", "bodies.0.particles_per_edge=3", "--duration", "0.2", "--fps", "20", "--quiet"]


@pytest.fixture(scope="module")
def take(tmp_path_factory):
    """jelly-plane's cube of 3 x 3 x 3, 0.2 s at 20 fps, and a copy padded beyond 16 MB."""
    folder = tmp_path_factory.mktemp("takes")
    path = folder / "take.npz"
    assert main(["run", "jelly-plane", *SMALL, "--out", str(path)]) == 0
    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files}
    big = folder / "big.npz"
    write_npz(big, {**arrays, "padding": np.ones(17 * 2 ** 20, np.uint8)})
    assert big.stat().st_size > 16 * 2 ** 20
    return path, big, arrays


@pytest.fixture
def rendered(monkeypatch):
    calls = []

    def render_video(model, times, positions, path, *, fps, **options):
        calls.append((model.particle_count, np.array(times), np.array(positions), fps))
        return path

    monkeypatch.setattr(springsim.render, "render_video", render_video)
    return calls


@pytest.mark.parametrize("which", [0, 1])
def test_render_draws_a_recordings_own_frames(take, rendered, tmp_path, capsys, which):
    path = take[which]
    arrays = take[2]
    assert main(["render", str(path), "--out", str(tmp_path / "x.mp4"), "--quiet"]) == 0
    (particles, times, positions, fps), = rendered
    assert capsys.readouterr().err == ""
    assert fps == 20 and particles == arrays["positions"].shape[1]
    np.testing.assert_array_equal(times, arrays["time"])
    np.testing.assert_array_equal(positions, arrays["positions"])


def test_render_at_another_rate_interpolates_between_recorded_frames(take, rendered, tmp_path):
    _, _, arrays = take
    assert main(["render", str(take[0]), "--out", str(tmp_path / "x.gif"), "--fps", "40",
                 "--duration", "0.1", "--quiet"]) == 0
    (_, times, positions, fps), = rendered
    recorded = arrays["positions"]
    np.testing.assert_allclose(times, np.arange(5) / 40, atol=1e-12)
    np.testing.assert_allclose(positions[::2], recorded[:3], atol=1e-12)
    np.testing.assert_allclose(positions[1::2], (recorded[:2] + recorded[1:3]) / 2, atol=1e-12)


def test_a_scene_exported_directly_is_its_recording_exported(take, tmp_path):
    scene = tmp_path / "cube.toml"
    scene.write_text('name = "cube"\nduration = 0.1\n[[bodies]]\ntype = "cube"\n'
                     'particles_per_edge = 3\nposition = [0.0, 1.0, 0.0]\n')
    recording = tmp_path / "cube.npz"
    assert main(["run", str(scene), "--out", str(recording), "--quiet"]) == 0
    assert main(["export", "--quiet", str(recording), str(tmp_path / "a.pc2")]) == 0
    assert main(["export", "--quiet", str(scene), str(tmp_path / "b.pc2")]) == 0
    assert (tmp_path / "a.pc2").read_bytes() == (tmp_path / "b.pc2").read_bytes()


@pytest.mark.parametrize("command", [["render", "--out", "x.mp4"], ["export", "x.usda"]])
def test_a_file_that_is_neither_gets_one_line_saying_so(tmp_path, capsys, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "photo.jpg").write_bytes(b"\xff\xd8\xff\xe0\x81\x00 binary")
    assert main([command[0], "photo.jpg", *command[1:]]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"springsim {command[0]}: scene = 'photo.jpg': is neither a scene "
                                "file (it is not UTF-8 text) nor a recording (it is not an NPZ "
                                "file)"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["photo.jpg"]


def test_run_given_a_recording_says_it_is_one(take, capsys):
    assert main(["run", str(take[0]), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert len(err.splitlines()) == 1 and "is a recording (an NPZ file), not a scene" in err


def test_export_at_another_rate_and_start_frame_resamples_the_recording(take, tmp_path):
    """Issue 28, item 5: a 20 fps take exported at 40 fps from frame 1001: the stage's rate is
    40, its time codes 1001 ... 1008, and code 1001 + k holds the positions at k / 40 s (the
    recorded frame, or the mean of the two around it); the PC2's header says 1001 too."""
    import struct

    from pxr import Usd, UsdGeom

    path, _, arrays = take
    usd, pc2 = tmp_path / "take.usda", tmp_path / "take.pc2"
    assert main(["export", "--quiet", "--fps", "40", "--start-frame", "1001", str(path),
                 str(usd), str(pc2)]) == 0
    stage = Usd.Stage.Open(str(usd))
    assert stage.GetTimeCodesPerSecond() == stage.GetFramesPerSecond() == 40
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1001, 1009)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/take/bodies/cube0"))
    surface = np.unique(load_take(path).layout.bodies[0].surface)
    recorded = arrays["positions"][:, surface]
    seen = np.stack([np.asarray(mesh.GetPointsAttr().Get(1001 + k)) for k in range(9)])
    np.testing.assert_allclose(seen[::2], recorded, atol=1e-5)
    np.testing.assert_allclose(seen[1::2], (recorded[:-1] + recorded[1:]) / 2, atol=1e-5)
    start, rate, samples = struct.unpack("<ffi", pc2.read_bytes()[20:32])
    assert (start, rate, samples) == (1001.0, 1.0, 9)


def test_export_numbers_the_first_frame_1_by_default(take, tmp_path):
    from pxr import Usd

    assert main(["export", "--quiet", str(take[0]), str(tmp_path / "take.usda")]) == 0
    stage = Usd.Stage.Open(str(tmp_path / "take.usda"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1, 5)


def test_run_names_a_scene_files_output_after_the_file(tmp_path, monkeypatch, capsys):
    """Issue 28, item 8: a copy of jelly-plane keeps the name "jelly-plane" inside, and its
    output is still my_scene.npz (not jelly-plane.npz, the preset's own output)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my_scene.toml").write_text('name = "jelly-plane"\nduration = 0.05\n[[bodies]]\n'
                                            'type = "cube"\nparticles_per_edge = 3\n')
    assert main(["run", "my_scene.toml", "--quiet"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["my_scene.npz", "my_scene.toml"]


def test_render_of_a_recording_to_a_log_prints_one_line_per_stage_and_no_bars(take, tmp_path):
    """Issue 28, item 8: with stderr a file (a log), `render` says what it does in one line on
    stdout and draws no progress bar (tqdm's carriage returns) and nothing on stderr; the GIF has
    the recording's 5 frames."""
    import subprocess
    import sys

    import imageio.v3 as iio

    out = tmp_path / "take.gif"
    done = subprocess.run([sys.executable, "-m", "springsim", "render", str(take[0]), "--out",
                           str(out), "--width", "64", "--height", "48"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert done.stderr == "" and done.stdout.splitlines()[0] == f"rendering 5 frames to {out}"
    assert len(done.stdout.splitlines()) == 2    # and the summary: wrote ...
    assert "\r" not in done.stdout + done.stderr
    assert iio.imread(out, index=None).shape[:3] == (5, 48, 64)


def test_a_re_run_sweep_says_it_skipped_the_runs_done_and_names_its_table(tmp_path, capsys,
                                                                         monkeypatch):
    """Issue 28, item 8: `--out s/` is reported as s/results.csv (not s//results.csv), and a
    sweep run again says that its runs were already done."""
    monkeypatch.chdir(tmp_path)
    sweep = ["sweep", "jelly-plane", "--vary", "bodies.0.structural.ks=1000,2000", "--duration",
             "0.05", "--workers", "1", "--set", "bodies.0.particles_per_edge=3", "--out", "s/"]
    assert main(sweep) == 0
    out, err = capsys.readouterr()
    assert out.strip().endswith("wrote s/results.csv") and "already" not in err
    assert main(sweep) == 0
    out, err = capsys.readouterr()
    assert "2 of 2 runs are already in s/results.csv; skipped them, running 0" in err


def test_counts_of_one_are_singular():
    from springsim.commands.stability import plural

    assert (plural(1, "scene"), plural(2, "scene")) == ("1 scene", "2 scenes")


def test_a_printed_built_in_scene_names_its_meshes_portably_and_runs_from_another_folder(
        tmp_path, capsys, monkeypatch):
    """Issue 28, item 8: `springsim scenes jelly-torus > my.toml` wrote this installation's
    absolute path to its meshes. It writes ``builtin:NAME``, which the reader finds wherever
    springsim is installed: the file runs from another folder, and a mesh copied beside it
    works too."""
    import shutil

    from springsim.presets import MESHES
    from springsim.scenefile import load_scene

    assert main(["scenes", "jelly-torus"]) == 0
    text = capsys.readouterr().out
    assert str(MESHES) not in text and str(MESHES.parent) not in text
    files = [line for line in text.splitlines() if line.startswith("file = ")]
    assert files == ['file = "builtin:torus.obj"', 'file = "builtin:stairs.obj"']
    (tmp_path / "scenes").mkdir()
    (tmp_path / "elsewhere").mkdir()
    (tmp_path / "scenes" / "my.toml").write_text(text)
    monkeypatch.chdir(tmp_path / "elsewhere")
    scene = load_scene("../scenes/my.toml")
    assert (scene.bodies[0].file, scene.terrains[0].file) == (str(MESHES / "torus.obj"),
                                                               str(MESHES / "stairs.obj"))
    assert main(["run", "../scenes/my.toml", "--duration", "0.01", "--fps", "100", "--quiet",
                 "--out", "my.npz"]) == 0
    with np.load("my.npz") as take:
        assert take["positions"].shape[0] == 2 and np.all(np.isfinite(take["positions"]))
    # a mesh of one's own, beside the scene file, as the comment above the line says
    shutil.copy(MESHES / "torus.obj", tmp_path / "scenes" / "torus.obj")
    (tmp_path / "scenes" / "mine.toml").write_text(
        text.replace('"builtin:torus.obj"', '"torus.obj"'))
    assert load_scene("../scenes/mine.toml").bodies[0].file == "../scenes/torus.obj"


def test_a_builtin_mesh_that_is_not_installed_is_one_line(capsys):
    assert main(["scenes", "jelly-torus", "--set", "bodies.0.file=builtin:teapot.obj"]) == 2
    assert capsys.readouterr().err == (
        "springsim scenes: bodies.0.file = 'builtin:teapot.obj': is not a file installed with "
        "springsim; those are builtin:platform.obj, builtin:stairs.obj, builtin:torus.obj, "
        "builtin:walking-figure.obj, builtin:walking-figure.pc2\n")