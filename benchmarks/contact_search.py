"""Time backward Euler's start-of-step contact search (implicit/constraints.find_constraints) on
the default cube lowered to 5 cm above jelly-plane's floor, in whichever tree is on the path.

    .venv/bin/python benchmarks/contact_search.py
    PYTHONPATH=/other/checkout/src .venv/bin/python benchmarks/contact_search.py

Prints the tree it imported and microseconds a call, best of ``--repeats`` rounds of about
0.3 s. It takes the older signature too (before the moving world: no surface velocities and no
lookups), so that a tree from before terrains moved can be run against this one; run the trees
alternately, since a shared machine's speed drifts by 10% or more from minute to minute.
"""
import argparse
import inspect
import time

import numpy as np

import springsim
from springsim.implicit import constraints


def arguments(simulation):
    """find_constraints' arguments for the cube with its lowest layer 5 cm above the floor."""
    model = simulation.model.arrays
    x = simulation.state.positions.copy()
    x[:, 1] += model.terrain_offset.max() + 0.05 - x[:, 1].min() - 1.0   # floor at y = -1
    v = simulation.state.velocities.copy()
    count, terrains = x.shape[0], model.terrain_epsilon.shape[0]
    memory = simulation.state.contacts
    values = {"model": model, "x": x, "v": v, "h": float(simulation.dt),
              "kind": np.zeros_like(memory.kind), "normal": np.zeros((count, 3)),
              "surface": np.zeros((count, 3)), "terrain": np.full_like(memory.terrain, -1),
              "normal_floor": np.zeros(count), "friction_damping": np.zeros(count),
              "lookups": np.zeros((count, terrains, 4))}
    names = inspect.signature(constraints.find_constraints.py_func).parameters
    if "slots" in names:   # the arrays it writes, in one named tuple (since issue 54)
        values["slots"] = constraints.ContactSlots(
            values["kind"], values["terrain"], values["normal"], values["surface"],
            values["normal_floor"], values["friction_damping"], np.zeros(count, np.int8),
            np.zeros(count, np.int16))
    return tuple(values[name] for name in names)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    options = parser.parse_args()
    simulation = springsim.Simulation(springsim.load_scene("jelly-plane"),
                                      integrator="implicit_euler", dt=1 / 60, threads=1)
    call = arguments(simulation)
    constraints.find_constraints(*call)   # compiled (or loaded) here
    rounds = []
    for _ in range(options.repeats):
        began, calls = time.perf_counter(), 0
        while time.perf_counter() - began < 0.3:
            constraints.find_constraints(*call)
            calls += 1
        rounds.append((time.perf_counter() - began) / calls * 1e6)
    print(f"{springsim.__file__}: find_constraints, {call[1].shape[0]} particles: "
          f"{min(rounds):.1f} us a call (best of {options.repeats}; "
          f"{max(rounds):.1f} the slowest)")


if __name__ == "__main__":
    main()
