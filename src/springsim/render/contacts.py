"""Where body-body contacts are, for drawing them: no window, only the contact kernels.

The contacts of a state are those the step's own narrow phase would find there
(contact_sets/after_step.touching_contacts, with the state as its own start): each is a stencil of
signed weights c over four particles. Its point is on the second side: the closest point
-sum of c_i x_i over the negative weights (the triangle's closest point, the second edge's, or
a ball's partner), moved out by the partner's radius if it is a ball; its normal points from
there towards the first side (the touching point, edge or ball). The drawn normal is a segment
twice the pair's rest distance (the mean of the two bodies' thicknesses) long, or for a ball's
contact half the ball's radius.
"""
from typing import NamedTuple

import numpy as np

from ..collision.broad_phase.surfaces import surface_pairs
from ..collision.pipeline import ball_pairs
from ..collision.pair_lists.keeping import surface_skin
from ..collision.contact_sets.after_step import touching_contacts

NORMAL_LENGTH = 2.0   # drawn normals, in rest distances (thicknesses) of their pair
BALL_NORMAL_LENGTH = 0.5   # a ball's drawn contact normals, in its radii


class ContactMarks(NamedTuple):
    points: np.ndarray    # (K, 3) m: each contact's point on its second side
    normals: np.ndarray   # (K, 3) unit normals, towards the first side
    ends: np.ndarray      # (K, 3) m: the far ends of the drawn normal segments


def has_body_contact(model) -> bool:
    """Whether ``model`` has bodies that can touch: surfaces or balls (a replay's recorded
    model has neither)."""
    arrays = model.arrays
    if not hasattr(arrays, "surface_triangles"):
        return False   # a replay: its arrays hold what is drawn, not what touches
    return len(arrays.surface_triangles) > 0 or len(arrays.balls) > 0


def contact_marks(arrays, x) -> ContactMarks:
    """The body-body contacts of positions ``x`` (P, 3) in a model with ``arrays``
    (model.ModelArrays)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    no_pairs = np.empty((0, 2), np.int64)
    point_pairs = edge_pairs = no_pairs
    if len(arrays.surface_triangles) > 0:
        skin = surface_skin(arrays)
        point_pairs, edge_pairs = surface_pairs(arrays, x, skin, skin)
    balls = ball_pairs(x, arrays.radius, arrays.balls, arrays.ball_slot)
    nodes, weights, normals, _, _ = touching_contacts(arrays, x, x, point_pairs, edge_pairs,
                                                      balls)
    second_side = np.minimum(weights, 0.0)
    points = -np.einsum("kn,knc->kc", second_side, x[nodes])
    points += arrays.radius[nodes[:, 3]][:, None] * normals   # a ball partner's surface
    bodies = arrays.particle_body[nodes[:, [0, 3]]]   # the first and the second side's
    rest = 0.5 * arrays.body_thickness[bodies].sum(axis=1)
    ball = arrays.radius[nodes[:, 0]]   # the first side's radius: a ball's contact, if > 0
    length = np.where(ball > 0.0, BALL_NORMAL_LENGTH * ball, NORMAL_LENGTH * rest)
    return ContactMarks(points, normals, points + length[:, None] * normals)
