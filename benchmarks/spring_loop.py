"""Time one evaluation of all spring forces of a scene, in runs (the default layout) and with
every spring loose (the plain loop over the spring list), as quoted in the README:

    .venv/bin/python benchmarks/spring_loop.py [SCENE] [--set key=value ...]

Each figure is the best of 20 timings of 200 evaluations in one compiled loop.
"""
import argparse
import time

import numpy as np
from numba import njit

from springsim import load_scene
from springsim.forces import force_columns, spring_forces
from springsim.model import build_model

EVALUATIONS, REPEATS = 200, 20


@njit
def evaluate(arrays, x, v, columns, out, count):
    for _ in range(count):
        spring_forces(arrays, x, v, columns, out)


def microseconds_per_evaluation(arrays, x, v) -> float:
    columns, out = force_columns(x), np.empty_like(x)
    evaluate(arrays, x, v, columns, out, 1)   # compile
    best = np.inf
    for _ in range(REPEATS):
        started = time.perf_counter()
        evaluate(arrays, x, v, columns, out, EVALUATIONS)
        best = min(best, (time.perf_counter() - started) / EVALUATIONS)
    return best * 1e6


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="jelly-plane")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    args = parser.parse_args()
    model = build_model(load_scene(args.scene, args.set))
    arrays = model.arrays
    springs = len(arrays.springs)
    rng = np.random.default_rng(0)
    x = model.initial_positions + 0.01 * rng.standard_normal(model.initial_positions.shape)
    v = rng.standard_normal(x.shape)
    all_loose = arrays._replace(spring_runs=np.empty((0, 5), np.int64),
                                run_rest_length=np.empty(0),
                                loose_springs=np.arange(springs, dtype=np.uint32))
    loose = len(arrays.loose_springs)
    holes = len(arrays.run_rest_length) - (springs - loose)
    print(f"{args.scene}: {model.particle_count:,} particles, {springs:,} springs "
          f"({len(arrays.spring_runs):,} runs with {holes:,} holes, {loose:,} loose)")
    for label, layout in (("in runs", arrays), ("all loose", all_loose)):
        us = microseconds_per_evaluation(layout, x, v)
        print(f"  {label:10s} {us:10.1f} us per evaluation, {1000 * us / springs:6.2f} ns per spring")


if __name__ == "__main__":
    main()
