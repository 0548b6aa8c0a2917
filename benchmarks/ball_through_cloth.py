"""Small fast balls dropped onto the reference cloth under implicit_euler: how many go through
(issue 10, part 6, second bug).

    .venv/bin/python benchmarks/ball_through_cloth.py [INTEGRATOR]

The grid: radius 0.15, 0.175, 0.2 m (about the cloth's particle spacing, 4/24 m), speed 10, 15,
20 m/s downward from 1 m above the cloth, dt 1/60, 1/30, 1/20 s, aimed at a particle, at the
middle of an edge and at the centre of a cell; 0.6 s each. A ball goes through when its centre
ever ends a step below the cloth's surface at its (x, z) (the height of the surface triangle
under it) or below the lowest cloth particle within its radius plus a spacing horizontally.

Measured 2026-11-23: 0 of the 81 go through. Before the fix, 68 of the 81 went through; only
balls aimed at a particle at the smaller steps stayed on the cloth. Why: the solve's contacts
paired a ball with particles only. A ball over a cell touches its four corners at 0.118 m horizontally, so once its centre
sinks to their level the contact normals are horizontal: they push the corners apart instead
of holding the ball up, and it slips through the cell. (The first Newton iteration also takes
the normal at the free-flight prediction x + h v, which already has the centre at the cloth's
level, so the normals are horizontal from the first contact step; taking them at the start of
the step instead still let 63 of 81 through.) The fix: the solve's contacts touch the cloth's
triangles (the closest point on the triangle, its barycentric weights sharing the reaction;
collision/response/penalty.py), whose normals hold the ball up wherever it lands.
"""
import itertools
import sys

import numpy as np

import springsim
from springsim.bodies.balls import Ball

SPACING = 4.0 / 24   # m, the reference cloth's particle spacing
SPOTS = {"particle": (0.0, 0.0), "edge": (SPACING / 2, 0.0), "cell": (SPACING / 2, SPACING / 2)}


def surface_height(x, triangles, point):
    """The highest height of the surface triangles whose (x, z) projection holds ``point``'s,
    NaN where none does."""
    a, b, c = (x[triangles[:, k]][:, [0, 2]] for k in range(3))
    p = point[[0, 2]]
    e0, e1, e2 = b - a, c - a, p - a
    det = e0[:, 0] * e1[:, 1] - e1[:, 0] * e0[:, 1]
    safe = np.where(np.abs(det) > 1e-14, det, np.inf)
    u = (e2[:, 0] * e1[:, 1] - e1[:, 0] * e2[:, 1]) / safe
    w = (e0[:, 0] * e2[:, 1] - e2[:, 0] * e0[:, 1]) / safe
    inside = (np.abs(det) > 1e-14) & (u >= 0) & (w >= 0) & (u + w <= 1)
    if not inside.any():
        return np.nan
    y = x[triangles[:, 0], 1]
    height = y + u * (x[triangles[:, 1], 1] - y) + w * (x[triangles[:, 2], 1] - y)
    return height[inside].max()


def lowest_clearance(integrator, radius, speed, dt, spot, duration=0.6):
    """The least height of the ball's centre above the surface under it, and above the lowest
    cloth particle near it (m), over every step."""
    scene = springsim.load_scene("cloth-balls")
    scene.bodies[1].balls = [Ball(position=(spot[0], 1.0, spot[1]), velocity=(0.0, -speed, 0.0),
                                  radius=radius)]
    simulation = springsim.Simulation(scene, integrator=integrator, dt=dt)
    triangles = simulation.surfaces()[0].triangles
    cloth = np.flatnonzero(simulation.model.arrays.radius == 0)
    above_surface = above_particles = np.inf
    for _ in range(round(duration / dt)):
        simulation.step(1)
        x = simulation.positions[cloth]
        centre = simulation.positions[-1]
        height = surface_height(x, triangles, centre)
        if not np.isnan(height):
            above_surface = min(above_surface, centre[1] - height)
        near = np.hypot(x[:, 0] - centre[0], x[:, 2] - centre[2]) < radius + SPACING
        if near.any():
            above_particles = min(above_particles, centre[1] - x[near, 1].min())
    return above_surface, above_particles


def main(integrator: str) -> None:
    through = total = 0
    for dt, radius, speed, spot in itertools.product((1 / 60, 1 / 30, 1 / 20), (0.15, 0.175, 0.2),
                                                     (10.0, 15.0, 20.0), SPOTS):
        surface, particles = lowest_clearance(integrator, radius, speed, dt, SPOTS[spot])
        passed = surface < 0.0 or particles < 0.0
        through += passed
        total += 1
        print(f"dt {dt:.4f} radius {radius} speed {speed:4.1f} at a {spot:8s}: centre above the "
              f"surface by {surface:+.3f} m, above the lowest particle near it by "
              f"{particles:+.3f} m{'  THROUGH' if passed else ''}", flush=True)
    print(f"{through} of {total} balls went through the cloth")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "implicit_euler")
