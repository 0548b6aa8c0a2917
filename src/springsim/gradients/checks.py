"""What the adjoint covers, checked before the work (``check_supported``) and after the forward
run (``check_contact_free``), each a one-line SceneError.

Covered: every integrator (adjoints.py), springs,
dampers, gravity, drag, the wind on surfaces and balls (wind.py), pins that hold, move or are
soft (pins.py) and attachments, soft or hard (attachments.py); contact with planes, spheres,
bowls and meshes, still, moving rigidly or deforming (contact.py, implicit_replay.py and
implicit_contact.py); body-body
contact of surfaces (a self-colliding body's own too) and of balls with balls and particles under
every integrator (body_contact.py, implicit_bodies.py). Not yet covered under implicit_euler, so
refused at that step rather than given a gradient that leaves a force out: a contact that a
solve's update sweeps onto a deforming mesh's edge or corner from beyond its reach
(implicit_lookup.py), a particle let go and taken again within a step on another terrain
(implicit_replay.py), and a step the forward cut into parts. A terrain the adjoint does not
follow may be in the scene as long as no particle comes within its contact band during the
run (``contact_check``).
"""
import numpy as np

from ..errors import SceneError
from .adjoints import adjoint_class, differentiable


def check_supported(simulation) -> None:
    name = simulation.integrator.name
    if adjoint_class(simulation.integrator) is None:
        raise SceneError("integrator", name, "has no adjoint yet: gradients run under "
                         + ", ".join(differentiable()))


def contact_check(simulation, physical=None):
    """A function ``check(step, (x, v))`` that refuses a state in which some particle is within
    the contact band of a terrain the adjoint does not follow (a kind whose ``adjoint_shape``
    is None: every built-in kind has one), or would be within the step, as
    implicit_euler's constraints look ahead; None if it follows them all. Such a terrain
    neither moves nor deforms (both are the built-in kinds' own). The backward pass calls it on
    every step's start."""
    from .contact import Planes

    model = simulation.model
    shapes = (Planes.of(model) if physical is None else physical.planes).shapes
    followed = [shape is not None for shape in shapes]
    if all(followed):
        return None
    radii = model.arrays.terrain_offset
    h = simulation.dt

    def check(step, state):
        x, v = state[0], state[1]
        for t, terrain in enumerate(model.terrains):
            if followed[t]:
                continue
            phi = terrain.signed_distance(x, radii)
            reach = phi + h * np.minimum(_normal_speed(terrain, x, v, radii), 0.0)
            touching = (np.minimum(phi, reach) < model.arrays.terrain_epsilon[t]) & ~model.pinned
            if touching.any():
                raise SceneError(f"terrains.{t}", type(terrain).__name__,
                                 f"is touched at step {step} (particle "
                                 f"{int(np.argmax(touching))}): gradients follow contact with "
                                 "planes, spheres, bowls and meshes, still, moving rigidly or "
                                 "deforming, only")
    return check


def _normal_speed(terrain, x, v, radii):
    """v . n, n the terrain's normal by differences of its distance (any terrain kind)."""
    step = 1e-6
    normal = np.stack([(terrain.signed_distance(x + step * e, radii)
                        - terrain.signed_distance(x - step * e, radii)) / (2 * step)
                       for e in np.eye(3)], axis=1)
    return np.einsum("ij,ij->i", v, normal)
