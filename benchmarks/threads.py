"""Threads: the speed of a large model's step with 1 and with more threads, in one run, and
whether the results agree bit for bit.

    .venv/bin/python benchmarks/threads.py [--edge 100] [--integrator rk4] [--steps 3]

Builds the cube of ``--edge`` particles per edge on the plane once, then alternates timed calls
of ``--steps`` steps with each thread count from the same start (so the machine's drift hits
both alike), and reports the best of ``--repeats`` for each and their ratio.
"""
import argparse
import time

import numpy as np

from springsim.integrators import available_threads
from springsim.scenefile import load_scene
from springsim.simulation import Simulation


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--edge", type=int, default=100)
    parser.add_argument("--integrator", default="rk4")
    parser.add_argument("--steps", type=int, default=3)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", default=f"1,{available_threads()}")
    args = parser.parse_args()
    counts = [int(text) for text in args.threads.split(",")]
    scene = load_scene("jelly-plane", [f"bodies.0.particles_per_edge={args.edge}"])
    simulation = Simulation(scene, integrator=args.integrator, dt=0.001)
    start = simulation.state.copy()
    best = {count: np.inf for count in counts}
    results = {}
    for count in counts:   # warm-up: compile or load the cache
        simulation.threads = count
        simulation.step(1)
    for _ in range(args.repeats):
        for count in counts:
            simulation.state = start.copy()
            simulation.threads = count
            began = time.perf_counter()
            simulation.step(args.steps)
            best[count] = min(best[count], (time.perf_counter() - began) / args.steps)
            results[count] = simulation.state.positions.copy(), simulation.state.velocities.copy()
    print(f"{args.edge}^3 cube, {simulation.model.particle_count:,} particles, "
          f"{args.integrator}, dt 0.001 s, best of {args.repeats} x {args.steps} steps:")
    for count in counts:
        same = all(np.array_equal(a, b) for a, b in zip(results[count], results[counts[0]]))
        print(f"  {count} thread(s): {1000 * best[count]:8.1f} ms/step, "
              f"{best[counts[0]] / best[count]:.2f}x of {counts[0]} thread(s), "
              f"bit-identical: {same}")


if __name__ == "__main__":
    main()
