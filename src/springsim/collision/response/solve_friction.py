"""Coulomb friction of the solve's surface contacts, applied when the solve is done.

Why: the penalty springs of penalty.py push inside the solve but have no friction, and a
contact they hold at rest leaves the post-step pass (collision/pipeline.py) no approach speed
to stop, so no normal impulse to scale its friction by: a cube resting on another slid off it
at about 0.065 m/s. Here each active surface contact's push over the step, its penalty force
times h,
    J_N = h k (-phi) = (h^2 k) (-phi) / h,      phi = n . sum_i c_i x_i(end of step) - R,
is the normal impulse that bounds its friction (a cube at rest on another: J_N sums to m g h,
what gravity gives in a step), and response/impulses.apply_friction applies Coulomb friction
against it (static, else kinetic; the same Jacobi passes with mass splitting, so the result
depends on no order and conserves momentum) to the end-of-step velocities. The positions are
then taken from those velocities, x + h v, so a contact that sticks does not slide during the
step either. A ball's contacts with particles and sheets take the ball's friction here the same
way (balls resting on the reference cloth slid about on it for ever without it: the post-step
pass, which had their friction before, sees them at rest and gives none); a ball against a ball
has none, as in the post-step pass.
"""
import numpy as np

from ..._jit import kernel
from ..contact_sets import BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE, PARAMS, PASSES, ImpulseContacts
from ..contact_sets.after_step import surface_contact_keys, surface_params
from .impulses import apply_friction


@kernel
def apply_contact_friction(model, contacts, x_end, v, h):
    """Friction of the active contacts of the solve's contact set ``contacts`` (but ball-ball
    ones) on the end-of-step velocities v, in place, against their penalty impulses at the
    end-of-step positions ``x_end`` (module doc). Returns whether there was any (then the
    positions are to be taken from v again)."""
    nodes, weights, normal = contacts.nodes, contacts.weights, contacts.normal
    coefficient, active, shape, rest = (contacts.coefficient, contacts.active, contacts.shape,
                                        contacts.rest)
    rows = np.empty(nodes.shape[0], np.int64)
    count = 0
    for p in range(nodes.shape[0]):
        if active[p] and not (shape[p] == BALL_POINT and model.ball_slot[nodes[p, 1]] >= 0):
            rows[count] = p
            count += 1
    if count == 0:
        return False
    rows = rows[:count]
    pushed = np.empty(count)
    params = np.empty((count, PARAMS))
    keys, body = surface_contact_keys(model), model.particle_body
    for k in range(count):
        p = rows[k]
        phi = -rest[p]
        for i in range(4):
            for c in range(3):
                phi += weights[p, i] * normal[p, c] * x_end[nodes[p, i], c]
        pushed[k] = coefficient[p] * max(-phi, 0.0) / h
        if shape[p] == BALL_POINT or shape[p] == BALL_TRIANGLE or shape[p] == BALL_SAMPLE:
            ball_friction_params(model, nodes[p, 0], params[k])
        else:
            surface_params(keys, body[nodes[p, 0]], body[nodes[p, 3]], params[k])
    rubbing = ImpulseContacts(nodes[rows], weights[rows], normal[rows], np.zeros(count), params)
    apply_friction(model.inv_mass, v, rubbing, pushed)
    return True


@kernel
def ball_friction_params(model, ball, out):
    """A ball contact's parameters for friction alone: the ball's Coulomb friction, kinetic and
    static, in the surfaces' passes."""
    friction = model.particle_friction[model.ball_slot[ball]]
    out[0], out[1], out[2], out[3], out[4], out[5] = 0.0, friction, friction, 0.0, 1.0, PASSES
