"""Where body-body surface contacts are, for drawing them: no window, only the contact kernels.

The contacts of a state are those the step's own narrow phase would find there
(surface_collisions.touching_contacts, with the state as its own start; ball contacts are
not drawn): each is a stencil of
signed weights c over four particles. Its point is the second side's closest point,
-sum of c_i x_i over the negative weights (the triangle's closest point, or the second edge's);
its normal points from there towards the first side (the touching point or edge). The drawn
normal is a segment twice the pair's rest distance (the mean of the two bodies' thicknesses).
"""
from typing import NamedTuple

import numpy as np

from ..proximity import surface_pairs
from ..surface_collisions import surface_skin, touching_contacts

NORMAL_LENGTH = 2.0   # drawn normals, in rest distances (thicknesses) of their pair


class ContactMarks(NamedTuple):
    points: np.ndarray    # (K, 3) m: each contact's point on its second side
    normals: np.ndarray   # (K, 3) unit normals, towards the first side
    ends: np.ndarray      # (K, 3) m: the far ends of the drawn normal segments


def has_surface_contact(model) -> bool:
    """Whether ``model`` has surfaces that can touch (a replay's recorded model has none)."""
    triangles = getattr(model.arrays, "surface_triangles", None)
    return triangles is not None and len(triangles) > 0


def contact_marks(arrays, x) -> ContactMarks:
    """The surface contacts of positions ``x`` (P, 3) in a model with ``arrays``
    (model.ModelArrays)."""
    x = np.ascontiguousarray(x, dtype=np.float64)
    if len(arrays.surface_triangles) == 0:
        empty = np.empty((0, 3))
        return ContactMarks(empty, empty, empty)
    skin = surface_skin(arrays)
    point_pairs, edge_pairs = surface_pairs(arrays, x, skin, skin)
    no_balls = np.empty((0, 2), np.int64)
    nodes, weights, normals, _, _ = touching_contacts(arrays, x, x, point_pairs, edge_pairs,
                                                      no_balls)
    bodies = arrays.particle_body[nodes[:, [0, 3]]]   # the first and the second side's
    second_side = np.minimum(weights, 0.0)
    points = -np.einsum("kn,knc->kc", second_side, x[nodes])
    rest = 0.5 * arrays.body_thickness[bodies].sum(axis=1)
    ends = points + NORMAL_LENGTH * rest[:, None] * normals
    return ContactMarks(points, normals, ends)
