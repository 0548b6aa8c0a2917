"""Mesh bodies in body-body contact (issue 10): other bodies touch a mesh body through the
boundary faces of its lattice (``BuiltBody.collision_surface``).

Oracles: a box's boundary is the cube's surface (count, and every triangle on one face of the
box); the boundary is a closed surface (every edge in two triangles, met once each way; the
enclosed volume is the full cells' by the divergence theorem) for a box and for the shipped
torus; a small cube dropped on a mesh box stays on top. The full cells are counted here with
plain NumPy, not with the code under test.
"""
import dataclasses

import numpy as np
import pytest
import trimesh

import springsim.bodies.mesh as mesh_module
from springsim import presets
from springsim.bodies.cube import Cube
from springsim.bodies.mesh import MeshBody
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.terrains import Plane


@pytest.fixture(scope="module")
def box_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("meshes") / "box.obj"
    trimesh.creation.box(extents=(1.0, 1.0, 1.0)).export(path)
    return str(path)


def jelly_torus() -> MeshBody:
    """The preset's torus (src/springsim/meshes/torus.obj, spacing 0.2, tilted 75 degrees)."""
    body = presets.jelly_torus().bodies[0]
    assert isinstance(body, MeshBody) and body.spacing == 0.2
    return body


def edge_counts(triangles):
    """(undirected edges, how many triangles hold each), (directed edges, counts)."""
    directed = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    undirected = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    return undirected, np.unique(directed, axis=0, return_counts=True)


def full_cell_count(index):
    kept = index >= 0
    full = np.ones(tuple(n - 1 for n in index.shape), bool)
    for a in (0, 1):
        for b in (0, 1):
            for c in (0, 1):
                full &= kept[a:a + full.shape[0], b:b + full.shape[1], c:c + full.shape[2]]
    return int(full.sum())


def check_closed_surface(body: MeshBody, manifold: bool):
    built = body.build()
    triangles = built.collision_surface.astype(np.int64)
    x = built.positions
    index = body.lattice().index
    # non-degenerate: half a lattice square each
    corners = x[triangles]
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                          corners[:, 2] - corners[:, 0]), axis=1)
    np.testing.assert_allclose(areas, 0.5 * body.spacing ** 2, rtol=1e-9)
    # no triangle twice
    assert len(np.unique(np.sort(triangles, axis=1), axis=0)) == len(triangles)
    (edges, counts), (directed, directed_counts) = edge_counts(triangles)
    if manifold:
        assert np.all(counts == 2), np.bincount(counts)
    else:
        assert set(np.unique(counts)) <= {2, 4}, np.bincount(counts)
    # closed and consistently wound: each edge is met as often one way as the other
    reverse = {tuple(e): c for e, c in zip(directed, directed_counts)}
    assert all(reverse.get((b, a), 0) == c for (a, b), c in zip(directed, directed_counts))
    # the enclosed volume is the full cells' (divergence theorem; exact for a closed surface)
    volume = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum()
    np.testing.assert_allclose(abs(volume) / 6, full_cell_count(index) * body.spacing ** 3,
                               rtol=1e-9)
    return built, edges, counts


def test_a_box_lattice_boundary_is_the_cube_surface(box_file):
    body = MeshBody(file=box_file, spacing=0.25, position=(0.3, 2.0, -0.1))
    built, _, _ = check_closed_surface(body, manifold=True)
    n = 5   # points per edge
    triangles = built.collision_surface
    assert triangles.shape == (6 * (n - 1) ** 2 * 2, 3)
    x = built.positions
    low, high = x.min(axis=0), x.max(axis=0)
    np.testing.assert_allclose(high - low, 1.0, atol=1e-12)
    # every triangle lies in one of the box's six boundary planes
    corners = x[triangles]
    on_plane = [np.all(np.abs(corners[:, :, axis] - bound[axis]) < 1e-9, axis=1)
                for axis in range(3) for bound in (low, high)]
    assert np.all(np.sum(on_plane, axis=0) == 1)
    assert [int(p.sum()) for p in on_plane] == [2 * (n - 1) ** 2] * 6
    # every particle on the box's faces is on a triangle, no interior one is
    on_faces = np.any((np.abs(x - low) < 1e-9) | (np.abs(x - high) < 1e-9), axis=1)
    assert np.array_equal(np.unique(triangles), np.flatnonzero(on_faces))
    assert on_faces.sum() == n ** 3 - (n - 2) ** 3


