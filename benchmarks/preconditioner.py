"""implicit_euler's two preconditioners (implicit/coarse.py) on the same steps, alternately in one
process: conjugate-gradient iterations per linear solve and time per step.

    .venv/bin/python benchmarks/preconditioner.py [--steps 30] [--repeats 2] [SCENE ...]

Scenes: built-in names (run under implicit_euler at 1/60 s when they name another integrator)
or ``swing``, the Blender benchmark's cloth (benchmarks/blender_addon.py: a 50 x 50 grid, 1 m
square, pinned along one edge, swinging down from flat) at 1/24 s, or ``swing-100``, the same
cloth as a 100 x 100 grid. Each run steps once (compiled)
and then ``--steps`` steps, timed; the best of ``--repeats`` is kept. The motion agrees to the
solves' tolerance: the largest difference of the final positions is printed too.
"""
import argparse
import dataclasses
import time

import numpy as np

from springsim.bodies.cloth import Cloth
from springsim.bodies.cloth_material import ClothMaterial
from springsim.presets import preset
from springsim.scene import Scene
from springsim.simulation import Simulation

PRECONDITIONERS = ("two_level", "block_jacobi")


def swing(edge: int = 50) -> Scene:
    cloth = Cloth(particles_per_edge=edge, width=1.0, height=1.0, pinned="edge",
                  material=ClothMaterial())
    return Scene(name="swing", bodies=[cloth], integrator="implicit_euler", dt=1 / 24)


def scene_named(name: str) -> Scene:
    edges = {"swing": 50, "swing-100": 100}
    scene = swing(edges[name]) if name in edges else preset(name)
    if scene.integrator != "implicit_euler":
        scene = dataclasses.replace(scene, integrator="implicit_euler", dt=1 / 60)
    return scene


def timed(scene: Scene, preconditioner: str, steps: int):
    scene = dataclasses.replace(scene, implicit=dataclasses.replace(
        scene.implicit, preconditioner=preconditioner))
    simulation = Simulation(scene)
    simulation.step(1)
    statistics = simulation.integrator.statistics
    iterations, solves = int(statistics.cg_iterations[0]), int(statistics.linear_solves[0])
    start = time.perf_counter()
    simulation.step(steps)
    seconds = (time.perf_counter() - start) / steps
    per_solve = ((statistics.cg_iterations[0] - iterations)
                 / max(1, statistics.linear_solves[0] - solves))
    return seconds, per_solve, simulation.positions.copy()


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="*", default=["cape", "swing", "swing-100",
                                                      "cloth-hang", "jelly-plane",
                                                      "cloth-balls"])
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--repeats", type=int, default=2)
    arguments = parser.parse_args()
    for name in arguments.scenes:
        scene = scene_named(name)
        best = {p: (np.inf, 0.0, None) for p in PRECONDITIONERS}
        for _ in range(arguments.repeats):
            for preconditioner in PRECONDITIONERS:
                result = timed(scene, preconditioner, arguments.steps)
                if result[0] < best[preconditioner][0]:
                    best[preconditioner] = result
        (fast, fast_iterations, x), (slow, slow_iterations, y) = (best[p]
                                                                  for p in PRECONDITIONERS)
        print(f"{name} ({len(x)} particles, dt {scene.dt:.4g} s): two_level "
              f"{fast_iterations:.0f} iterations a solve, {fast * 1e3:.1f} ms a step; "
              f"block_jacobi {slow_iterations:.0f}, {slow * 1e3:.1f} ms; "
              f"{slow / fast:.2f}x faster; positions differ by at most "
              f"{np.abs(x - y).max():.1e} m", flush=True)


if __name__ == "__main__":
    main()
