"""Gradients through pins that move and soft pins (gradients/pins.py) against central finite
differences of the forward run, under each integrator with an adjoint: a cube carried by a
corner along a keyed path (a hard pin on a path), and one hung from two soft pins, one of them
moving, whose stiffness and damping are parameters too."""
import numpy as np
import pytest

from springsim.bodies.pins import Pin
from springsim.gradients import prepare, run_gradient
from springsim.gradients.losses import as_loss
from springsim.motion import Keyframe, Motion
from test_gradients import (STEPS, TIGHT, assert_gradients_match, central_difference, jittered,
                            small_scene, weighted_squares)

CARRIED = 8   # the carried corner

KEYS = ["bodies.0.structural.ks", "bodies.0.shear.kd", "bodies.0.velocity", "gravity", "drag"]


def carried():
    """The small cube (one corner pinned where it is) with another corner carried along a
    smooth keyed path that turns."""
    scene = small_scene()
    path = Motion(interpolation="smooth", keyframes=[
        Keyframe(time=0.0, position=(0.0, 0.0, 0.0)),
        Keyframe(time=0.01, position=(0.05, 0.02, 0.0), rotation_degrees=5.0,
                 rotation_axis=(0.0, 0.0, 1.0)),
        Keyframe(time=0.03, position=(0.12, -0.03, 0.04))])
    scene.bodies[0].pins = [Pin(particles=[CARRIED], motion=path)]
    return scene


def hung():
    """The small cube with no hard pin, on two soft pins: one holding a corner, one pulling
    another along at 0.5 m/s."""
    scene = small_scene()
    scene.bodies[0].pinned = ()
    scene.bodies[0].pins = [Pin(particles=[0], stiffness=400.0, damping=2.0),
                            Pin(particles=[26], stiffness=250.0, damping=1.0,
                                motion=Motion(velocity=(0.5, 0.0, 0.0)))]
    return scene


SCENES = {"carried": (carried, KEYS),
          "hung": (hung, KEYS + ["bodies.0.pins.0.stiffness", "bodies.0.pins.0.damping",
                                 "bodies.0.pins.1.stiffness", "bodies.0.pins.1.damping"])}


@pytest.mark.parametrize("case", list(SCENES))
@pytest.mark.parametrize("integrator", list(STEPS))
def test_pin_gradients_match_finite_differences(integrator, case):
    scene_of, names = SCENES[case]
    assert_gradients_match(scene_of, integrator, names)


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_carried_particle_s_own_start_does_not_matter(integrator):
    """The carried corner is put on its path at every step's start: the gradient with respect
    to its own initial position and velocity is zero, as differences of the forward run say,
    while a free particle's is not (from a start off the rest shape: test_gradients.jittered)."""
    scene = carried()
    dt = STEPS[integrator]
    start = jittered(scene)
    _, simulation, params = prepare(scene, ["initial_positions", "initial_velocities"],
                                    {"initial_positions": start}, integrator=integrator, dt=dt,
                                    **TIGHT.get(integrator, {}))
    model = simulation.model
    result = run_gradient(simulation, as_loss(weighted_squares, 1 / (4 * dt)), 10 * dt)
    for p in params:
        grad = np.ravel(p.gradient(scene, model, result))
        base = p.read(model)
        for j in (3 * CARRIED, 3 * CARRIED + 1, 3 * 5 + 2):
            step = 1e-6 * max(abs(base.ravel()[j]), 1.0)
            expected = central_difference(scene, integrator, p.name, base, j, step, start)
            assert grad[j] == pytest.approx(expected, rel=1e-5, abs=1e-7), (p.name, j)
        assert not grad[3 * 5 + 2] == 0.0
