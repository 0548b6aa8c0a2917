"""Real meshes become bodies (issue 29): UV seams, holes, several shells, inside-out shells and
thin limbs, with the file's own vertices riding inside the lattice.

Oracles: a file split along its UV seams fills exactly as the same surface welded; an inside-out
box exactly as the box; every file vertex is a convex combination (weights in [0, 1]) of the eight
corners of one full lattice cell holding it, and at t = 0 is the file's vertex; the same model in
millimetres and in metres gets the same lattice, 1000 times apart; a thin-limbed animal dropped
tilted under implicit_euler keeps every vertex within one spacing of its cell's corners and above
the floor at every step. The models are tests/data/ (scripts/make_test_models.py).
"""
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import springsim
from springsim.bodies.mesh import MeshBody, MeshWarning
from springsim.meshfiles import weld
from springsim.scene import Scene
from springsim.terrains import Plane

DATA = Path(__file__).with_name("data")


def built(body: MeshBody):
    """(lattice, warning texts) of a validated and built body."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        body.validate("bodies.0")
        body.build()
    return body.lattice(), [str(w.message) for w in caught if w.category is MeshWarning]


def test_a_file_split_along_its_uv_seams_fills_as_its_welded_surface(tmp_path):
    seamed = MeshBody(file=str(DATA / "uv_sphere_unwelded.obj"), spacing=0.2)
    file = seamed.mesh()
    welded = weld(file.vertices)
    assert len(welded.vertices) < len(file.vertices)      # the seam and the poles repeat
    trimesh.Trimesh(welded.vertices, welded.of_file_vertex[file.triangles],
                    process=False).export(tmp_path / "welded.obj")
    lattice, warned = built(seamed)
    reference, _ = built(MeshBody(file=str(tmp_path / "welded.obj"), spacing=0.2))
    assert warned == []                                   # closed once welded: nothing unusual
    np.testing.assert_array_equal(lattice.positions, reference.positions)
    # one embedding row per vertex of the file, in its order; seam copies ride alike
    assert len(lattice.embedding.weights) == len(file.vertices)
    first = np.unique(welded.of_file_vertex, return_index=True)[1][welded.of_file_vertex]
    np.testing.assert_array_equal(lattice.embedding.particles, lattice.embedding.particles[first])


def test_an_inside_out_box_fills_as_the_box(tmp_path):
    box = trimesh.creation.box(extents=(1.0, 1.5, 2.0))
    box.export(tmp_path / "box.obj")
    box.invert()
    box.export(tmp_path / "inverted.obj")
    lattice, warned = built(MeshBody(file=str(tmp_path / "inverted.obj"), spacing=0.25))
    reference, _ = built(MeshBody(file=str(tmp_path / "box.obj"), spacing=0.25))
    np.testing.assert_array_equal(lattice.positions, reference.positions)
    assert len(lattice.positions) == 5 * 7 * 9
    assert warned == [f"{tmp_path / 'inverted.obj'}: 1 shell wound inside out; filled where the "
                      "generalized winding number says inside"]


@pytest.mark.parametrize("name, unusual", [
    ("open_scan.obj", "open (36 edges on the rims of holes)"),
    ("animal.obj", "8 separate shells"),
    ("uv_sphere_unwelded.obj", None)])
def test_every_file_vertex_rides_inside_a_full_cell(name, unusual):
    body = MeshBody(file=str(DATA / name), particles=600)
    lattice, warned = built(body)
    assert warned == ([] if unusual is None else [f"{body.file}: {unusual}; filled where the "
                                                  "generalized winding number says inside"])
    vertices = body.mesh().vertices
    weights, corners = lattice.embedding.weights, lattice.positions[lattice.embedding.particles]
    assert weights.min() >= -1e-6 and weights.max() <= 1 + 1e-6
    # the eight corners are one cell of the lattice: a cube of side `spacing`, in corner order
    cell = np.array(list(np.ndindex(2, 2, 2)), float) * lattice.spacing
    np.testing.assert_allclose(corners - corners[:, :1], np.broadcast_to(cell, corners.shape),
                               atol=1e-12)
    low = corners[:, 0]
    assert np.all((vertices >= low - 1e-6 * lattice.spacing)
                  & (vertices <= low + (1 + 1e-6) * lattice.spacing))
    np.testing.assert_allclose(np.einsum("vk,vkc->vc", weights, corners), vertices, atol=1e-12)


@pytest.mark.parametrize("name", ["uv_sphere_unwelded.obj", "animal.obj"])
def test_the_surface_cells_hold_every_point_of_every_triangle(name):
    """The conservative voxelization (lattice_fill.surface_cells) keeps every cell whose inside
    a triangle passes through: points sampled on each triangle (its corners, edges and inside,
    barycentric steps of 1/16) fall only in kept cells, at a spacing of a tenth of the size.
    A point on a face between cells (within TOUCH of it) is in the inside of neither."""
    from springsim.bodies.lattice_fill import TOUCH, grid_for, surface_cells

    mesh = trimesh.load(DATA / name, force="mesh", process=False)
    welded = weld(np.asarray(mesh.vertices))
    vertices, triangles = welded[0], welded[1][np.asarray(mesh.faces)]
    grid = grid_for(vertices, 0.1 * float(np.ptp(vertices, axis=0).max()))
    kept = surface_cells(vertices, triangles, grid)
    steps = np.array([(i, j, 16 - i - j) for i in range(17) for j in range(17 - i)]) / 16
    points = np.einsum("sk,tkc->tsc", steps, vertices[triangles]).reshape(-1, 3)
    local = (points - grid.origin) / grid.spacing
    inside = np.all(np.abs(local - np.round(local)) > 2 * TOUCH, axis=1)
    assert inside.mean() > 0.9
    cell = np.floor(local[inside]).astype(np.int64)
    assert kept[tuple(cell.T)].all()
    assert kept.sum() < kept.size     # and it is a surface, not the whole box


def test_the_open_scan_fills_as_the_closed_pebble_apart_from_its_hole(tmp_path):
    """The scan is the pebble (tests/data's maker: an ellipsoid) without its underside: its
    lattice keeps nearly all of the closed pebble's particles."""
    pebble = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    pebble.apply_scale((1.3, 0.8, 1.0))
    pebble.export(tmp_path / "pebble.obj")
    scan, _ = built(MeshBody(file=str(DATA / "open_scan.obj"), spacing=0.2))
    closed, _ = built(MeshBody(file=str(tmp_path / "pebble.obj"), spacing=0.2))
    shared = {tuple(p) for p in np.round(scan.positions, 9)} & \
        {tuple(p) for p in np.round(closed.positions, 9)}
    assert len(shared) >= 0.85 * len(closed.positions)


def test_thin_legs_get_particles_of_their_own():
    """At 500 particles the animal's legs (8 cm thick) are thinner than its lattice: its body
    starts 0.65 m up, and every leg has particles down to its foot."""
    lattice, _ = built(MeshBody(file=str(DATA / "animal.obj"), particles=500))
    assert lattice.spacing > 0.08
    feet = lattice.positions[lattice.positions[:, 1] < 0.1]
    for x in (-0.45, 0.45):
        for z in (-0.17, 0.17):
            assert np.any(np.linalg.norm(feet[:, [0, 2]] - (x, z), axis=1) < lattice.spacing)


def test_auto_spacing_makes_the_same_body_in_millimetres_and_metres(tmp_path):
    capsule = trimesh.creation.capsule(height=1.5, radius=0.25, count=(12, 12))
    capsule.export(tmp_path / "metres.obj")
    capsule.apply_scale(1000.0)
    capsule.export(tmp_path / "millimetres.obj")
    metres, _ = built(MeshBody(file=str(tmp_path / "metres.obj"), particles=500))
    millimetres, _ = built(MeshBody(file=str(tmp_path / "millimetres.obj"), particles=500))
    assert abs(len(metres.positions) / 500 - 1) <= 0.1
    assert len(millimetres.positions) == len(metres.positions)
    np.testing.assert_allclose(millimetres.spacing, 1000 * metres.spacing, rtol=1e-12)
    in_mm, _ = built(MeshBody(file=str(tmp_path / "millimetres.obj"), particles=500,
                              scale=0.001))
    np.testing.assert_allclose(in_mm.positions, metres.positions, atol=1e-9)


def test_a_tumbling_thin_limbed_body_keeps_its_surface_in_its_lattice():
    """The animal dropped tilted 70 degrees from 0.5 m under implicit_euler at 1/60 s: it lands
    on legs and ears and tumbles; at every step every vertex is within one spacing of each of its
    cell's corners (sqrt(3) spacings at rest) and no vertex is more than 2 cm below the floor."""
    body = MeshBody(file=str(DATA / "animal.obj"), particles=500, rotation_degrees=70.0,
                    rotation_axis=(1.0, 0.0, 1.0), velocity=(0.5, 0.0, 0.0))
    body.position = (0.0, 0.5 - body.lattice().positions[:, 1].min(), 0.0)
    simulation = springsim.Simulation(Scene(bodies=[body], terrains=[Plane(point=(0, 0, 0))],
                                            integrator="implicit_euler", dt=1 / 60))
    spacing = body.lattice().spacing
    embedding = simulation.model.bodies[0].embedding
    lowest, farthest = np.inf, 0.0
    for _ in range(90):
        simulation.step(1)
        vertices = simulation.surfaces()[0].vertices
        corners = simulation.positions[embedding.particles]
        farthest = max(farthest, float(np.linalg.norm(corners - vertices[:, None], axis=2).max()))
        lowest = min(lowest, float(vertices[:, 1].min()))
    assert farthest <= np.sqrt(3) * spacing + spacing
    assert -0.02 <= lowest < spacing     # it landed, and nothing went through the floor


def test_the_run_says_the_spacing_chosen_and_warns_in_one_line(tmp_path):
    (tmp_path / "scan.toml").write_text(
        'duration = 0.02\ndt = 0.0004\n[[bodies]]\ntype = "mesh"\n'   # dt given: no step said
        f'file = "{DATA / "open_scan.obj"}"\nparticles = 300\nposition = [0, 2, 0]\n')
    result = subprocess.run([sys.executable, "-m", "springsim", "run", str(tmp_path / "scan.toml"),
                             "--out", str(tmp_path / "scan.npz")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    spacing = MeshBody(file=str(DATA / "open_scan.obj"), particles=300,
                       position=(0, 2, 0)).lattice().spacing
    assert f"  {'bodies.0 lattice':<22}spacing {spacing:.4g} m (auto, for about 300 particles)" \
        in result.stdout
    assert result.stderr.strip().splitlines() == [
        f"springsim run: warning: {DATA / 'open_scan.obj'}: open (36 edges on the rims of holes); "
        "filled where the generalized winding number says inside"]


def test_the_separate_parts_of_one_file_collide_as_two_bodies(tmp_path):
    """One OBJ holding two boxes, one 1.2 m above the other, dropped on the plane: the pieces
    are one body (one point cache) but two contact bodies, so after 1.5 s the upper box rests on
    the lower one instead of passing into it."""
    import trimesh

    from springsim import Simulation
    from springsim.bodies.mesh import MeshBody
    from springsim.model import build_model
    from springsim.scene import Scene
    from springsim.terrains import Plane

    lower = trimesh.creation.box(extents=(1.0, 0.5, 1.0))
    upper = trimesh.creation.box(extents=(0.8, 0.5, 0.8))
    upper.apply_translation((0.0, 1.7, 0.0))
    path = tmp_path / "two_boxes.obj"
    trimesh.util.concatenate([lower, upper]).export(path)
    body = MeshBody(file=str(path), spacing=0.25, position=(0.0, 0.3, 0.0))
    scene = Scene(name="two", bodies=[body], terrains=[Plane(point=(0, 0, 0))],
                  integrator="implicit_euler", dt=1 / 60)
    model = build_model(scene)
    pieces = np.unique(model.arrays.particle_body)
    assert len(pieces) == 2 and len(model.bodies) == 1
    upper_particles = model.arrays.particle_body == pieces[1]
    simulation = Simulation(scene)
    simulation.advance(1.5)
    x = simulation.positions
    lower_top = x[~upper_particles, 1].max()
    assert x[upper_particles, 1].min() > lower_top - 0.05     # resting on it, not inside
    assert x[upper_particles, 1].min() < lower_top + 0.1      # and landed on it