def test_the_torus_boundary_is_closed_and_manifold():
    """The shipped torus at 0.2 m, upright: a closed manifold."""
    check_closed_surface(dataclasses.replace(jelly_torus(), rotation_degrees=0.0), manifold=True)


def test_the_jelly_torus_boundary_is_closed():
    """Tilted as in the preset, two full cells may meet along a lattice edge only at a few places
    (no full cell on the other two sides): that edge bounds four triangles, two from each
    cell. Everywhere else every edge is in exactly two. (Since the lattice keeps every cell the
    surface passes through, issue 29, the shipped torus has no such edge; the check stays for
    any that would.)"""
    body = jelly_torus()
    built, edges, counts = check_closed_surface(body, manifold=False)
    index = body.lattice().index
    sites = np.argwhere(index >= 0)[np.argsort(index[index >= 0])]   # particle -> site
    pinched = edges[counts == 4]
    assert len(pinched) <= 0.01 * len(edges)
    for a, b in pinched:
        step = sites[b] - sites[a]
        assert np.abs(step).sum() == 1   # a lattice edge, not a diagonal
        axis = int(np.flatnonzero(step)[0])
        base = np.minimum(sites[a], sites[b])
        full = []
        for du, dv in ((-1, -1), (0, -1), (0, 0), (-1, 0)):   # the four cells around it
            cell = base.copy()
            cell[(axis + 1) % 3] += du
            cell[(axis + 2) % 3] += dv
            corners = [cell + np.array(c) for c in np.ndindex(2, 2, 2)]
            full.append(all(np.all(c >= 0) and np.all(c < index.shape) and index[tuple(c)] >= 0
                            for c in corners))
        assert full in ([True, False, True, False], [False, True, False, True]), full


def drop_cube_on_mesh_box(box_file):
    """A 3^3 cube (0.5 m) dropped from 0.5 m onto a 1 m mesh box (spacing 0.25) on a plane."""
    box = MeshBody(file=box_file, spacing=0.25, position=(0.0, 0.5, 0.0))
    cube = Cube(particles_per_edge=3, edge_length=0.5, position=(0.1, 1.75, 0.0))
    simulation = Simulation(Scene(bodies=[box, cube], terrains=[Plane(point=(0.0, 0.0, 0.0))],
                                  integrator="rk4", dt=1e-3))
    bodies = simulation.model.bodies
    low, high = (slice(b.start, b.stop) for b in bodies)
    worst = np.inf
    for _ in range(150):   # 1.5 s
        simulation.step(10)
        x = simulation.positions
        worst = min(worst, x[high, 1].min() - x[low, 1].max())
    return simulation, box, cube, high, worst


def test_a_cube_dropped_on_a_mesh_body_stays_on_top(box_file):
    simulation, box, cube, high, worst = drop_cube_on_mesh_box(box_file)
    thickness = max(box.thickness, cube.thickness)
    assert worst >= -thickness, worst
    x = simulation.positions
    assert x[high, 1].min() > 1.0 - thickness            # resting on the box's top
    assert np.linalg.norm(simulation.velocities[high], axis=1).mean() < 0.05


def test_without_the_lattice_boundary_the_cube_falls_through(box_file, monkeypatch):
    """The control: the same drop with no collision triangles on the mesh body sinks in."""
    monkeypatch.setattr(mesh_module, "lattice_boundary",
                        lambda index: np.empty((0, 3), np.int32))
    *_, worst = drop_cube_on_mesh_box(box_file)
    assert worst < -0.3, worst
