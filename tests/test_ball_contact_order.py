"""Balls are clients of the one contact pipeline (issue 10, parts 1 and 5): their contacts with
particles and with each other are resolved with the surfaces' in one set, by the same Jacobi
passes, so the outcome depends on no order.

Oracles (geometric): a scene that its mirror x <-> z maps onto itself stays symmetric to
round-off, and listing the balls and bodies in another order changes the trajectory by no more
than round-off. Resolving the contacts one after the other (the balls' pass before) fails both:
a ball's contacts with the cloth particles under it were taken in particle-number order, which
the mirror does not keep.
"""
import numpy as np
import pytest

from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.scene import Scene
from springsim.simulation import Simulation

# four balls around the middle of the cloth: mirror images of each other under x <-> z (the
# first two each their own); they sink into the cloth, roll together and touch each other
BALLS = [(0.3, 0.3), (-0.3, -0.3), (0.3, -0.3), (-0.3, 0.3)]
MIRROR_BALL = [0, 1, 3, 2]
STEPS = {"rk4": 2e-4, "symplectic_euler": 2e-4, "implicit_euler": 1 / 60}
# backward Euler's conjugate gradients stop at a relative residual (1e-5 by default), and the
# mirror images' residuals differ by round-off: the trajectories part by about the tolerance
# (4.5e-6 m at 1e-5, 4e-9 m at 1e-8, 3e-13 m at 1e-11). Solved to round-off, the contacts'
# own order independence is what is left to test.
OPTIONS = {"implicit_euler": {"cg_tolerance": 1e-11}}


def ball_scene(integrator, order=(0, 1, 2, 3), balls_first=False):
    """An 11 x 11 cloth pinned at its corners and four balls dropped onto it, the balls listed
    in ``order``."""
    cloth = Cloth(particles_per_edge=11, width=1.5, height=1.5, position=(0.0, 0.0, 0.0))
    balls = Balls(balls=[Ball(position=(BALLS[b][0], 0.35, BALLS[b][1]), radius=0.25, mass=4.0)
                         for b in order])
    bodies = [balls, cloth] if balls_first else [cloth, balls]
    return Scene(bodies=bodies, terrains=[], integrator=integrator, dt=STEPS[integrator])


def mirror_map(simulation):
    """Each particle's mirror image under x <-> z, for ball_scene's default order."""
    cloth, balls = simulation.model.bodies
    grid = np.arange(11 * 11).reshape(11, 11)       # (row: z, column: x)
    return np.concatenate([grid.T.ravel() + cloth.start, np.array(MIRROR_BALL) + balls.start])


def balls_touched(simulation, integrator):
    """Whether the balls came down onto the cloth and (with the explicit methods' steps; at
    1/60 s backward Euler's cloth holds them apart) against each other."""
    x, balls = simulation.positions, simulation.model.bodies[1]
    centres = x[balls.start:balls.stop]
    gaps = [np.linalg.norm(centres[a] - centres[b]) - 0.5 for a in range(4) for b in range(a)]
    return centres[:, 1].max() < 0.2 and (integrator == "implicit_euler" or min(gaps) < 0.01)


@pytest.mark.parametrize("integrator", list(STEPS))
def test_balls_dropped_symmetrically_on_a_cloth_stay_symmetric(integrator):
    simulation = Simulation(ball_scene(integrator), **OPTIONS.get(integrator, {}))
    image = mirror_map(simulation)
    x = simulation.positions
    assert np.abs(x[image][:, [2, 1, 0]] - x).max() < 1e-12   # the start is symmetric
    simulation.advance(0.8)
    x = simulation.positions
    assert balls_touched(simulation, integrator)
    assert np.abs(x[image][:, [2, 1, 0]] - x).max() < 1e-9


@pytest.mark.parametrize("integrator", list(STEPS))
def test_balls_listed_in_another_order_give_the_same_trajectory(integrator):
    order = (2, 0, 3, 1)
    one = Simulation(ball_scene(integrator), **OPTIONS.get(integrator, {}))
    other = Simulation(ball_scene(integrator, order=order, balls_first=True),
                       **OPTIONS.get(integrator, {}))
    cloth, balls = other.model.bodies[1], other.model.bodies[0]
    # particle p of ``one`` is particle image[p] of ``other``
    image = np.concatenate([np.arange(cloth.start, cloth.stop),
                            balls.start + np.argsort(order)])
    assert np.array_equal(one.positions, other.positions[image])
    worst = 0.0
    for _ in range(8):
        one.advance(0.1)
        other.advance(0.1)
        worst = max(worst, np.abs(one.positions - other.positions[image]).max())
    assert balls_touched(one, integrator)
    assert worst < 1e-9
