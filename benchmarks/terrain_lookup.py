"""One terrain contact pass on its own: microseconds per call of
collision.response.terrain.apply_contact_forces for the default jelly-plane cube (1,000
particles above a still plane), this tree or another's.

    .venv/bin/python benchmarks/terrain_lookup.py [--calls 1000] [--repeats 5]
    PYTHONPATH=/path/to/other/checkout/src .venv/bin/python benchmarks/terrain_lookup.py

It isolates the per-particle lookup that every force evaluation does (the cube is in the air,
so nothing else of contact runs). Prints the compile time and each repeat's us per call.
"""
import argparse
import time

import numpy as np
from numba import njit

from springsim import Simulation, load_scene
from springsim.collision.response.terrain import apply_contact_forces


@njit(error_model="numpy")
def contact_passes(model, x, v, h, a, calls):
    for _ in range(calls):
        apply_contact_forces(model, x, v, h, a)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    simulation = Simulation(load_scene("jelly-plane"), integrator="rk4")
    model = simulation.model.arrays
    x, v = simulation.state.positions.copy(), simulation.state.velocities.copy()
    a = np.zeros_like(x)
    started = time.perf_counter()
    contact_passes(model, x, v, 1e-3, a, 1)
    print(f"compile: {time.perf_counter() - started:.1f} s")
    for _ in range(args.repeats):
        started = time.perf_counter()
        contact_passes(model, x, v, 1e-3, a, args.calls)
        print(f"{(time.perf_counter() - started) / args.calls * 1e6:.1f} us per call")


if __name__ == "__main__":
    main()
