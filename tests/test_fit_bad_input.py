"""`springsim fit` refuses bad observations in one line, before any work (issue 32, part 6): an
observed take of another particle count or time base, or longer than the run; marker CSVs whose
markers match no particle (by index or by distance), with a wrong header or a bad number; a
parameter that is not there or not differentiable. Exit code 2, one line on stderr naming the
key, and no fitted scene written."""
import numpy as np
import pytest

from springsim.bodies.cube import Cube
from springsim.cli import main
from springsim.scene import Scene
from springsim.scenefile import scene_to_toml

OPTIONS = ["--integrator", "rk4", "--dt", "0.002"]


@pytest.fixture
def scene_file(tmp_path):
    """The small pinned cube of test_gradients.py: 27 particles, 1 m, its corner 0 at
    (-0.5, 1.5, -0.5)."""
    scene = Scene(bodies=[Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 2.0, 0.0),
                               pinned=(0,))], terrains=[], drag=0.1)
    path = tmp_path / "cube.toml"
    path.write_text(scene_to_toml(scene))
    return path


def take(path, times, particles=27):
    rng = np.random.default_rng(0)
    np.savez(path, time=np.asarray(times, float),
             positions=rng.normal(0.0, 1.0, (len(times), particles, 3)))
    return path


def markers(path, text):
    path.write_text(text)
    return path


def refused(capsys, tmp_path, scene_file, observed, words, *extra):
    out = tmp_path / "fitted.toml"
    code = main(["fit", str(scene_file), *OPTIONS, "--observed", str(observed), "--fit",
                 "bodies.0.structural.ks", "--out", str(out), *extra])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(lines) == 1 and all(word in lines[0] for word in words), lines
    assert not out.exists()


def test_a_take_of_another_particle_count(capsys, tmp_path, scene_file):
    observed = take(tmp_path / "take.npz", [0.0, 0.1], particles=26)
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "26 particles",
                                                     "the scene has 27"])


def test_a_take_on_another_time_base(capsys, tmp_path, scene_file):
    observed = take(tmp_path / "take.npz", [0.0, 0.0105, 0.021])   # not steps of 2 ms
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "0.0105",
                                                     "whole number of steps"])


def test_a_take_longer_than_the_run(capsys, tmp_path, scene_file):
    observed = take(tmp_path / "take.npz", [0.0, 0.1, 0.2])
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "ends at 0.2 s"],
            "--duration", "0.1")


def test_a_file_that_is_no_take(capsys, tmp_path, scene_file):
    observed = tmp_path / "take.npz"
    observed.write_bytes(b"not a zip file")
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "is not an NPZ take"])


def test_a_marker_far_from_every_particle(capsys, tmp_path, scene_file):
    observed = markers(tmp_path / "m.csv",
                       "time,marker,x,y,z\n0.0,hand,5.0,5.0,5.0\n0.1,hand,5.0,5.0,5.0\n")
    refused(capsys, tmp_path, scene_file, observed, ["marker", "hand", "matches no particle"])


def test_a_marker_index_past_the_last_particle(capsys, tmp_path, scene_file):
    observed = markers(tmp_path / "m.csv",
                       "time,marker,x,y,z\n0.0,27,0.0,1.5,0.0\n0.1,27,0.0,1.5,0.0\n")
    refused(capsys, tmp_path, scene_file, observed,
            ["marker", "27", "a particle number from 0 to 26"], "--match", "index")


def test_a_marker_file_with_another_header(capsys, tmp_path, scene_file):
    observed = markers(tmp_path / "m.csv", "t,id,x,y,z\n0.0,1,0.0,1.5,0.0\n")
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "m.csv"])


def test_a_marker_row_with_a_missing_number(capsys, tmp_path, scene_file):
    observed = markers(tmp_path / "m.csv",
                       "time,marker,x,y,z\n0.0,0,-0.5,1.5,-0.5\n0.002,0,nan,1.5,-0.5\n")
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "m.csv"])


