"""Mesh bodies: a box mesh is exactly the default cube, the embedded surface is the input mesh at
t = 0, built-in and written-out mesh scenes work, and bad meshes are refused with one line."""
import subprocess
import sys

import numpy as np
import pytest
import trimesh

import springsim
from springsim.bodies.cube import Cube
from springsim.bodies.mesh import MeshBody
from springsim.errors import SceneError
from springsim.model import build_model
from springsim.scene import Scene
from springsim.springs import SpringKind
from springsim.terrains import Plane

SPACING = 4 / 9   # the default cube's


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("meshes")
    trimesh.creation.box(extents=(4.0, 4.0, 4.0)).export(folder / "box.obj")
    trimesh.creation.torus(major_radius=1.0, minor_radius=0.4).export(folder / "torus.stl")
    return folder


def box_like_the_cube(meshes) -> MeshBody:
    """The 4 m box placed where the default cube's lattice lies: its box starts at the cube's
    first particle, position - 5 spacings (the course framework's off-centre lattice)."""
    low = np.asarray(Cube().position) - 5 * SPACING
    return MeshBody(file=str(meshes / "box.obj"), spacing=SPACING, position=tuple(low + 2.0))


def test_a_box_mesh_is_exactly_the_default_cube(meshes):
    cube = build_model(Scene(bodies=[Cube()], terrains=[Plane()]))
    box = build_model(Scene(bodies=[box_like_the_cube(meshes)], terrains=[Plane()]))
    assert box.particle_count == 1000
    assert [box.spring_count(kind) for kind in (SpringKind.STRUCTURAL, SpringKind.SHEAR,
                                                SpringKind.BEND)] == [2700, 7776, 2400]
    np.testing.assert_allclose(box.initial_positions, cube.initial_positions, rtol=0, atol=1e-14)
    assert np.array_equal(box.springs, cube.springs)
    assert np.array_equal(box.spring_kind, cube.spring_kind)
    assert np.array_equal(box.arrays.spring_runs, cube.arrays.spring_runs)   # the fast loop
    assert len(box.arrays.loose_springs) == len(cube.arrays.loose_springs)


@pytest.mark.parametrize("integrator", ["rk4", "implicit_euler"])
def test_a_box_mesh_moves_as_the_default_cube(meshes, integrator):
    """Dropped on the plane, through the landing: the same motion to round-off."""
    runs = []
    for body in (Cube(), box_like_the_cube(meshes)):
        simulation = springsim.Simulation(Scene(bodies=[body], terrains=[Plane()],
                                                integrator=integrator,
                                                dt=1e-3 if integrator == "rk4" else 1e-2))
        simulation.advance(1.3)
        runs.append(simulation.positions.copy())
    # The two lattices agree to 1e-14 m; implicit_euler's CG stops at a relative residual
    # (cg_tolerance 1e-5), so such a difference can change where it stops by an iteration.
    np.testing.assert_allclose(runs[1], runs[0], rtol=0,
                               atol=1e-9 if integrator == "rk4" else 1e-7)


def test_the_embedded_surface_is_the_input_mesh_at_the_start(meshes):
    body = MeshBody(file=str(meshes / "torus.stl"), spacing=0.15, rotation_degrees=30.0,
                    rotation_axis=(1.0, 0.0, 1.0), position=(0.3, 2.0, -0.5), scale=1.5)
    simulation = springsim.Simulation(Scene(bodies=[body], terrains=[Plane()]))
    surface = simulation.surfaces()[0]
    expected = body.mesh()
    np.testing.assert_allclose(surface.vertices, expected.vertices, rtol=0, atol=1e-12)
    assert np.array_equal(surface.triangles, expected.triangles)
    embedding = simulation.model.bodies[0].embedding
    np.testing.assert_allclose(embedding.weights.sum(axis=1), 1.0, atol=1e-12)


def test_a_second_body_gets_its_embedding_in_global_particle_numbers(meshes):
    torus = MeshBody(file=str(meshes / "torus.stl"), spacing=0.2, position=(0.0, 3.0, 0.0))
    simulation = springsim.Simulation(Scene(bodies=[Cube(particles_per_edge=3), torus],
                                            terrains=[Plane()]))
    second = simulation.model.bodies[1]
    assert second.embedding.particles.min() >= second.start
    assert second.embedding.particles.max() < second.stop
    np.testing.assert_allclose(simulation.surfaces()[1].vertices, torus.mesh().vertices,
                               atol=1e-12)


def test_jelly_torus_written_out_runs_from_another_folder(tmp_path, monkeypatch):
    text = subprocess.run([sys.executable, "-m", "springsim", "scenes", "jelly-torus"],
                          check=True, capture_output=True, text=True).stdout
    (tmp_path / "x.toml").write_text(text)
    monkeypatch.chdir(tmp_path)
    scene = springsim.load_scene("x.toml")
    simulation = springsim.Simulation(scene)
    simulation.advance(0.05)
    assert np.all(np.isfinite(simulation.positions))


