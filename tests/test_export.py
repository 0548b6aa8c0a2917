"""Export: the recording's layout, and the USD, MDD, PC2 and OBJ files made from it.

Oracles: the layout read back from an NPZ is the model's (bodies, particle ranges, surfaces, an
embedding, ball radii, terrains equal to the scene's); the files are read back with independent
readers (Pixar's USD library; the MDD and PC2 byte layouts unpacked with ``struct`` as their
specifications say) and every vertex equals the recorded particle, or the embedding's weighted
sum of particles computed here by a plain loop; a ball's centre and radius are the recording's;
the stage's time codes per second is the fps and it has one time code per frame. Bad input gets
one line and exit 2 before any file is written; a failed write leaves the old file and no
temporary one.
"""
import os
import struct
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from springsim import Simulation, load_scene
from springsim.cli import main
from springsim.errors import SceneError
from springsim.export import export, extensions, load_take, take_from_arrays
from springsim.export import mdd as mdd_format
from springsim.model import BodySlice
from springsim.recording import record, write_npz
from springsim.recording_layout import LAYOUT_KEYS, layout_arrays, read_layout
from springsim.surfaces import Embedding

SMALL_BALLS = ["bodies.0.particles_per_edge=4"]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """jelly-balls with a 4 x 4 x 4 cube: 0.5 s at 20 fps, written to an NPZ file."""
    simulation = Simulation(load_scene("jelly-balls", SMALL_BALLS))
    recording = record(simulation, 0.5, 20.0)
    path = tmp_path_factory.mktemp("take") / "take.npz"
    write_npz(path, recording.arrays())
    return simulation, recording, path


def test_the_npz_layout_reads_back_to_the_models_bodies_balls_and_terrains(recorded):
    simulation, _, path = recorded
    model = simulation.model
    layout = load_take(path).layout
    assert not layout.legacy
    assert [(b.name, b.start, b.stop) for b in layout.bodies] == \
        [(b.name, b.start, b.stop) for b in model.bodies]
    for read, body in zip(layout.bodies, model.bodies):
        np.testing.assert_array_equal(read.surface, body.surface)
        assert read.embedding is None
    np.testing.assert_array_equal(layout.ball_particles, np.flatnonzero(model.arrays.radius > 0))
    np.testing.assert_array_equal(layout.ball_radii, [b.radius for b in
                                                      simulation.scene.bodies[1].balls])
    assert list(layout.terrains) == list(simulation.scene.terrains)


def test_an_embedding_survives_the_npz_row_for_row(tmp_path):
    model = _embedded_model()
    arrays = layout_arrays(model)
    np.savez(tmp_path / "layout.npz", **arrays)
    with np.load(tmp_path / "layout.npz") as data:
        layout = read_layout(dict(data))
    plain, embedded = layout.bodies
    assert plain.embedding is None and (plain.start, plain.stop) == (0, 4)
    np.testing.assert_array_equal(embedded.embedding.particles, model.bodies[1].embedding.particles)
    np.testing.assert_array_equal(embedded.embedding.weights, model.bodies[1].embedding.weights)
    np.testing.assert_array_equal(embedded.surface, model.bodies[1].surface)