@pytest.mark.parametrize("key, words", [
    ("bodies.0.nothing", ["bodies.0.nothing", "names no parameter"]),
    ("bodies.0.particles_per_edge", ["bodies.0.particles_per_edge",
                                     "cannot be differentiated"]),
])
def test_a_parameter_that_cannot_be_fitted(capsys, tmp_path, scene_file, key, words):
    observed = take(tmp_path / "take.npz", [0.0, 0.1])
    out = tmp_path / "fitted.toml"
    code = main(["fit", str(scene_file), *OPTIONS, "--observed", str(observed), "--fit", key,
                 "--out", str(out)])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and all(word in lines[0] for word in words), lines
    assert not out.exists()


# --- issue 56, item 9: files that are not what they say, and options out of range ----------------

def _truncated(path, good):
    data = good.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def _corrupt(path, good):
    data = bytearray(good.read_bytes())
    middle = len(data) // 3   # inside the first array's bytes: its CRC no longer matches
    data[middle:middle + 64] = bytes(64)
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("damage", [
    lambda path, good: path.write_bytes(b""),            # empty
    _truncated,
    _corrupt,
    lambda path, good: np.save(path.with_suffix(".npy"), np.zeros(3)) or
    path.with_suffix(".npy").rename(path),               # an .npy array named .npz
], ids=["empty", "truncated", "corrupt", "npy"])
def test_a_damaged_take_is_one_line(capsys, tmp_path, scene_file, damage):
    good = take(tmp_path / "good.npz", [0.0, 0.1])
    observed = tmp_path / "take.npz"
    damage(observed, good)
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "take.npz", "NPZ take"])


@pytest.mark.parametrize("damage", [
    lambda path, good: path.write_bytes(b""), _truncated, _corrupt,
], ids=["empty", "truncated", "corrupt"])
def test_observed_take_refuses_a_damaged_file_from_python(tmp_path, damage):
    from springsim.errors import SceneError
    from springsim.gradients.losses import ObservedTake

    good = take(tmp_path / "good.npz", [0.0, 0.1])
    observed = tmp_path / "take.npz"
    damage(observed, good)
    with pytest.raises(SceneError, match="NPZ take"):
        ObservedTake(observed)


@pytest.mark.parametrize("content", [bytes(range(256)) * 4, bytes(64), b"\xff\xfe\x00t\x00i\x00m\x00e"],
                         ids=["binary", "nul", "utf-16"])
def test_a_binary_marker_file_is_one_line(capsys, tmp_path, scene_file, content):
    observed = tmp_path / "m.csv"
    observed.write_bytes(content)
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "m.csv"])


def test_a_marker_at_a_negative_time(capsys, tmp_path, scene_file):
    observed = markers(tmp_path / "m.csv",
                       "time,marker,x,y,z\n-0.1,0,-0.5,1.5,-0.5\n0.0,0,-0.5,1.5,-0.5\n")
    refused(capsys, tmp_path, scene_file, observed, ["--observed", "line 2", "-0.1", ">= 0"])


@pytest.mark.parametrize("tolerance", ["nan", "-1", "inf"])
def test_a_tolerance_out_of_range(capsys, tmp_path, scene_file, tolerance):
    observed = take(tmp_path / "take.npz", [0.0, 0.1])
    refused(capsys, tmp_path, scene_file, observed, ["--tolerance", tolerance, ">= 0"],
            "--tolerance", tolerance)


@pytest.mark.parametrize("answer", ["1.5", b"1.5", [1.0, 2.0], None, True, ("1.5", 0.0)],
                         ids=["string", "bytes", "list", "none", "bool", "tuple of a string"])
def test_a_loss_that_returns_no_number(scene_file, answer):
    import springsim
    from springsim.errors import SceneError

    scene = springsim.load_scene(str(scene_file), ["dt=0.002"])

    def loss(frames):
        if isinstance(answer, tuple):
            return answer[0], np.zeros_like(frames)
        return answer

    with pytest.raises(SceneError) as refusal:
        springsim.gradient(scene, loss, ["bodies.0.structural.ks"], duration=0.004)
    assert str(refusal.value).startswith("loss = ") and "real number" in str(refusal.value)
    assert "\n" not in str(refusal.value)
