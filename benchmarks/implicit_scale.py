"""Backward Euler at scale: ms per step and conjugate-gradient iterations per step.

    .venv/bin/python benchmarks/implicit_scale.py [--steps N] [--rows cloth100,cube30,...]

Rows: the 100 x 100 cloth hanging from one edge (cloth-hang, N = 100) and the 30^3 jelly cube on
the plane, at dt = 1/60 s (issue 14's bars: <= 16.7 ms and <= 100 ms per step), plus the small
scenes. One warm-up step (compiling or loading the cache), then ``--steps`` steps in one call.
"""
import argparse
import time

from springsim.scenefile import load_scene
from springsim.simulation import Simulation

ROWS = {
    "cloth25": ("cloth-hang", []),
    "cloth100": ("cloth-hang", ["bodies.0.particles_per_edge=100"]),
    "cube10": ("jelly-plane", []),
    "cube30": ("jelly-plane", ["bodies.0.particles_per_edge=30"]),
    "cloth200": ("cloth-hang", ["bodies.0.particles_per_edge=200"]),
}


def measure(name, steps, dt=1 / 60, threads=None, skip=0):
    scene_name, overrides = ROWS[name]
    scene = load_scene(scene_name, overrides)
    options = {} if threads is None else {"threads": threads}
    simulation = Simulation(scene, integrator="implicit_euler", dt=dt, **options)
    simulation.step(1 + skip)
    statistics = simulation.integrator.statistics
    before = statistics.cg_iterations[0], statistics.linear_solves[0]
    started = time.perf_counter()
    simulation.step(steps)
    seconds = time.perf_counter() - started
    iterations = statistics.cg_iterations[0] - before[0]
    solves = statistics.linear_solves[0] - before[1]
    return {"row": name, "particles": simulation.model.particle_count,
            "ms_per_step": 1000 * seconds / steps, "cg_per_step": iterations / steps,
            "solves_per_step": solves / steps}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--skip", type=int, default=0, help="untimed steps first")
    parser.add_argument("--rows", default="cloth25,cloth100,cube10,cube30")
    args = parser.parse_args()
    for name in args.rows.split(","):
        r = measure(name, args.steps, skip=args.skip)
        print(f"{r['row']:9s} {r['particles']:7d} particles  {r['ms_per_step']:8.2f} ms/step  "
              f"{r['cg_per_step']:7.1f} CG iterations/step  {r['solves_per_step']:.2f} solves/step",
              flush=True)


if __name__ == "__main__":
    main()