@pytest.mark.parametrize("extension", [".usda", ".usdc", ".usd"])
def test_usd_holds_every_surface_vertex_and_ball_at_every_frame(recorded, tmp_path, extension):
    simulation, recording, path = recorded
    out = tmp_path / f"take{extension}"
    assert main([*"export --quiet".split(), str(path), str(out)]) == 0
    stage = Usd.Stage.Open(str(out))
    frames = recording.frame_count
    assert stage.GetTimeCodesPerSecond() == recording.fps == 20.0
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1, frames)  # from frame 1
    assert UsdGeom.GetStageUpAxis(stage) == "Y" and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    cube = simulation.model.bodies[0]
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/take/bodies/cube0"))
    indices = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 3)
    surface = np.unique(cube.surface)
    # the cube's surface triangles (the winding aside) over its surface particles, in order
    np.testing.assert_array_equal(np.sort(surface[indices], axis=1),
                                  np.sort(cube.surface, axis=1))
    for frame in range(frames):
        points = np.asarray(mesh.GetPointsAttr().Get(frame + 1), float)
        np.testing.assert_allclose(points, recording.positions[frame][surface], atol=1e-5)
        if frame == 0:   # wound to face outwards: the enclosed volume is positive, 4 x 4 x 4 m
            a, b, c = (points[indices[:, k]] for k in range(3))
            assert np.einsum("ij,ij->", a, np.cross(b, c)) / 6 == pytest.approx(64.0, rel=1e-5)
        extent = np.asarray(mesh.GetExtentAttr().Get(frame + 1))
        np.testing.assert_allclose(extent, [points.min(0), points.max(0)])
    for number, particle in enumerate(simulation.model.arrays.balls):
        sphere = UsdGeom.Sphere(stage.GetPrimAtPath(f"/take/balls/ball_{number}"))
        assert sphere.GetRadiusAttr().Get() == simulation.model.arrays.radius[particle]
        for frame in (0, frames // 2, frames - 1):
            world = sphere.ComputeLocalToWorldTransform(frame + 1)
            np.testing.assert_allclose(np.asarray(world.ExtractTranslation()),
                                       recording.positions[frame, particle], atol=1e-9)
    plane = UsdGeom.Mesh(stage.GetPrimAtPath("/take/terrains/terrain_0_plane"))
    corners = np.asarray(plane.GetPointsAttr().Get())
    np.testing.assert_allclose(corners[:, 1], -1.0)     # the scene's plane y = -1


def test_an_embedded_surface_exports_as_the_weighted_sums_of_its_particles(tmp_path):
    model = _embedded_model()
    rng = np.random.default_rng(3)
    positions = rng.normal(size=(5, model.particle_count, 3))
    arrays = {"time": np.arange(5) / 10, "fps": np.asarray(10.0), "positions": positions,
              "scene": np.asarray("hand-made"), **layout_arrays(model)}
    take = take_from_arrays(arrays)
    export(take, tmp_path / "take.usda")
    stage = Usd.Stage.Open(str(tmp_path / "take.usda"))
    embedding = model.bodies[1].embedding
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/take/bodies/embedded"))
    for frame in range(5):
        expected = np.zeros((len(embedding.particles), 3))
        for v in range(len(embedding.particles)):
            for k in range(8):
                expected[v] += embedding.weights[v, k] * positions[frame, embedding.particles[v, k]]
        np.testing.assert_allclose(np.asarray(mesh.GetPointsAttr().Get(frame + 1)), expected,
                                   atol=1e-5)


def test_mdd_and_pc2_unpack_by_their_specifications_to_the_recorded_points(recorded, tmp_path):
    simulation, recording, path = recorded
    mdd, pc2 = tmp_path / "take.mdd", tmp_path / "take.pc2"
    assert main(["export", "--quiet", str(path), str(mdd), str(pc2)]) == 0
    rest = _obj_vertices(tmp_path / "take.obj")
    cube = simulation.model.bodies[0]
    surface = np.unique(cube.surface)
    frames, count = recording.frame_count, len(rest)

    data = mdd.read_bytes()                     # big-endian: frames, points, times, points
    assert struct.unpack(">ii", data[:8]) == (frames, count)
    times = struct.unpack(f">{frames}f", data[8:8 + 4 * frames])
    np.testing.assert_allclose(times, recording.time, rtol=1e-6)
    mdd_points = np.frombuffer(data[8 + 4 * frames:], ">f4").reshape(frames, count, 3)

    data = pc2.read_bytes()                     # little-endian, a 32-byte header
    signature, version, points, start, rate, samples = struct.unpack("<12siiffi", data[:32])
    assert (signature, version, points, start, rate, samples) == \
        (b"POINTCACHE2\0", 1, count, 1.0, 1.0, frames)
    pc2_points = np.frombuffer(data[32:], "<f4").reshape(frames, count, 3)

    for cache in (mdd_points, pc2_points):
        np.testing.assert_allclose(cache[0], rest, atol=1e-6)   # the OBJ is the first frame
        # the cube's surface particles first, in ascending order, then a sphere per ball
        np.testing.assert_allclose(cache[:, :len(surface)], recording.positions[:, surface],
                                   atol=1e-5)
        balls = simulation.model.arrays.balls
        per_ball = (count - len(surface)) // len(balls)
        for number, particle in enumerate(balls):
            first = len(surface) + number * per_ball
            sphere = cache[:, first:first + per_ball]
            offset = np.linalg.norm(sphere - recording.positions[:, particle, None], axis=-1)
            np.testing.assert_allclose(offset, simulation.model.arrays.radius[particle], rtol=1e-5)


def test_a_recording_from_before_the_layout_still_exports_its_surface(recorded, tmp_path, capsys):
    _, recording, _ = recorded
    old = {key: value for key, value in recording.arrays().items() if key not in LAYOUT_KEYS}
    np.savez(tmp_path / "old.npz", **old)
    assert main(["export", "--quiet", str(tmp_path / "old.npz"), str(tmp_path / "old.usda")]) == 0
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "balls and terrains are left out" in err
    stage = Usd.Stage.Open(str(tmp_path / "old.usda"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/take/bodies/jelly_balls"))
    np.testing.assert_allclose(np.asarray(mesh.GetPointsAttr().Get(4)),
                               recording.positions[3][np.unique(recording.surface)], atol=1e-5)


@pytest.mark.parametrize("case, message", [
    ("not_npz", "is not an NPZ file"), ("other_npz", "is not a springsim recording"),
    ("missing", "no such file"), ("extension", "must end in one of .usd, .usda, .usdc"),
    ("folder", "does not exist"), ("target_is_folder", "is a folder"),
    ("damaged", "has a damaged layout"), ("inconsistent", "numbers particles up to")])
def test_bad_input_is_one_line_and_exit_2_and_writes_nothing(recorded, tmp_path, capsys, case,
                                                            message):
    recording, out = recorded[2], tmp_path / "take.usd"
    if case == "not_npz":
        recording = tmp_path / "notes.npz"
        recording.write_text("not a zip file")
    elif case == "other_npz":
        recording = tmp_path / "other.npz"
        np.savez(recording, weights=np.ones(3))
    elif case in ("damaged", "inconsistent"):
        with np.load(recording) as data:
            arrays = dict(data)
        if case == "damaged":
            arrays["body_surface_rows"] = arrays["body_surface_rows"][:1]
        else:
            arrays["ball_particles"] = arrays["ball_particles"] + 1000
        recording = tmp_path / f"{case}.npz"
        np.savez(recording, **arrays)
    elif case == "missing":
        recording = tmp_path / "nowhere.npz"
    elif case == "extension":
        out = tmp_path / "take.fbx"
    elif case == "folder":
        out = tmp_path / "no" / "take.usd"
    elif case == "target_is_folder":
        out = tmp_path / "folder.usd"
        out.mkdir()
    before = sorted(os.listdir(tmp_path))
    assert main(["export", str(recording), str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and err.startswith("springsim export:")
    assert sorted(os.listdir(tmp_path)) == before


def test_run_export_refuses_an_unknown_extension_before_simulating(tmp_path, capsys):
    out = tmp_path / "run.npz"
    code = main(["run", "jelly-balls", "--quiet", "--out", str(out),
                 "--export", str(tmp_path / "take.abc")])
    assert code == 2 and "--export" in capsys.readouterr().err and not out.exists()


def test_run_export_writes_the_recorded_frames(tmp_path):
    npz, usd, mdd = tmp_path / "run.npz", tmp_path / "run.usdc", tmp_path / "run.mdd"
    assert main(["run", "jelly-balls", "--quiet", "--duration", "0.2", "--fps", "10",
                 "--set", SMALL_BALLS[0], "--out", str(npz), "--export", str(usd),
                 "--export", str(mdd)]) == 0
    take = load_take(npz)
    stage = Usd.Stage.Open(str(usd))
    assert stage.GetEndTimeCode() == take.frame_count == 3
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/take/bodies/cube0"))
    surface = np.unique(take.layout.bodies[0].surface)
    np.testing.assert_allclose(np.asarray(mesh.GetPointsAttr().Get(3)),
                               take.positions[2, surface], atol=1e-5)
    assert (tmp_path / "run.obj").exists() and mdd.stat().st_size > 0


def test_a_failed_write_leaves_the_old_files_and_no_temporary_one(recorded, tmp_path,
                                                                  monkeypatch):
    take = load_take(recorded[2])
    (tmp_path / "take.mdd").write_bytes(b"old cache")
    (tmp_path / "take.obj").write_text("old mesh")

    def broken(file, points, times, fps, start_frame):
        file.write(b"half a cache")
        raise OSError("disk full")

    monkeypatch.setattr(mdd_format, "encode", broken)
    with pytest.raises(OSError):
        export(take, tmp_path / "take.mdd")
    assert sorted(os.listdir(tmp_path)) == ["take.mdd", "take.obj"]
    assert (tmp_path / "take.mdd").read_bytes() == b"old cache"
    assert (tmp_path / "take.obj").read_text() == "old mesh"


def test_every_extension_has_a_writer():
    assert set(extensions()) == {".usd", ".usda", ".usdc", ".mdd", ".pc2", ".obj", "#.obj"}


def test_an_obj_sequence_is_the_point_cache_frame_by_frame(recorded, tmp_path, capsys):
    """take_###.obj: a file a frame, numbered from --start-frame and padded to the #s, each the
    rest OBJ's faces with that frame's points of the PC2 (the same vertices, in its order)."""
    path = recorded[2]
    frames = recorded[1].frame_count
    assert main(["export", str(path), str(tmp_path / "take.pc2"),
                 str(tmp_path / "seq" / ".." / "take_###.obj"), "--start-frame", "7"]) == 0
    assert f"take_007.obj to {tmp_path}/seq/../take_{6 + frames:03d}.obj ({frames} files)" in \
        capsys.readouterr().out
    data = (tmp_path / "take.pc2").read_bytes()
    count = struct.unpack("<12siiffi", data[:32])[2]
    cache = np.frombuffer(data[32:], "<f4").reshape(frames, count, 3)
    rest_faces = _obj_faces(tmp_path / "take.obj")
    names = sorted(name for name in os.listdir(tmp_path) if name.startswith("take_"))
    assert names == [f"take_{7 + k:03d}.obj" for k in range(frames)]
    for k, name in enumerate(names):
        np.testing.assert_allclose(_obj_vertices(tmp_path / name), cache[k], atol=1e-6)
        np.testing.assert_array_equal(_obj_faces(tmp_path / name), rest_faces)


def test_an_obj_sequence_is_written_whole_or_not_at_all(recorded, tmp_path, monkeypatch):
    from springsim.export import obj_sequence

    take, calls = load_take(recorded[2]), []

    def failing(path, *args):
        calls.append(path)
        if len(calls) == 3:
            raise OSError("disk full")
        Path(path).write_text("v 0 0 0\n")

    monkeypatch.setattr(obj_sequence, "write_obj", failing)
    with pytest.raises(OSError):
        export(take, tmp_path / "frame_####.obj")
    assert os.listdir(tmp_path) == []
    (tmp_path / "frame_0003.obj").mkdir()       # a frame's name taken by a folder: refused first
    with pytest.raises(SceneError, match="frame_0003.obj.: is a folder"):
        export(take, tmp_path / "frame_####.obj")
    assert os.listdir(tmp_path) == ["frame_0003.obj"]


def test_an_obj_sequence_refuses_a_negative_start_frame_before_reading_the_take(tmp_path,
                                                                              capsys):
    code = main(["export", str(tmp_path / "missing.npz"), str(tmp_path / "f_##.obj"),
                 "--start-frame", "-1"])
    err = capsys.readouterr().err
    assert code == 2 and "--start-frame" in err and "0 or more" in err, err
    assert len(err.splitlines()) == 1 and os.listdir(tmp_path) == []


def _obj_faces(path) -> np.ndarray:
    lines = [line.split() for line in path.read_text().splitlines()]
    return np.array([[int(c) for c in line[1:]] for line in lines if line and line[0] == "f"])


def _obj_vertices(path) -> np.ndarray:
    lines = [line.split() for line in path.read_text().splitlines()]
    return np.array([[float(c) for c in line[1:]] for line in lines if line and line[0] == "v"])


class _Arrays:
    def __init__(self, count):
        self.balls = np.empty(0, np.int64)
        self.radius = np.zeros(count)


class _Model:
    """What layout_arrays reads of a model: a plain quad (particles 0-3) and a mesh body whose two
    triangles are embedded in the eight particles 4-11 of one lattice cell."""

    def __init__(self):
        rng = np.random.default_rng(7)
        weights = rng.random((4, 8))
        weights /= weights.sum(axis=1, keepdims=True)
        particles = np.tile(np.arange(4, 12), (4, 1))
        self.bodies = (BodySlice("plain", 0, 4, np.array([[0, 1, 2], [0, 2, 3]])),
                       BodySlice("embedded", 4, 12, np.array([[0, 1, 2], [1, 3, 2]]),
                                 Embedding(particles, weights)))
        self.arrays = _Arrays(12)
        self.terrains = ()
        self.particle_count = 12


def _embedded_model():
    return _Model()


def test_a_loaded_recording_keeps_its_layout_and_writes_it_again(recorded, tmp_path):
    from springsim.recording import Recording

    _, recording, path = recorded
    loaded = Recording.load(path)
    assert set(loaded.layout) == set(LAYOUT_KEYS)
    write_npz(tmp_path / "again.npz", loaded.arrays())
    with np.load(tmp_path / "again.npz") as again, np.load(path) as first:
        assert sorted(again.files) == sorted(first.files)
        for key in LAYOUT_KEYS:
            np.testing.assert_array_equal(again[key], first[key])


def test_an_export_too_large_for_memory_is_refused_before_writing(recorded, tmp_path,
                                                                  monkeypatch):
    take = load_take(recorded[2])
    pages = os.sysconf("SC_PHYS_PAGES")
    monkeypatch.setattr(os, "sysconf", lambda name: 1 if name == "SC_PHYS_PAGES" else 4096)
    with pytest.raises(SceneError, match="needs .* GB of the machine's"):
        export(take, tmp_path / "take.usd")
    assert os.listdir(tmp_path) == [] and pages > 1
