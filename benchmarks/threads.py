"""Threads: the speed of a large model's step with 1 and with more threads, in one run, and
whether the results agree bit for bit.

    .venv/bin/python benchmarks/threads.py [--edge 100] [--integrator rk4] [--steps 3]

Builds the cube of ``--edge`` particles per edge on the plane once, then alternates timed calls
of ``--steps`` steps with each thread count from the same start (so the machine's drift hits
both alike), and reports the best of ``--repeats`` for each and their ratio.

The control line times a memory-bound loop (a[i] = b[i] + s c[i] over arrays the size of the
model's positions, the STREAM triad) with the same thread counts: where more threads do not
speed it up, the machine's memory bandwidth is shared by its cores, and a step that streams its
arrays cannot scale with threads either.
"""
import argparse
import time

import numba
import numpy as np

from springsim.integrators import available_threads
from springsim.scenefile import load_scene
from springsim.simulation import Simulation


@numba.njit(parallel=True)
def triad(a, b, c, scale):
    for i in numba.prange(a.shape[0]):
        a[i] = b[i] + scale * c[i]


def bandwidth(size, counts, repeats=10):
    """Best seconds of one triad over ``size`` float64s, for each thread count."""
    a, b, c = np.zeros(size), np.ones(size), np.ones(size)
    best = {count: np.inf for count in counts}
    for _ in range(repeats):
        for count in counts:
            numba.set_num_threads(count)
            triad(a, b, c, 2.0)   # the first call compiles
            began = time.perf_counter()
            triad(a, b, c, 2.0)
            best[count] = min(best[count], time.perf_counter() - began)
    numba.set_num_threads(max(counts))
    return best


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
    size = 3 * simulation.model.particle_count
    control = bandwidth(size, counts)
    print(f"control, memory-bound triad over {size:,} float64s (3 arrays):")
    for count in counts:
        rate = 3 * 8 * size / control[count] / 1e9
        print(f"  {count} thread(s): {1000 * control[count]:8.2f} ms, {rate:5.1f} GB/s, "
              f"{control[counts[0]] / control[count]:.2f}x of {counts[0]} thread(s)")


if __name__ == "__main__":
    main()
