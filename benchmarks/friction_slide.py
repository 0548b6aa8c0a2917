"""The default jelly cube resting on the plane, then given 3 m/s sideways: how far it slides
against Coulomb's v^2 / (2 mu g), and how much the first sliding step removes against the
Coulomb impulse mu g h per unit mass (issue 10, part 6).

    .venv/bin/python benchmarks/friction_slide.py [INTEGRATOR:DT ...]

Default: implicit_euler at 1/120, 1/60, 1/30 and 1/20 s, and rk4 at 1e-3 s as the explicit
reference. The distance is the centre of mass's travel until its velocity first reaches zero:
the cube's friction, mu times its weight while every bottom particle slides, is the only
horizontal force on the centre of mass, so that travel is v^2 / (2 mu g) for any stiffness.
After it the cube sways on its stuck bottom layer, which the final position would include.
Backward Euler's x' = x + h v' makes it v^2 / (2 mu g) - v h / 2 (first order in h).
"""
import sys

import numpy as np

from springsim import Simulation, load_scene

SPEED, FRICTION, GRAVITY = 3.0, 0.3, 9.8   # m/s, the plane's default friction, m/s^2


def resting_cube(integrator: str, dt: float) -> Simulation:
    """The default cube put with its lowest layer 1 mm above the plane and left 2 s to settle."""
    simulation = Simulation(load_scene("jelly-plane"), integrator=integrator, dt=dt)
    simulation.state.positions[:, 1] += -0.999 - simulation.positions[:, 1].min()
    simulation.advance(2.0)
    return simulation


def slide(simulation: Simulation, speed: float = SPEED) -> tuple[float, float]:
    """Give the cube ``speed`` along x; returns (the centre of mass's velocity change in the
    first step, its travel until its velocity first stops, interpolated within that step)."""
    start = simulation.positions[:, 0].mean()
    simulation.state.velocities[:, 0] += speed
    simulation.step(1)
    first_change = speed - simulation.velocities[:, 0].mean()
    limit = round(3.0 * speed / (FRICTION * GRAVITY) / simulation.dt)
    for _ in range(limit):
        before = simulation.positions[:, 0].mean(), simulation.velocities[:, 0].mean()
        simulation.step(1)
        after = simulation.positions[:, 0].mean(), simulation.velocities[:, 0].mean()
        if after[1] <= 0.0:
            share = before[1] / (before[1] - after[1])   # where in the step v crossed zero
            return first_change, before[0] + share * (after[0] - before[0]) - start
    raise RuntimeError("the cube did not stop")


def main(cases) -> None:
    coulomb = SPEED ** 2 / (2 * FRICTION * GRAVITY)
    print(f"Coulomb distance v^2/(2 mu g) = {coulomb:.4f} m")
    for case in cases:
        integrator, dt = case.split(":")
        dt = float(dt)
        first_change, distance = slide(resting_cube(integrator, dt))
        discrete = coulomb - SPEED * dt / 2 if integrator == "implicit_euler" else coulomb
        print(f"{integrator:15s} dt {dt:.5f}: travel {distance:.4f} m = {distance / coulomb:.4f} "
              f"of Coulomb's ({distance / discrete:.4f} of {discrete:.4f} with backward Euler's "
              f"-v h/2); first step removes {first_change / (FRICTION * GRAVITY * dt):.2f} x "
              f"the Coulomb impulse")


if __name__ == "__main__":
    main(sys.argv[1:] or ["implicit_euler:" + str(1 / 120), "implicit_euler:" + str(1 / 60),
                          "implicit_euler:" + str(1 / 30), "implicit_euler:0.05", "rk4:0.001"])
