"""Mesh terrains and mesh bodies: the figures issue 11 names, measured in one run.

    .venv/bin/python benchmarks/mesh_terrain.py

1. Loading a 20,000-triangle terrain (rolling hills, 40 x 40 m) and building its distance grid
   (limit: 5 s).
2. A particle's contact with a mesh terrain against its contact with the analytic plane: the
   contact kernel (apply_contact_forces) over 100,000 particles at rest in the contact band
   (limit: 3x), timed alternately, best of CONTACT_ROUNDS:
   - the same particles on the plane and on a flat mesh floor (the same physics: the difference
     is the distance query alone);
   - particles on the hills against the plane's resting ones (on the hills' slopes some stick and
     some slide, which costs more than the plane's all-sticking particles whatever the terrain),
     and against the plane's particles given the hills' slopes (each feels gravity at the angle
     its hills twin feels it to the normal: the same sticking and sliding, particle by particle);
   and whole jelly-plane steps with the plane replaced by a flat mesh floor.
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
from springsim.collision.response.terrain import apply_contact_forces
from springsim.meshfiles import _read
from springsim.model import build_model
from springsim.scene import Scene
from springsim.terrains import MeshTerrain, Plane
from springsim.terrains.mesh import _cached_grid

ROUNDS = 5
CONTACT_ROUNDS = 20


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


def contact_pass(terrain, x, a=None):
    """apply_contact_forces over particles x at rest (acceleration a, gravity by default)."""
    model = build_model(Scene(bodies=[Cube(particles_per_edge=2)], terrains=[terrain]))
    arrays = model.arrays._replace(inv_mass=np.ones(len(x)), radius=np.zeros(len(x)),
                                   terrain_offset=np.zeros(len(x)))
    v = np.zeros_like(x)
    a = np.tile(arrays.gravity, (len(x), 1)) if a is None else a
    return lambda: apply_contact_forces(arrays, x, v, 1e-3, a.copy())


def alternate_best(passes: dict, repeats: int = 5) -> dict:
    """Seconds per particle of each pass (name -> (function, particles)): the passes take turns,
    ``repeats`` calls each, CONTACT_ROUNDS times, and each call is timed alone (best of all): the
    machine's load falls on all of them alike."""
    best = dict.fromkeys(passes, np.inf)
    for function, _ in passes.values():
        function()   # compile
    for _ in range(CONTACT_ROUNDS):
        for name, (function, count) in passes.items():
            for _ in range(repeats):
                start = time.perf_counter()
                function()
                best[name] = min(best[name], (time.perf_counter() - start) / count)
    return best


def slopes_on_the_plane(terrain, x: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """Each particle's gravity as it meets the terrain's surface at x, turned so that the
    terrain's normal there becomes the plane's (0, 1, 0): on the plane it then presses and slides
    as on the terrain."""
    step = 1e-6
    normal = np.stack([(terrain.signed_distance(x + step * e) - terrain.signed_distance(x - step * e))
                       / (2 * step) for e in np.eye(3)], axis=1)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    up = np.array([0.0, 1.0, 0.0])
    axis = np.cross(normal, up)
    sine, cosine = np.linalg.norm(axis, axis=1, keepdims=True), normal @ up
    axis = np.divide(axis, sine, out=np.zeros_like(axis), where=sine > 0)
    g = np.broadcast_to(gravity, x.shape)
    return (g * cosine[:, None] + np.cross(axis, g) * sine
            + axis * (axis @ gravity)[:, None] * (1 - cosine[:, None]))


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
    x_hills = particles_on(terrain, 100_000, rng)
    x_plane = particles_on(plane, 100_000, rng)
    in_band = np.mean(np.abs(terrain.signed_distance(x_hills)) < terrain.epsilon)
    floor = folder / "floor.obj"
    trimesh.Trimesh([[-20, -1, -20], [20, -1, -20], [20, -1, 20], [-20, -1, 20]],
                    [[0, 2, 1], [0, 3, 2]], process=False).export(floor)
    gravity = np.asarray(Scene().gravity, float)
    sloped = slopes_on_the_plane(terrain, x_hills, gravity)
    count = len(x_plane)
    ns = {name: cost * 1e9 for name, cost in alternate_best({
        "plane": (contact_pass(plane, x_plane), count),
        "floor": (contact_pass(MeshTerrain(file=str(floor)), x_plane), count),
        "hills": (contact_pass(terrain, x_hills), count),
        "sloped plane": (contact_pass(plane, x_plane, sloped), count)}).items()}
    print(f"contact per particle ({count:,} particles at rest in the contact band, "
          f"{in_band:.0%} of the hills' particles in its band):")
    print(f"  plane {ns['plane']:.1f} ns, flat mesh floor {ns['floor']:.1f} ns (the same "
          f"particles): ratio {ns['floor'] / ns['plane']:.2f} (limit 3)")
    print(f"  hills mesh {ns['hills']:.1f} ns: ratio {ns['hills'] / ns['plane']:.2f} against the "
          f"plane's resting particles (limit 3), {ns['hills'] / ns['sloped plane']:.2f} against "
          f"the plane's particles given the hills' slopes ({ns['sloped plane']:.1f} ns: the same "
          "sticking and sliding)")
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
