"""The contact set at the end of a step: every touching pair's stencil and its parameters
(contact_sets.ImpulseContacts), surfaces first (point-triangle, edge-edge), then balls.

Each contact carries its parameters (PARAMS numbers):
- surfaces: the means of the two bodies' restitution, friction and static friction,
  CORRECTION of the depth a step, PASSES passes;
- a ball and a particle: the ball's ``particle_restitution``, ``particle_friction`` (static and
  kinetic alike) and ``position_correction``; a ball and a ball: the means of their
  ``ball_restitution`` and ``position_correction``, no friction; BALL_PASSES pass.
"""
import numpy as np

from ..._jit import inline_kernel
from . import CORRECTION, PARAMS, PASSES, ImpulseContacts
from ..narrow_phase.after_step import ball_contact, point_triangle_contact, edge_edge_contact


@inline_kernel
def touching_contacts(model, x, start, point_pairs, edge_pairs, balls):
    """The touching pairs as stencils (ImpulseContacts): surfaces first (point-triangle,
    edge-edge), then balls."""
    capacity = point_pairs.shape[0] + edge_pairs.shape[0] + balls.shape[0]
    found = ImpulseContacts(np.empty((capacity, 4), np.int64), np.empty((capacity, 4)),
                            np.empty((capacity, 3)), np.empty(capacity),
                            np.empty((capacity, PARAMS)))
    bodies = np.empty((1, 2), np.int64)   # the touching pair's bodies, from the tests
    corners = np.empty((3, 3))   # work space of closest_on_triangle
    triangles, edges = model.surface_triangles, model.surface_edges
    body, thickness = model.particle_body, model.body_thickness
    # the arrays read in the loops, taken from the model once (each read of one from the model
    # inside them costs a reference count a contact)
    surface_keys = surface_contact_keys(model)
    ball_keys = (model.radius, model.ball_slot, model.ball_restitution,
                 model.particle_restitution, model.particle_friction, model.position_correction)
    count = 0
    params = found.params
    for k in range(point_pairs.shape[0]):
        if point_triangle_contact(triangles, body, thickness, x, start, point_pairs[k, 0],
                                  point_pairs[k, 1], found, count, bodies, corners):
            surface_params(surface_keys, bodies[0, 0], bodies[0, 1], params[count])
            count += 1
    for k in range(edge_pairs.shape[0]):
        if edge_edge_contact(edges, body, thickness, x, start, edge_pairs[k, 0],
                             edge_pairs[k, 1], found, count, bodies):
            surface_params(surface_keys, bodies[0, 0], bodies[0, 1], params[count])
            count += 1
    for k in range(balls.shape[0]):
        if ball_contact(ball_keys, x, balls[k, 0], balls[k, 1], found, count):
            count += 1
    return ImpulseContacts(found.nodes[:count], found.weights[:count], found.normal[:count],
                           found.depth[:count], params[:count])


@inline_kernel
def surface_contact_keys(model):
    """The bodies' restitution, kinetic and static friction (surface_params reads them)."""
    return model.body_restitution, model.body_friction, model.body_static_friction


@inline_kernel
def surface_params(keys, first, second, out):
    """A surface contact's parameters between bodies ``first`` and ``second`` (the means of
    their ``keys``, surface_contact_keys; CORRECTION of the depth a step; a stuck contact's
    sliding all taken back) into ``out`` (PARAMS,)."""
    restitution, kinetic, static = keys
    out[0] = 0.5 * (restitution[first] + restitution[second])
    out[1] = 0.5 * (kinetic[first] + kinetic[second])
    out[2] = 0.5 * (static[first] + static[second])
    out[3] = CORRECTION
    out[4] = 1.0
    out[5] = PASSES
