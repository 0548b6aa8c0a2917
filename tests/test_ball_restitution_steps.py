"""Two balls colliding head-on leave as the one-dimensional restitution law has them under
backward Euler at every step size, small and frame-sized.

Oracle: momentum conserved and the relative velocity reversed times e,
    v1' = (m1 v1 + m2 v2 + m2 e (v2 - v1)) / (m1 + m2),
    v2' = (m1 v1 + m2 v2 + m1 e (v1 - v2)) / (m1 + m2).
Backward Euler's solve holds ball pairs at rest on each other as penalty springs
(collision/contact_sets/solve.resting_pair). At 1e-3 s it took a pair leaving a bounce, still
overlapping, for one at rest and pushed the overlap out as speed: the balls left 0.1 to 0.15 m/s
faster than the law, while at 1/30 s and under the explicit methods they were exact.
"""
import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball, Balls
from springsim.scene import Scene

RESTITUTION = 0.5
HALF_GAP = 0.60055   # m, each centre from the middle


def head_on(masses, dt):
    """Balls of radius 0.2 m closing at 3 m/s along x from 0.8011 m apart (surface to surface),
    under gravity (along y: both fall alike), no drag. The step that brings them together
    leaves them 2.9 mm into each other at 1e-3 s, more than the 1.5 mm they part by in the
    next step, and 9.9 cm at 1/30 s."""
    balls = Balls(balls=[Ball(position=(-HALF_GAP, 1.0, 0.0), velocity=(2.0, 0.0, 0.0),
                              radius=0.2, mass=masses[0]),
                         Ball(position=(HALF_GAP, 1.0, 0.0), velocity=(-1.0, 0.0, 0.0),
                              radius=0.2, mass=masses[1])],
                  ball_restitution=RESTITUTION, drag=0.0)
    return springsim.Simulation(Scene(bodies=[balls], terrains=[], dt=dt),
                                integrator="implicit_euler")


def restitution_law(m1, m2, v1, v2, e):
    momentum = m1 * v1 + m2 * v2
    return ((momentum + m2 * e * (v2 - v1)) / (m1 + m2),
            (momentum + m1 * e * (v1 - v2)) / (m1 + m2))


@pytest.mark.parametrize("masses", [(1.0, 1.0), (2.0, 5.0)], ids=["equal", "unequal"])
@pytest.mark.parametrize("dt", [1e-3, 1 / 30], ids=["1e-3 s", "1/30 s"])
def test_balls_colliding_head_on_leave_by_the_restitution_law(masses, dt):
    simulation = head_on(masses, dt)
    simulation.advance(1.0)   # they meet at about 0.27 s and are well apart by 1 s
    v = simulation.velocities
    assert v[1, 0] - v[0, 0] > 0.5   # parting
    expected = restitution_law(*masses, 2.0, -1.0, RESTITUTION)
    np.testing.assert_allclose(v[:, 0], expected, rtol=0, atol=1e-9)
    np.testing.assert_allclose(v[0, 1:], v[1, 1:], rtol=0, atol=1e-12)   # nothing across x
    np.testing.assert_allclose(np.asarray(masses) @ v[:, 0], np.asarray(masses) @ [2.0, -1.0],
                               rtol=0, atol=1e-9)
