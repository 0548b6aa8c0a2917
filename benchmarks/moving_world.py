"""Issue 30's speed bars for a world that moves, measured in one run.

    .venv/bin/python benchmarks/moving_world.py

1. A rigidly moving mesh terrain against the same terrain standing still (limit: 1.2x): the
   default jelly cube (1,000 particles) on a flat mesh floor of 20,000 triangles, the floor
   turning slowly about its centre (motion.angular_velocity), sliding at 1 cm/s
   (motion.velocity) or standing still, rk4 steps of 1 ms and implicit_euler steps of 1/60 s,
   with implicit_euler's conjugate-gradient iterations per step.
2. Wind on a cloth against the same cloth in still air (limit: 15% more per step): the reference
   cloth (25 x 25) hanging from its corners, rk4 at 0.1 ms (its scenes' step) and
   implicit_euler at 1/60 s, in a 6 m/s wind with gusts; and the wind's force pass alone.
3. The `cape` preset against real time (limit: faster than real time): a 2,500-particle cloth
   lying over the shoulders of a walking figure, a mesh terrain of about 10,000 triangles that a
   point cache deforms, implicit_euler at 1/60 s; simulated seconds per wall-clock second over
   its first 3 s (after the kernels are compiled), its linear solves and conjugate-gradient
   iterations a step, and what the deforming figure's refits cost of it.
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


def step_times(scenes: dict, integrator: str, dt: float, steps: int) -> tuple[dict, dict]:
    """Seconds per step of each scene, alternately, best of ROUNDS (after a run to settle), and
    implicit_euler's conjugate-gradient iterations per step over all rounds (else None)."""
    sims = {name: springsim.Simulation(scene, integrator=integrator, dt=dt)
            for name, scene in scenes.items()}
    for sim in sims.values():
        sim.step(steps)   # compiled, and resting or hanging
    statistics = {name: getattr(sim.integrator, "statistics", None) for name, sim in sims.items()}
    before = {name: int(s.cg_iterations[0]) if s is not None else 0
              for name, s in statistics.items()}
    best = {name: np.inf for name in sims}
    for _ in range(ROUNDS):
        for name, sim in sims.items():
            start = time.perf_counter()
            sim.step(steps)
            best[name] = min(best[name], (time.perf_counter() - start) / steps)
    iterations = {name: (int(s.cg_iterations[0]) - before[name]) / (ROUNDS * steps)
                  if s is not None else None for name, s in statistics.items()}
    return best, iterations


def moving_mesh() -> None:
    """A floor that turns makes backward Euler's friction solve work harder (a rotating support
    drags every particle a different way); one that slides does not, so the sliding floor
    measures what the lookup in a moving frame costs."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "floor.obj"
        floor(path)
        scenes = {}
        for name, motion in (("still", None),
                             ("turning", Motion(angular_velocity=(0.0, 0.05, 0.0))),
                             ("sliding", Motion(velocity=(0.01, 0.0, 0.0)))):
            terrain = MeshTerrain(file=str(path), resolution=128, motion=motion)
            scenes[name] = Scene(bodies=[Cube(position=(0.0, 1.25, 0.0))], terrains=[terrain])
        for integrator, dt, steps in (("rk4", 1e-3, 400), ("implicit_euler", 1 / 60, 30)):
            times, iterations = step_times(scenes, integrator, dt, steps)
            line = (f"moving mesh terrain, {integrator}: still {times['still'] * 1e3:.3f} ms, "
                    f"turning {times['turning'] * 1e3:.3f} ms "
                    f"({times['turning'] / times['still']:.2f}x), sliding "
                    f"{times['sliding'] * 1e3:.3f} ms ({times['sliding'] / times['still']:.2f}x) "
                    f"per step (limit 1.2x)")
            if iterations["still"] is not None:
                line += (f"; CG iterations a step: still {iterations['still']:.1f}, turning "
                         f"{iterations['turning']:.1f}, sliding {iterations['sliding']:.1f}")
            print(line)


def wind() -> None:
    """Both cloths start every round from the same state (the windy one's after 0.3 s, blown
    out), so that they differ by the wind's force alone, not by their shapes' contacts."""
    gusty = Wind(velocity=(6.0, 0.0, 0.0), friction=0.02, gusts=Gusts(0.3, 1.0, 1))
    for integrator, dt, steps in (("rk4", 1e-4, 400), ("implicit_euler", 1 / 60, 30)):
        sims = {name: springsim.Simulation(Scene(bodies=[Cloth()], wind=air),
                                           integrator=integrator, dt=dt)
                for name, air in (("still air", None), ("wind", gusty))}
        sims["wind"].advance(0.3)
        start = sims["wind"].state.positions.copy(), sims["wind"].state.velocities.copy()
        best = {name: np.inf for name in sims}
        for _ in range(ROUNDS + 1):
            for name, sim in sims.items():
                sim.state.positions[:], sim.state.velocities[:] = start
                began = time.perf_counter()
                sim.step(steps)
                best[name] = min(best[name], (time.perf_counter() - began) / steps)
        print(f"wind on the reference cloth, {integrator}: still air "
              f"{best['still air'] * 1e3:.3f} ms, wind {best['wind'] * 1e3:.3f} ms per step "
              f"from the same blown-out state: +{(best['wind'] / best['still air'] - 1) * 100:.1f}%"
              f" (limit 15%)")
    print(f"the wind's force pass alone (wind.add_wind_forces) on that state: "
          f"{wind_pass_time(sims['wind']) * 1e6:.1f} us, best of {ROUNDS} rounds of 200")


def wind_pass_time(sim) -> float:
    """Seconds per call of the wind's force pass at the simulation's state, best of ROUNDS."""
    from numba import njit

    from springsim.wind import add_wind_forces

    @njit
    def passes(model, x, v, scale, out, count):
        for _ in range(count):
            add_wind_forces(model, x, v, scale, out)

    model = sim.model.arrays
    x, v = sim.state.positions.copy(), sim.state.velocities.copy()
    out = np.zeros_like(x)
    passes(model, x, v, model.inv_mass, out, 1)
    best = np.inf
    for _ in range(ROUNDS):
        start = time.perf_counter()
        passes(model, x, v, model.inv_mass, out, 200)
        best = min(best, (time.perf_counter() - start) / 200)
    return best


def cape() -> None:
    from springsim.terrains.deforming_mesh import deform

    scene = springsim.load_scene("cape")
    figure = scene.terrains[1].deforming_surface()
    sim = springsim.Simulation(scene)
    sim.step(1)   # compiled
    best = np.inf
    for _ in range(2):
        sim = springsim.Simulation(scene)
        start = time.perf_counter()
        sim.advance(3.0)
        best = min(best, time.perf_counter() - start)
    iterations, solves, _ = (int(total[0]) / 180 for total in sim.integrator.statistics)
    model = sim.model.arrays
    block = int(model.terrain_deforming[1])
    start = time.perf_counter()
    for k in range(180):
        deform(model.terrain_data, block, 10.0 + k / 60)
    refit = (time.perf_counter() - start) / 180
    print(f"cape ({len(sim.positions)} particles, figure of {len(figure.triangles)} triangles), "
          f"implicit_euler at 1/60 s: 3 s simulated in {best:.2f} s, {3.0 / best:.2f}x real "
          f"time (limit > 1x), {solves:.2f} linear solves and {iterations:.0f} conjugate-gradient "
          f"iterations a step; a refit of the figure {refit * 1e3:.2f} ms, "
          f"{2 * refit * 180 / best * 100:.0f}% of the run at two refits a step at most")


if __name__ == "__main__":
    moving_mesh()
    wind()
    cape()
