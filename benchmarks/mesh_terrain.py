"""Mesh terrains and mesh bodies: the figures issue 11 names, measured in one run.

    .venv/bin/python benchmarks/mesh_terrain.py

1. Loading a 20,000-triangle terrain (rolling hills, 40 x 40 m) and building its distance grid
   (limit: 5 s).
2. A particle's contact with a mesh terrain against its contact with the analytic plane: the
   contact kernel (apply_contact_forces) over 100,000 particles lying in the contact band, on the
   hills and on the plane, and the same particles on the plane and on a flat mesh floor (the
   same physics: the difference is the distance query alone) (limit: 3x); and whole jelly-plane
   steps with the plane replaced by a flat mesh floor.
3. A box mesh body (the default cube as a mesh) against the cube: steps/s (limit: 20% slower).
Ratios are measured in the same process, alternately, best of ROUNDS.
"""
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

import springsim
from springsim.bodies.cube import Cube
from springsim.bodies.mesh import MeshBody
from springsim.contact import apply_contact_forces
from springsim.meshfiles import _read
from springsim.model import build_model
from springsim.scene import Scene
from springsim.terrains import MeshTerrain, Plane
from springsim.terrains.mesh import _cached_grid

ROUNDS = 5


def hills(path: Path, cells: int = 100, size: float = 40.0) -> None:
    """A height field of 2 cells^2 triangles: 20,000 for 100 x 100 cells."""
    u = np.linspace(-size / 2, size / 2, cells + 1)
    x, z = np.meshgrid(u, u, indexing="ij")
    y = 1.5 * np.sin(x / 3.0) * np.cos(z / 4.0) - 1.0
    vertices = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    index = np.arange((cells + 1) ** 2).reshape(cells + 1, cells + 1)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, d, c], 1), np.stack([a, c, b], 1)])   # facing +y
    trimesh.Trimesh(vertices, faces, process=False).export(path)


def best_time(function, repeats: int) -> float:
    function()
    best = np.inf
    for _ in range(ROUNDS):
        start = time.perf_counter()
        for _ in range(repeats):
            function()
        best = min(best, (time.perf_counter() - start) / repeats)
    return best


def particles_on(terrain, count: int, rng) -> np.ndarray:
    """Points in the contact band of ``terrain`` (a height field over x, z), at rest, in the
    order of a lattice body's particles (neighbours in space are neighbours in memory)."""
    xz = rng.uniform(-15.0, 15.0, (count, 2))
    xz = xz[np.lexsort((xz[:, 1], np.floor(xz[:, 0] / 0.5)))]
    x = np.stack([xz[:, 0], np.zeros(count), xz[:, 1]], axis=1)
    for _ in range(30):   # walk down the normal onto the surface (the terrain's own distance)
        phi = terrain.signed_distance(x)
        x[:, 1] -= phi - 0.005
    return x


def contact_cost(terrain, x) -> float:
    model = build_model(Scene(bodies=[Cube(particles_per_edge=2)], terrains=[terrain]))
    arrays = model.arrays._replace(inv_mass=np.ones(len(x)), radius=np.zeros(len(x)),
                                   terrain_offset=np.zeros(len(x)))
    v = np.zeros_like(x)
    a = np.tile(arrays.gravity, (len(x), 1))
    return best_time(lambda: apply_contact_forces(arrays, x, v, 1e-3, a.copy()), 10) / len(x)


def steps_per_second(scene) -> float:
    simulation = springsim.Simulation(scene)
    simulation.step(1500)   # compile, fall and land
    return 200 / best_time(lambda: simulation.step(200), 1)


def main() -> None:
    folder = Path(tempfile.mkdtemp())
    hills(folder / "hills.obj")
    _read.cache_clear()
    _cached_grid.cache_clear()
    start = time.perf_counter()
    terrain = MeshTerrain(file=str(folder / "hills.obj"))
    terrain.validate("terrains.0")
    grid = terrain.grid()
    build = time.perf_counter() - start
    print(f"load + distance grid of a {len(terrain.mesh().triangles):,}-triangle terrain: "
          f"{build:.2f} s (limit 5 s), grid {grid.values.shape}, cell {grid.cell:.3f} m")

    rng = np.random.default_rng(0)
    plane = Plane(point=(0.0, -1.0, 0.0))
    x_mesh = particles_on(terrain, 100_000, rng)
    x_plane = particles_on(plane, 100_000, rng)
    in_band = np.mean(np.abs(terrain.signed_distance(x_mesh)) < terrain.epsilon)
    mesh_cost, plane_cost = contact_cost(terrain, x_mesh), contact_cost(plane, x_plane)
    print(f"contact per particle: plane {plane_cost * 1e9:.1f} ns, hills mesh "
          f"{mesh_cost * 1e9:.1f} ns, ratio {mesh_cost / plane_cost:.2f} (limit 3; "
          f"{in_band:.0%} of the mesh's particles in its band; on the hills' slopes some stick "
          "and some slide, which the plane's all-sticking particles do not)")

    floor = folder / "floor.obj"
    trimesh.Trimesh([[-20, -1, -20], [20, -1, -20], [20, -1, 20], [-20, -1, 20]],
                    [[0, 2, 1], [0, 3, 2]], process=False).export(floor)
    floor_cost = contact_cost(MeshTerrain(file=str(floor)), x_plane)
    plane_cost = contact_cost(plane, x_plane)
    print(f"the same particles on the plane and on a flat mesh floor: plane "
          f"{plane_cost * 1e9:.1f} ns, mesh floor {floor_cost * 1e9:.1f} ns, ratio "
          f"{floor_cost / plane_cost:.2f} (limit 3)")
    low = np.asarray(Cube().position) - 5 * 4 / 9
    trimesh.creation.box(extents=(4.0, 4.0, 4.0)).export(folder / "box.obj")
    box = MeshBody(file=str(folder / "box.obj"), spacing=4 / 9, position=tuple(low + 2.0))
    for integrator in ("rk4", "explicit_euler"):
        cube_plane = steps_per_second(Scene(bodies=[Cube()], terrains=[Plane()],
                                            integrator=integrator))
        cube_floor = steps_per_second(Scene(bodies=[Cube()],
                                            terrains=[MeshTerrain(file=str(floor))],
                                            integrator=integrator))
        box_plane = steps_per_second(Scene(bodies=[box], terrains=[Plane()],
                                           integrator=integrator))
        print(f"{integrator}: cube on plane {cube_plane:.0f} steps/s, on a mesh floor "
              f"{cube_floor:.0f} ({cube_floor / cube_plane:.2f}x); box mesh body on plane "
              f"{box_plane:.0f} ({box_plane / cube_plane:.2f}x, limit 0.8)")


if __name__ == "__main__":
    main()