def test_a_relative_mesh_path_is_relative_to_the_scene_file(meshes, tmp_path, monkeypatch):
    folder = tmp_path / "scene"
    folder.mkdir()
    (folder / "box.obj").write_bytes((meshes / "box.obj").read_bytes())
    (folder / "s.toml").write_text('[[bodies]]\ntype = "mesh"\nfile = "box.obj"\n'
                                   'spacing = 1.0\nposition = [0, 5, 0]\n')
    monkeypatch.chdir(tmp_path)
    scene = springsim.load_scene(str(folder / "s.toml"))
    assert springsim.Simulation(scene).model.particle_count == 125


# --- bad meshes -------------------------------------------------------------------------------

def refusal(body: MeshBody) -> SceneError:
    with pytest.raises(SceneError) as error:
        Scene(bodies=[body]).validate()
    assert "\n" not in str(error.value)
    return error.value


def test_bad_meshes_are_refused_with_one_line(meshes, tmp_path):
    error = refusal(MeshBody(file=str(tmp_path / "missing.obj")))
    assert error.key == "bodies.0.file" and "no such file" in error.allowed

    (tmp_path / "text.obj").write_text("this is not a mesh\n")
    (tmp_path / "bytes.stl").write_bytes(b"\x00\x01garbage" * 10)
    (tmp_path / "empty.obj").write_text("")
    (tmp_path / "nan.obj").write_text("v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\n"
                                      "f 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
    for name in ("text.obj", "bytes.stl", "empty.obj", "nan.obj"):
        error = refusal(MeshBody(file=str(tmp_path / name)))
        assert error.key == "bodies.0.file"
    assert "not finite" in refusal(MeshBody(file=str(tmp_path / "nan.obj"))).allowed

    # a single open sheet has no inside: it is a cloth
    sheet = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], [[0, 2, 1], [0, 3, 2]])
    sheet.export(tmp_path / "sheet.obj")
    error = refusal(MeshBody(file=str(tmp_path / "sheet.obj")))
    assert error.key == "bodies.0.file" and 'type = "cloth"' in error.allowed

    for particles in (0, 7, 10**8):
        error = refusal(MeshBody(file=str(meshes / "box.obj"), particles=particles))
        assert error.key == "bodies.0.particles" and "[8, 10,000,000]" in error.allowed
    for particles in (2.5, True):
        error = refusal(MeshBody(file=str(meshes / "box.obj"), particles=particles))
        assert error.key == "bodies.0.particles" and "whole number" in error.allowed
    for spacing in ("fine", -1.0, 0.0):
        error = refusal(MeshBody(file=str(meshes / "box.obj"), spacing=spacing))
        assert error.key == "bodies.0.spacing"


def test_a_lattice_too_large_for_memory_is_refused_before_it_is_built(meshes):
    error = refusal(MeshBody(file=str(meshes / "box.obj"), spacing=1e-4))
    assert error.key == "bodies.0.spacing" and "GiB" in error.allowed


def test_surfaces_give_balls_as_centres_and_radii():
    simulation = springsim.Simulation(springsim.load_scene("jelly-balls"))
    cube, balls = simulation.surfaces()
    assert cube.radii is None and len(cube.triangles) == 6 * 2 * 81
    assert balls.triangles.size == 0
    np.testing.assert_array_equal(balls.radii, [0.5, 0.5, 0.5])
    np.testing.assert_array_equal(balls.vertices, simulation.positions[-3:])


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".off", ".glb", ".gltf"])
def test_every_format_reads_as_the_same_mesh(tmp_path, suffix):
    """The same box in every format: the same solid once welded (STL repeats each corner per
    triangle), and the same particles."""
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    path = tmp_path / f"box{suffix}"
    box.export(path)
    body = MeshBody(file=str(path), spacing=0.25)
    body.validate("bodies.0")
    assert body.solid().vertices.shape == (8, 3)
    np.testing.assert_allclose(np.sort(body.solid().vertices, axis=0),
                               np.sort(box.vertices, axis=0))
    assert len(body.lattice().positions) == 5 * 9 * 13


def test_the_command_line_refuses_a_bad_mesh_in_one_line(tmp_path):
    (tmp_path / "bad.toml").write_text('[[bodies]]\ntype = "mesh"\nfile = "nowhere.obj"\n')
    result = subprocess.run([sys.executable, "-m", "springsim", "run", str(tmp_path / "bad.toml"),
                             "--out", str(tmp_path / "x.npz")], capture_output=True, text=True)
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1
    assert "bodies.0.file" in result.stderr and "no such file" in result.stderr


