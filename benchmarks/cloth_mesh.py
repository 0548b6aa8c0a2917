"""Mesh cloth: what it costs to build, how fast it steps, and whether its material is the same
sheet at two resolutions (issue bars: build a 70,000-triangle cloth in under 5 s; step as fast as
the grid cloth of the same particle count, within 10%; a hanging cloth's sag at 50 x 50 and
100 x 100 particles within 5%).

    .venv/bin/python benchmarks/cloth_mesh.py [--part build,speed,sag,orders] [--repeats 3]

- build: a round tablecloth of about 35,000 vertices and 70,000 triangles (a Delaunay
  triangulation of a jittered disk, written as an OBJ with texture coordinates), built into a
  simulation (reading, welding, springs, model) in a fresh process each time.
- speed: steps per second of the 100 x 100 grid cloth, of the same grid read from a quad OBJ, and
  of an irregular triangle mesh with the same particle count, measured alternately (the machine's
  speed drifts), under rk4 (dt 1e-4) and implicit_euler (dt 1/60); ratios mesh / grid per round,
  and each cloth's spring layout (runs, holes in them, loose springs).
- orders: the spring force loop (forces.spring_forces) on the irregular disk with its vertices
  numbered in other orders (the file's rings; reverse Cuthill-McKee; scan lines of one grid
  spacing, and the same turning back every other line; random), against the grid cloth: what a
  renumbering at build could win (each order's runs, holes and loose springs, spring_runs.py).
- sag: a 1 m square cloth of a soft material hanging from its top edge, to rest under
  implicit_euler; the drop of its bottom edge below its pinned edge at 50 x 50 and 100 x 100.
"""
import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def write_obj(path: Path, vertices, faces, uv: bool = False) -> Path:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, float).tolist()]
    if uv:
        lines += [f"vt {x:.6f} {z:.6f}" for x, _, z in np.asarray(vertices, float).tolist()]
        lines += ["f " + " ".join(f"{v + 1}/{v + 1}" for v in face) for face in faces]
    else:
        lines += ["f " + " ".join(str(v + 1) for v in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def disk_mesh(vertex_count: int, radius: float = 1.0, seed: int = 1):
    """A jittered disk triangulated by Delaunay: (vertices (V, 3) in the x-z plane, triangles)."""
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(seed)
    rings = int(np.sqrt(vertex_count / np.pi))
    points = [np.zeros((1, 2))]
    for ring in range(1, rings + 1):
        count = max(6, int(round(2 * np.pi * ring)))
        angle = (np.arange(count) + rng.uniform(-0.3, 0.3, count)) * 2 * np.pi / count
        points.append(ring / rings * radius * np.stack([np.cos(angle), np.sin(angle)], 1))
    points = np.concatenate(points)
    triangles = Delaunay(points).simplices
    a, b, c = (points[triangles[:, k]] for k in range(3))
    upward = (b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0] < 0   # ccw from +y
    triangles[~upward] = triangles[~upward][:, ::-1]
    return np.stack([points[:, 0], np.zeros(len(points)), points[:, 1]], 1), triangles


def grid_quads(n: int) -> np.ndarray:
    index = np.arange(n * n).reshape(n, n)
    return np.stack([index[:-1, :-1].ravel(), index[1:, :-1].ravel(), index[1:, 1:].ravel(),
                     index[:-1, 1:].ravel()], axis=1)


BUILD_CHILD = """
import sys, time
t = time.perf_counter()
from springsim import Simulation
from springsim.bodies.cloth import Cloth
from springsim.scene import Scene
start = time.perf_counter()
scene = Scene(name="disk", bodies=[Cloth(file=sys.argv[1], pinned="none")], terrains=[],
              integrator="implicit_euler", dt=1 / 60)
scene.validate()
simulation = Simulation(scene)
print(time.perf_counter() - start, simulation.model.particle_count,
      len(simulation.model.springs))
"""


def part_build(folder: Path, repeats: int) -> dict:
    vertices, triangles = disk_mesh(35_000)
    path = write_obj(folder / "disk.obj", vertices, triangles, uv=True)
    times = []
    for _ in range(repeats):
        out = subprocess.run([sys.executable, "-c", BUILD_CHILD, str(path)], check=True,
                             capture_output=True, text=True).stdout.split()
        times.append(float(out[0]))
    return {"triangles": len(triangles), "vertices": len(vertices), "particles": int(out[1]),
            "springs": int(out[2]), "build_s": times}


def simulation_of(cloth, integrator: str, dt: float):
    from springsim import Simulation
    from springsim.scene import Scene

    return Simulation(Scene(name="c", bodies=[cloth], terrains=[], integrator=integrator,
                            dt=dt))


def steps_per_second(simulation, steps: int) -> float:
    start = time.perf_counter()
    simulation.step(steps)
    return steps / (time.perf_counter() - start)


def run_layout(arrays) -> list:
    """How the springs are laid out for the force loop (spring_runs.py): runs, holes, loose."""
    return [len(arrays.spring_runs), int((arrays.run_rest_length < 0).sum()),
            len(arrays.loose_springs)]


def part_speed(folder: Path, repeats: int) -> dict:
    from springsim.bodies.cloth import Cloth

    n = 100
    grid = Cloth(particles_per_edge=n, width=4.0, height=4.0)
    quad_file = write_obj(folder / "grid.obj", grid.particle_positions(), grid_quads(n))
    disk_vertices, disk_triangles = disk_mesh(n * n, radius=2.0)
    disk_file = write_obj(folder / "disk.obj", disk_vertices, disk_triangles)
    cloths = {"grid": grid, "quad file": Cloth(file=str(quad_file)),
              "triangle file": Cloth(file=str(disk_file))}
    result = {}
    for integrator, dt, steps in (("rk4", 1e-4, 400), ("implicit_euler", 1 / 60, 20)):
        simulations = {name: simulation_of(cloth, integrator, dt)
                       for name, cloth in cloths.items()}
        for simulation in simulations.values():
            simulation.step(2)                       # compile and warm
        rates = {name: [] for name in cloths}
        for _ in range(repeats):
            for name, simulation in simulations.items():
                rates[name].append(steps_per_second(simulation, steps))
        result[integrator] = {
            "particles": {name: s.model.particle_count for name, s in simulations.items()},
            "springs": {name: len(s.model.springs) for name, s in simulations.items()},
            "runs_holes_loose": {name: run_layout(s.model.arrays)
                                 for name, s in simulations.items()},
            "steps_per_s": rates,
            "ratio_to_grid": {name: [r / g for r, g in zip(rates[name], rates["grid"])]
                              for name in cloths if name != "grid"}}
    return result


def hanging_sag(n: int) -> float:
    from springsim import Simulation
    from springsim.bodies.cloth import Cloth
    from springsim.bodies.cloth_material import ClothMaterial
    from springsim.scene import Scene

    material = ClothMaterial(density=0.3, stretch=20.0, shear=5.0, bend=1.0,
                             stretch_damping=0.5, shear_damping=0.1, bend_damping=0.02)
    cloth = Cloth(particles_per_edge=n, width=1.0, height=1.0, position=(0.0, 1.0, 0.0),
                  rotation_degrees=-90.0, rotation_axis=(1.0, 0.0, 0.0), pinned="edge+z",
                  material=material, drag=0.0, self_collision=False)
    scene = Scene(name="hang", bodies=[cloth], terrains=[], integrator="implicit_euler",
                  dt=1 / 120, drag=0.01)
    simulation = Simulation(scene)
    simulation.advance(6.0)
    y = simulation.positions[:, 1]
    top = simulation.model.initial_positions[:, 1].max()
    bottom_row = np.arange(n)                       # local z = -height/2: the free edge
    return float(top - y[bottom_row].mean())


def part_sag(folder: Path, repeats: int) -> dict:
    sags = {n: hanging_sag(n) for n in (50, 100)}
    return {"sag_m": sags, "relative_difference": abs(sags[50] - sags[100]) / sags[100],
            "stretch_m": {n: s - 1.0 for n, s in sags.items()}}


def disk_orders(vertices, triangles) -> dict:
    """Numberings of the disk's vertices (order[new] = old) that part_orders compares."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import reverse_cuthill_mckee

    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    count = len(vertices)
    adjacency = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])),
                           shape=(count, count)).tocsr()
    line = np.floor((vertices[:, 2] - vertices[:, 2].min()) / (4.0 / 100)).astype(int)
    return {"file (rings)": np.arange(count),
            "reverse Cuthill-McKee": reverse_cuthill_mckee(adjacency + adjacency.T,
                                                           symmetric_mode=True),
            "scan lines": np.lexsort((vertices[:, 0], line)),
            "scan lines, turning": np.lexsort((np.where(line % 2 == 0, vertices[:, 0],
                                                        -vertices[:, 0]), line)),
            "random": np.random.default_rng(0).permutation(count)}


def part_orders(folder: Path, repeats: int) -> dict:
    from numba import njit

    from springsim.bodies.cloth import Cloth
    from springsim.forces import force_columns, spring_forces

    @njit
    def spring_loop(arrays, x, v, columns, out):
        spring_forces(arrays, x, v, columns, out)

    n = 100
    vertices, triangles = disk_mesh(n * n, radius=2.0)
    cloths = {"grid": Cloth(particles_per_edge=n, width=4.0, height=4.0)}
    for name, order in disk_orders(vertices, triangles).items():
        new_number = np.empty(len(order), np.int64)
        new_number[order] = np.arange(len(order))
        path = write_obj(folder / f"disk-{len(cloths)}.obj", vertices[order],
                         new_number[triangles])
        cloths[name] = Cloth(file=str(path))
    work = {}
    for name, cloth in cloths.items():
        simulation = simulation_of(cloth, "rk4", 1e-4)
        arrays, x = simulation.model.arrays, simulation.positions.copy()
        v = np.random.default_rng(1).normal(0.0, 1e-2, x.shape)
        work[name] = (arrays, x, v, force_columns(x), np.empty_like(x))
        spring_loop(*work[name])
    micros = {name: [] for name in cloths}
    for _ in range(repeats):
        for name, arguments in work.items():
            start = time.perf_counter()
            for _ in range(200):
                spring_loop(*arguments)
            micros[name].append((time.perf_counter() - start) / 200 * 1e6)
    return {name: {"spring_loop_us": micros[name], "runs_holes_loose": run_layout(work[name][0])}
            for name in cloths}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--part", default="build,speed,sag")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    parts = {"build": part_build, "speed": part_speed, "sag": part_sag, "orders": part_orders}
    with tempfile.TemporaryDirectory() as folder:
        for name in args.part.split(","):
            result = parts[name](Path(folder), args.repeats)
            print(json.dumps({name: result}, default=float))
            if name == "build":
                print(f"build: {min(result['build_s']):.2f}-{max(result['build_s']):.2f} s for "
                      f"{result['triangles']:,} triangles")
            if name == "speed":
                for integrator, row in result.items():
                    for mesh, ratios in row["ratio_to_grid"].items():
                        print(f"speed {integrator} {mesh} / grid: {min(ratios):.3f}-"
                              f"{max(ratios):.3f} (median {statistics.median(ratios):.3f})")
            if name == "orders":
                for order, row in result.items():
                    runs, holes, loose = row["runs_holes_loose"]
                    print(f"orders {order}: {statistics.median(row['spring_loop_us']):.0f} us "
                          f"a force loop; {runs} runs, {holes} holes, {loose} loose springs")
            if name == "sag":
                print(f"sag: 50 x 50 {result['sag_m'][50]:.4f} m, 100 x 100 "
                      f"{result['sag_m'][100]:.4f} m, differ by "
                      f"{100 * result['relative_difference']:.2f}%")


if __name__ == "__main__":
    main()
