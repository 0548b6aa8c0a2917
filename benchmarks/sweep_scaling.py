"""Sweep scaling: the same 8 runs on 1 worker and on 2 workers, timed in one process.

The issue's bar: 8 runs on 2 workers take at most 1/1.6 of the time on 1 worker. The timings are
of the whole `springsim.sweep` call (grid, kernel warm-up, starting the local Dask cluster,
running, collecting rows), the same for both, measured in alternation (1, 2, 1, 2, ...) so that a
machine shared with other work affects both alike; the ratio is taken between the medians.

    .venv/bin/python benchmarks/sweep_scaling.py                 # jelly-plane, 8 x 2 s runs
    .venv/bin/python benchmarks/sweep_scaling.py --repeats 3 --duration 1
"""
import argparse
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=2.0, help="simulated s per run")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    timed_sweep(1, 0.01)   # compile (or load) the kernels outside the timings
    times = {1: [], 2: []}
    for _ in range(args.repeats):
        for workers in (1, 2):
            times[workers].append(timed_sweep(workers, args.duration))
    one, two = statistics.median(times[1]), statistics.median(times[2])
    print(f"8 runs of jelly-plane, rk4, {args.duration:g} s each")
    for workers, values in times.items():
        print(f"  {workers} worker{'s' * (workers > 1)}: "
              + ", ".join(f"{value:.2f}" for value in values) + " s")
    verdict = "meets" if two / one <= BAR else "misses"
    print(f"  2 workers / 1 worker = {two / one:.3f} (median); the bar is <= {BAR:.3f}: "
          f"{verdict} it")


if __name__ == "__main__":
    main()
