"""What the checks before every compiled call cost: ``Simulation.step(count)`` checks its count,
dt and the state's arrays (``State.check``) once per call, not per step.

    .venv/bin/python benchmarks/step_checks.py

Prints the time of the checks alone and of ``step(1)`` (one step per call: the worst case for the
checks' share) on a small and on the default cube; each figure is the best of 20 timings.
"""
import time

import numpy as np

from springsim import Simulation, load_scene

REPEATS, CALLS = 20, 2000


def best_microseconds(call) -> float:
    best = np.inf
    for _ in range(REPEATS):
        started = time.perf_counter()
        for _ in range(CALLS):
            call()
        best = min(best, (time.perf_counter() - started) / CALLS)
    return best * 1e6


def main() -> None:
    for label, overrides in (("3^3 cube", ["bodies.0.particles_per_edge=3"]),
                             ("10^3 cube", [])):
        simulation = Simulation(load_scene("jelly-plane", overrides), integrator="rk4", dt=1e-4)
        simulation.step(1)   # compile or load the kernels
        count = simulation.model.particle_count
        checks = best_microseconds(lambda: simulation.state.check(count))
        step = best_microseconds(lambda: simulation.step(1))
        print(f"{label} ({count} particles): checks {checks:.2f} us, step(1) {step:.1f} us "
              f"({100 * checks / step:.1f}% of one single-step call)")


if __name__ == "__main__":
    main()
