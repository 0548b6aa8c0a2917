"""Sweep scaling: the same 8 runs on 1 worker and on 2 workers, timed in one process.

The issue's bar: 8 runs on 2 workers take at most 1/1.6 of the time on 1 worker. The timings are
of the whole `springsim.sweep` call (grid, kernel warm-up, starting the local Dask cluster,
running, collecting rows), the same for both, measured in alternation (1, 2, 1, 2, ...) so that a
machine shared with other work affects both alike; the ratio is taken between the medians. The
fixed cost (starting the cluster, each worker loading the compiled kernels) is timed too, with
8 runs of 0.01 s: it is why each run should take seconds, not milliseconds.

    .venv/bin/python benchmarks/sweep_scaling.py                 # jelly-plane, 8 x 8 s runs
    .venv/bin/python benchmarks/sweep_scaling.py --repeats 3 --duration 4
"""
import argparse
import multiprocessing
import statistics
import time

import springsim

BAR = 1 / 1.6


def timed_sweep(workers: int, duration: float) -> float:
    vary = {"bodies.0.structural.ks": [1000 + 250 * k for k in range(8)]}
    started = time.perf_counter()
    table = springsim.sweep("jelly-plane", vary, duration=duration, workers=workers)
    elapsed = time.perf_counter() - started
    assert all(row["status"] == "ok" for row in table), table
    return elapsed


def spin(_=None) -> float:
    """Seconds for a fixed pure-Python loop."""
    started = time.perf_counter()
    total = 0
    for i in range(10_000_000):
        total += i
    return time.perf_counter() - started


def parallel_capacity() -> float:
    """How long one loop takes when two run at once, relative to one alone: 1.0 on two free
    cores, 2.0 when the machine has only one core to give (then no sweep can scale)."""
    alone = spin()
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        pool.map(spin, range(2))                  # start both processes
        together = max(pool.map(spin, range(2)))
    return together / alone


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=8.0, help="simulated s per run")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    timed_sweep(1, 0.01)   # compile (or load) the kernels outside the timings
    capacity = [parallel_capacity()]
    fixed = {workers: timed_sweep(workers, 0.01) for workers in (1, 2)}
    times = {1: [], 2: []}
    for _ in range(args.repeats):
        for workers in (1, 2):
            times[workers].append(timed_sweep(workers, args.duration))
    one, two = statistics.median(times[1]), statistics.median(times[2])
    print(f"8 runs of jelly-plane, rk4, {args.duration:g} s each")
    for workers, values in times.items():
        print(f"  {workers} worker{'s' * (workers > 1)}: "
              + ", ".join(f"{value:.2f}" for value in values) + " s "
              f"(fixed cost, from 8 runs of 0.01 s: {fixed[workers]:.2f} s)")
    capacity.append(parallel_capacity())
    print("  control, before and after: a CPU-bound loop run twice at once takes "
          + " and ".join(f"{value:.2f}" for value in capacity)
          + " times as long as alone (1.0: two free cores; 2.0: one)")
    verdict = "meets" if two / one <= BAR else "misses"
    print(f"  2 workers / 1 worker = {two / one:.3f} (median); the bar is <= {BAR:.3f}: "
          f"{verdict} it")


if __name__ == "__main__":
    main()
