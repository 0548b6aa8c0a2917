"""Body-body contact after the step: the one pass every integrator runs after its update, for every
pair that touches. A point of one surface against a triangle of another (or of its own, for a
self-colliding body), two edges of self-colliding bodies, and a ball against any particle or
another ball.

The stages, in order: the surface pair list is kept or renewed at the step's end positions
(pair_lists/keeping.py), the balls' pairs are found afresh (broad_phase/balls.py: balls are few
and fast), the touching pairs become stencils (contact_sets/after_step.py), and the response
changes velocities, then positions (response/impulses.py, response/overlap.py).
"""
import numpy as np

from .._jit import inline_kernel, kernel
from .broad_phase.balls import find_contacts
from .contact_sets.after_step import touching_contacts
from .pair_lists.keeping import pairs_at
from .response.impulses import split_mobilities, apply_impulses
from .response.overlap import correct_overlaps


@inline_kernel
def resolve_contacts(model, x, v, start, pairs):
    """Apply every body-body contact of (x, v) in place (module doc): those of the surface pair
    list and those of the balls; ``start`` holds the positions at the start of the step.
    Returns the surface list for the next step: ``pairs``, or a renewed one once it no longer
    holds (``list_holds``, ``renewed_surface_pairs``). Inlined, with the model passed on only
    where there is a search or a contact: a step where nothing touches makes no call that takes
    the model."""
    if model.surface_triangles.shape[0] > 0:
        pairs.age[0] += 1
        pairs = pairs_at(model, x, pairs)
    balls = ball_pairs(x, model.radius, model.balls, model.ball_slot)
    if pairs.points.shape[0] + pairs.edges.shape[0] + balls.shape[0] > 0:
        respond_to_contacts(model, x, v, start, pairs.points, pairs.edges, balls)
    return pairs


@kernel
def ball_pairs(x, radius, balls, ball_slot):
    """The (ball, partner) pairs that overlap (broad_phase/balls.find_contacts; none without
    balls)."""
    if balls.shape[0] == 0:
        return np.empty((0, 2), np.int64)
    return find_contacts(x, radius, balls, ball_slot)


@kernel
def respond_to_contacts(model, x, v, start, point_pairs, edge_pairs, balls):
    """The touching pairs' impulses and overlap corrections (module doc)."""
    contacts = touching_contacts(model, x, start, point_pairs, edge_pairs, balls)
    if contacts.nodes.shape[0] > 0:
        mobility = split_mobilities(model.inv_mass, contacts.nodes, contacts.weights)
        stuck = apply_impulses(model.inv_mass, v, contacts, mobility)
        correct_overlaps(model.inv_mass, x, start, contacts, stuck, mobility)
