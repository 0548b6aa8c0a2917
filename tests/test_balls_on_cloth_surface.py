"""Small fast balls never pass through the cloth under implicit_euler (issue 10, part 6).

A ball of radius 0.15 to 0.2 m (about the reference cloth's particle spacing, 4/24 m) dropped
at 10 to 20 m/s onto the cloth, at dt = 1/60 to 1/20 s, aimed at a particle, at the middle of an
edge and at the centre of a cell. Oracle (geometric): the cloth is a surface, so the ball's centre
stays above it: above the surface's height at the centre's (x, z) (the surface triangle under
it) and above the lowest cloth particle within a radius plus a spacing of it, at the end of every
step; and the ball did land (the cloth slowed it). Before the solve touched the cloth's triangles
(collision/response/penalty.py) 68 of these 81 went through: between four particles the point
contacts' normals turn sideways and push the particles apart (benchmarks/ball_through_cloth.py).
"""
import itertools

import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball

SPACING = 4.0 / 24   # m, the reference cloth's particle spacing
SPOTS = {"particle": (0.0, 0.0), "edge": (SPACING / 2, 0.0), "cell": (SPACING / 2, SPACING / 2)}
GRID = list(itertools.product((0.15, 0.175, 0.2), (10.0, 15.0, 20.0), (1 / 60, 1 / 30, 1 / 20),
                              SPOTS))


def surface_height(x, triangles, point):
    """The highest height of the triangles whose (x, z) projection holds ``point``'s (NaN if
    none does), by barycentric coordinates in the (x, z) plane."""
    a, b, c = (x[triangles[:, k]][:, [0, 2]] for k in range(3))
    e0, e1, e2 = b - a, c - a, point[[0, 2]] - a
    det = e0[:, 0] * e1[:, 1] - e1[:, 0] * e0[:, 1]
    safe = np.where(np.abs(det) > 1e-14, det, np.inf)
    u = (e2[:, 0] * e1[:, 1] - e1[:, 0] * e2[:, 1]) / safe
    w = (e0[:, 0] * e2[:, 1] - e2[:, 0] * e0[:, 1]) / safe
    inside = (np.abs(det) > 1e-14) & (u >= 0) & (w >= 0) & (u + w <= 1)
    y = x[triangles, 1]
    height = y[:, 0] + u * (y[:, 1] - y[:, 0]) + w * (y[:, 2] - y[:, 0])
    return height[inside].max() if inside.any() else np.nan


@pytest.mark.parametrize("radius, speed, dt, spot", GRID,
                         ids=[f"r{r}-v{v:g}-dt{dt:.3f}-{s}" for r, v, dt, s in GRID])
def test_a_small_fast_ball_never_passes_through_the_cloth(radius, speed, dt, spot):
    scene = springsim.load_scene("cloth-balls")
    x0, z0 = SPOTS[spot]
    scene.bodies[1].balls = [Ball(position=(x0, 1.0, z0), velocity=(0.0, -speed, 0.0),
                                  radius=radius)]
    simulation = springsim.Simulation(scene, integrator="implicit_euler", dt=dt)
    triangles = simulation.surfaces()[0].triangles
    cloth = np.flatnonzero(simulation.model.arrays.radius == 0)
    landed = False
    for _ in range(round(0.6 / dt)):
        simulation.step(1)
        x, centre = simulation.positions[cloth], simulation.positions[-1]
        height = surface_height(x, triangles, centre)
        assert not centre[1] < height   # NaN (not over the cloth) fails it too
        near = np.hypot(x[:, 0] - centre[0], x[:, 2] - centre[2]) < radius + SPACING
        assert centre[1] > x[near, 1].min()
        landed |= simulation.velocities[-1, 1] > -0.5 * speed
    assert landed
