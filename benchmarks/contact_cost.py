"""What body-body surface contact costs (issue 10): rk4 steps per second

(a) of the cloth-balls and jelly-plane presets with surface contact as it is and switched off
    (``self_collision = False`` on the cloth: with one surface body nothing else can touch; the
    jelly cube does not collide with itself, so jelly-plane should cost the same both ways):
    the two simulations step the first 3.4 s (34,000 steps of cloth-balls, the span
    ``springsim bench`` times, balls landing included) in alternating pieces of 1,000 steps, so
    that the machine's drift hits both alike; 3 repetitions, the range of the ratio off / on;
(b) a collapsing 25 x 25 cloth (default Cloth(), pinned="none", standing upright just above a
    plane, dt 1e-4) with self-collision: steps/s over the collapse (the issue's bar: >= 2,000);
(c) a jelly-stack-like scene: three default cubes aligned, stacked 0.2 m apart on the plane.

    .venv/bin/python benchmarks/contact_cost.py [--steps 2000] [--repeats 3]

Each case is built and stepped once first (compiling or loading the cached kernels), then timed
with time.perf_counter over ``--steps`` steps from the same start.
"""
import argparse
import copy
import time

import numpy as np

from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.presets import preset
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.terrains import Plane


def without_self_collision(scene: Scene) -> Scene:
    scene = copy.deepcopy(scene)
    for body in scene.bodies:
        if hasattr(body, "self_collision"):
            body.self_collision = False
    return scene


def interleaved(on_scene: Scene, off_scene: Scene, seconds: float, piece: int = 1000):
    """Steps/s of the two scenes' rk4 simulations over their first ``seconds``, stepped in
    alternating pieces of ``piece`` steps: (on, off)."""
    simulations = [Simulation(scene, integrator="rk4") for scene in (on_scene, off_scene)]
    for simulation in simulations:
        simulation.step(1)   # compile or load the cache
    spent = [0.0, 0.0]
    steps = round(seconds / on_scene.dt)
    for _ in range(steps // piece):
        for k, simulation in enumerate(simulations):
            began = time.perf_counter()
            simulation.step(piece)
            spent[k] += time.perf_counter() - began
    return steps // piece * piece / spent[0], steps // piece * piece / spent[1]


def steps_per_second(scene: Scene, steps: int, seconds_first: float = 0.0) -> float:
    """Steps/s of ``steps`` rk4 steps, after ``seconds_first`` s of untimed simulation."""
    simulation = Simulation(scene, integrator="rk4")
    simulation.step(1)   # compile or load the cache
    if seconds_first:
        simulation.advance(seconds_first)
    began = time.perf_counter()
    simulation.step(steps)
    return steps / (time.perf_counter() - began)


def standing_cloth() -> Scene:
    """The default 25 x 25, 4 m cloth, free, standing upright (89 degrees about x) with its lower
    edge 3 cm above the plane y = 0, thrown down at 3 m/s so that it buckles and folds."""
    cloth = Cloth(pinned="none", rotation_degrees=89.0, position=(0.0, 2.03, 0.0),
                  velocity=(0.0, -3.0, 0.0))
    return Scene(name="cloth-collapse", bodies=[cloth], terrains=[Plane(point=(0.0, 0.0, 0.0))],
                 dt=1e-4)


def jelly_stack() -> Scene:
    """Three default cubes (10^3, edge 4 m), aligned, each 0.2 m above the one below, the lowest
    on the plane y = -1."""
    # lattice offsets (-5 .. 4) x 4/9 m: the lowest layer is position - 2.22 m
    low = -1.0 + 5 * 4.0 / 9 + 0.01
    cubes = [Cube(position=(0.0, low + k * (4.0 + 0.2), 0.0)) for k in range(3)]
    return Scene(name="jelly-stack", bodies=cubes, terrains=[Plane()], dt=1e-3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    print(f"{'scene':28s} {'contact on':>12s} {'contact off':>12s} {'off/on':>14s}")
    for name in ("cloth-balls", "jelly-plane"):
        on_scene = preset(name)
        off_scene = without_self_collision(on_scene)
        seconds = 3.4 if name == "cloth-balls" else 3.0
        runs = np.array([interleaved(on_scene, off_scene, seconds) for _ in range(args.repeats)])
        on, off = runs[:, 0], runs[:, 1]
        ratios = off / on
        print(f"{name:28s} {max(on):10.0f}/s {max(off):10.0f}/s "
              f"{ratios.min():6.2f}-{ratios.max():.2f}")

    # (b) over the collapse: 1.5 s of falling and folding at dt 1e-4, timed in pieces
    simulation = Simulation(standing_cloth(), integrator="rk4")
    simulation.step(1)
    rates = []
    for _ in range(15):
        began = time.perf_counter()
        simulation.step(1000)
        rates.append(1000 / (time.perf_counter() - began))
    overall = len(rates) / sum(1 / r for r in rates)
    print(f"{'cloth-collapse 25x25 (1.5 s)':28s} {overall:10.0f}/s   "
          f"(per 0.1 s: {', '.join(f'{r:.0f}' for r in rates)}; bar >= 2000/s)")

    # (c) the stack, from the drop to the landing and after
    stack = [steps_per_second(jelly_stack(), args.steps, seconds_first=0.5)
             for _ in range(args.repeats)]
    print(f"{'jelly-stack (3 cubes)':28s} {max(stack):10.0f}/s   "
          f"(best of {args.repeats}, steps 0.5 s after the start)")


if __name__ == "__main__":
    main()
