"""What stepping one step a call costs against one call of many steps (issue 10: the body-body
pair list is kept between calls, Integrator.pair_list).

    .venv/bin/python benchmarks/step_per_call.py [SCENE] [--steps 2000] [--integrator NAME]
        [--dt SECONDS]

The scene (default cloth-balls, at its integrator and dt unless given, one thread) is first
advanced 1 s (the balls on the cloth), then ``--steps`` steps are taken one per
``Simulation.step(1)`` call, then as many in one call; each is timed with time.perf_counter.
Before the list was kept, every call began with a pair search (and implicit_euler's solve with
one of its own).
"""
import argparse
import time

from springsim.presets import preset
from springsim.simulation import Simulation


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="cloth-balls")
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--integrator")
    parser.add_argument("--dt", type=float)
    args = parser.parse_args()
    simulation = Simulation(preset(args.scene), integrator=args.integrator, dt=args.dt, threads=1)
    simulation.step(1)   # compile or load the cache
    simulation.advance(1.0)
    began = time.perf_counter()
    for _ in range(args.steps):
        simulation.step(1)
    one_a_call = (time.perf_counter() - began) / args.steps
    began = time.perf_counter()
    simulation.step(args.steps)
    one_call = (time.perf_counter() - began) / args.steps
    print(f"{args.scene}: one step a call {one_a_call * 1e6:.0f} us a step, "
          f"{args.steps} steps in one call {one_call * 1e6:.0f} us a step "
          f"(ratio {one_a_call / one_call:.2f})")


if __name__ == "__main__":
    main()
