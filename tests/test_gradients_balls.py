"""Gradients with balls (a ball is a particle whose terrain offset is its radius): a ball thrown
onto a plane and one into a bowl, against central finite differences of the forward run under
each integrator with an adjoint (restitution, friction, gravity, the ball's mass and velocity),
onto the plane against a gusty wind, and two balls pressed into each other (balls
against cubes and cloths: test_gradients_bodies.py)."""
import pytest

from springsim.bodies.balls import Ball, Balls
from springsim.scene import Scene
from springsim.terrains.bowl import Bowl
from springsim.terrains.plane import Plane
from test_gradients import STEPS, assert_gradients_match

KEYS = ["terrains.0.restitution", "terrains.0.friction", "gravity",
        "bodies.0.balls.0.velocity", "bodies.0.balls.0.mass", "drag"]


def on_plane():
    """A ball of radius 0.2 m half a centimetre above a plane, thrown down onto it and
    sideways."""
    ball = Ball(position=(0.0, 0.205, 0.0), velocity=(0.8, -2.0, 0.3), radius=0.2, mass=2.0)
    return Scene(bodies=[Balls(balls=[ball])], drag=0.1,
                 terrains=[Plane(point=(0.0, 0.0, 0.0), friction=0.3, restitution=0.5)])


def in_bowl():
    """The same ball 1.4 cm from the inside of a bowl of radius 1 m, thrown against it."""
    ball = Ball(position=(0.58, 0.47, 0.0), velocity=(2.0, -1.0, 0.5), radius=0.2, mass=2.0)
    return Scene(bodies=[Balls(balls=[ball])], drag=0.1,
                 terrains=[Bowl(center=(0.0, 1.0, 0.0), radius=1.0, friction=0.3,
                                restitution=0.5)])


SCENES = {"plane": on_plane, "bowl": in_bowl}
# a bowl under implicit_euler is refused for every body (test_gradients_curved.py)
CASES = [(integrator, case) for integrator in STEPS for case in SCENES
         if not (case == "bowl" and integrator == "implicit_euler")]


@pytest.mark.parametrize("integrator, case", CASES)
def test_ball_gradients_match_finite_differences(integrator, case):
    assert_gradients_match(SCENES[case], integrator, KEYS)


def meeting():
    """Two balls 1 mm apart that close at 5 cm/s in the air: slower than gravity adds in a step,
    so that backward Euler's solve holds them as a resting pair (contact_sets/solve.py)."""
    balls = Balls(balls=[Ball(position=(-0.2005, 1.0, 0.0), velocity=(0.03, 0.2, 0.1),
                              radius=0.2, mass=2.0),
                         Ball(position=(0.2005, 1.0, 0.02), velocity=(-0.02, -0.1, 0.0),
                              radius=0.2, mass=1.0)], ball_restitution=0.6)
    return Scene(bodies=[balls], terrains=[], drag=0.1)


@pytest.mark.parametrize("integrator", list(STEPS))
def test_balls_that_meet_match_finite_differences(integrator):
    """Under implicit_euler two balls that close slowly are a penalty contact of the solve
    (gradients/implicit_bodies.py), under the explicit methods the post-step pass's."""
    assert_gradients_match(meeting, integrator, ["bodies.0.balls.0.velocity",
                                                 "bodies.0.balls.1.mass",
                                                 "bodies.0.ball_restitution", "gravity"])


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_ball_landing_in_a_wind_matches_finite_differences(integrator):
    """The ball thrown onto the plane against a gusty wind: the air's drag on a sphere beside
    the plane's contact (gradients/wind.py)."""
    from springsim.wind import Gusts, Wind

    def windy():
        scene = on_plane()
        scene.wind = Wind(velocity=(-6.0, 1.0, 2.0), density=1.2, drag=0.8,
                          gusts=Gusts(strength=0.3, length=0.5, seed=1))
        return scene
    assert_gradients_match(windy, integrator, ["wind.velocity", "wind.drag",
                                               "terrains.0.friction", "bodies.0.balls.0.mass"])
