"""Contact at a fixed cost: vertex block descent (``vbd``) against backward Euler
(``implicit_euler``) on the scenes where cloth lies on things, alternated in one run (the
machine's speed drifts), at 1/60 s a step.

    .venv/bin/python benchmarks/vbd_contact.py [--cases cape,cloth-drape,cloth-100,flat-mesh]
        [--rounds 2] [--budget 60]

Cases (issue 57's):
- cape: the cape on the walking figure (a point cache deforming 10,000 triangles), self-collision
  on, timed from 1 s (when it lies on the figure) to 2 s;
- cloth-drape: the cloth falling over the sphere, timed from 1 s to 2 s;
- cloth-100: the 100 x 100 cloth hanging from one edge, self-collision on, timed 0.5 s to 1 s;
- flat-mesh: an irregular triangle mesh of about 3,000 vertices (a jittered disk, Delaunay),
  dropped flat from 0.3 m onto the floor, timed from 0.5 s (on the floor) to 1.5 s.

Each round builds the scene afresh for each integrator in turn, runs it (untimed) to the window's
start, then times the window step by step. A method's window stops early where it has spent
``--budget`` seconds (backward Euler on flat-mesh takes tens of seconds a step): the table says
how many steps were timed. Prints milliseconds a step (the range over rounds), the share of real
time (1/60 s over the time a step takes), and backward Euler's time over vbd's per round. The
first run compiles both integrators' kernels (minutes; cached after).
"""
import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from springsim import Simulation, load_scene
from springsim.bodies.cloth import Cloth
from springsim.scene import Scene
from springsim.terrains import Plane

sys.path.insert(0, str(Path(__file__).parent))
from cloth_mesh import disk_mesh, write_obj  # noqa: E402

H = 1.0 / 60.0
INTEGRATORS = ("vbd", "implicit_euler")


def flat_mesh_scene(folder: Path) -> Scene:
    vertices, triangles = disk_mesh(3000, radius=0.8)
    path = write_obj(folder / "disk.obj", vertices, triangles)
    cloth = Cloth(file=str(path), position=(0.0, -0.7, 0.0), pinned="none")
    return Scene(name="flat-mesh", bodies=[cloth], terrains=[Plane()])


CASES = {   # name -> (scene builder, window start, window end) in s
    "cape": (lambda folder: load_scene("cape"), 1.0, 2.0),
    "cloth-drape": (lambda folder: load_scene("cloth-drape"), 1.0, 2.0),
    "cloth-100": (lambda folder: load_scene("cloth-hang", ["bodies.0.particles_per_edge=100"]),
                  0.5, 1.0),
    "flat-mesh": (flat_mesh_scene, 0.5, 1.5),
}


def time_window(scene, integrator, start, end, budget):
    """(seconds a step, steps timed, particles) over [start, end] of a fresh run."""
    sim = Simulation(scene, integrator=integrator, dt=H)
    spent = time.perf_counter()
    while sim.time < start - 1e-9 and time.perf_counter() - spent < 4 * budget:
        sim.step(1)
    steps, seconds = 0, 0.0
    while sim.time < end - 1e-9 and seconds < budget:
        began = time.perf_counter()
        sim.step(1)
        seconds += time.perf_counter() - began
        steps += 1
    return seconds / max(steps, 1), steps, sim.model.particle_count


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--budget", type=float, default=60.0,
                        help="most seconds one method's window may take in a round")
    args = parser.parse_args()
    cases = args.cases.split(",")
    with tempfile.TemporaryDirectory() as folder:
        for name in cases:
            build, start, end = CASES[name]
            print(f"{name}: compiling and warming (first run: minutes)...", flush=True)
            for integrator in INTEGRATORS:   # compiled before the timed rounds
                Simulation(build(Path(folder)), integrator=integrator, dt=H).step(1)
            results = {integrator: [] for integrator in INTEGRATORS}
            for round_ in range(args.rounds):
                for integrator in INTEGRATORS:
                    per_step, steps, particles = time_window(build(Path(folder)), integrator,
                                                             start, end, args.budget)
                    results[integrator].append((per_step, steps))
                    print(f"  round {round_ + 1} {integrator}: {per_step * 1e3:.1f} ms a step "
                          f"({steps} steps timed)", flush=True)
            report(name, particles, results)


def report(name, particles, results):
    print(f"| {name} ({particles} particles) | ms a step | real time | steps timed |")
    for integrator, rows in results.items():
        times = [per_step * 1e3 for per_step, _ in rows]
        shares = [H / per_step for per_step, _ in rows]
        print(f"| {integrator} | {min(times):.1f} to {max(times):.1f} | "
              f"{min(shares):.2f}x to {max(shares):.2f}x | "
              f"{', '.join(str(steps) for _, steps in rows)} |")
    ratios = [slow[0] / fast[0] for slow, fast in zip(results["implicit_euler"], results["vbd"])]
    print(f"implicit_euler / vbd per round: {', '.join(f'{r:.1f}' for r in ratios)}", flush=True)


if __name__ == "__main__":
    main()
