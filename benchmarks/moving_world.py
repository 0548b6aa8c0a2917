"""Issue 30's speed bars for a world that moves, measured in one run.

    .venv/bin/python benchmarks/moving_world.py

1. A rigidly moving mesh terrain against the same terrain standing still (limit: 1.2x): the
   default jelly cube (1,000 particles) on a flat mesh floor of 20,000 triangles, the floor
   turning slowly about its centre (motion.angular_velocity) or standing still, rk4 steps of
   1 ms and implicit_euler steps of 1/60 s.
2. Wind on a cloth against the same cloth in still air (limit: 15% more per step): the reference
   cloth (25 x 25) hanging from its corners, rk4 at 1 ms and implicit_euler at 1/60 s, in a
   6 m/s wind with gusts.
Each pair is timed alternately in the same process, best of ROUNDS.
"""
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

import springsim
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.motion import Motion
from springsim.scene import Scene
from springsim.terrains import MeshTerrain
from springsim.wind import Gusts, Wind

ROUNDS = 5


def floor(path: Path, cells: int = 100, size: float = 40.0) -> None:
    """A flat floor at y = -1 of 2 cells^2 triangles (20,000 for 100 x 100), facing +y."""
    u = np.linspace(-size / 2, size / 2, cells + 1)
    x, z = np.meshgrid(u, u, indexing="ij")
    vertices = np.stack([x, np.full_like(x, -1.0), z], axis=-1).reshape(-1, 3)
    index = np.arange((cells + 1) ** 2).reshape(cells + 1, cells + 1)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = np.concatenate([np.stack([a, d, c], 1), np.stack([a, c, b], 1)])
    trimesh.Trimesh(vertices, faces, process=False).export(path)


def step_times(scenes: dict, integrator: str, dt: float, steps: int) -> dict:
    """Seconds per step of each scene, alternately, best of ROUNDS (after a run to settle)."""
    sims = {name: springsim.Simulation(scene, integrator=integrator, dt=dt)
            for name, scene in scenes.items()}
    for sim in sims.values():
        sim.step(steps)   # compiled, and resting or hanging
    best = {name: np.inf for name in sims}
    for _ in range(ROUNDS):
        for name, sim in sims.items():
            start = time.perf_counter()
            sim.step(steps)
            best[name] = min(best[name], (time.perf_counter() - start) / steps)
    return best


def moving_mesh() -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "floor.obj"
        floor(path)
        scenes = {}
        for name, motion in (("still", None),
                             ("turning", Motion(angular_velocity=(0.0, 0.05, 0.0)))):
            terrain = MeshTerrain(file=str(path), resolution=128, motion=motion)
            scenes[name] = Scene(bodies=[Cube(position=(0.0, 1.25, 0.0))], terrains=[terrain])
        for integrator, dt, steps in (("rk4", 1e-3, 400), ("implicit_euler", 1 / 60, 30)):
            times = step_times(scenes, integrator, dt, steps)
            print(f"moving mesh terrain, {integrator}: still {times['still'] * 1e3:.3f} ms, "
                  f"turning {times['turning'] * 1e3:.3f} ms per step: "
                  f"{times['turning'] / times['still']:.2f}x (limit 1.2x)")


def wind() -> None:
    scenes = {"still air": Scene(bodies=[Cloth()]),
              "wind": Scene(bodies=[Cloth()], wind=Wind(velocity=(6.0, 0.0, 0.0), friction=0.02,
                                                        gusts=Gusts(0.3, 1.0, 1)))}
    for integrator, dt, steps in (("rk4", 1e-3, 400), ("implicit_euler", 1 / 60, 30)):
        times = step_times(scenes, integrator, dt, steps)
        print(f"wind on the reference cloth, {integrator}: still air "
              f"{times['still air'] * 1e3:.3f} ms, wind {times['wind'] * 1e3:.3f} ms per step: "
              f"+{(times['wind'] / times['still air'] - 1) * 100:.1f}% (limit 15%)")


if __name__ == "__main__":
    moving_mesh()
    wind()
