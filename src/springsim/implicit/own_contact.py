"""A self-colliding body's own pairs among backward Euler's contacts: those in contact at the
step's start and, as the Newton estimates show them, those the step brings into contact.

Why not searched like the pairs of two bodies (surface_contact.py): searched with the step's
reach, a 100 x 100 cloth hanging at 1/60 s ran at 1.5 steps/s instead of 67 (every particle
within a few thicknesses of hundreds of its own triangles), and a cloth hit by a 20 m/s ball at
1/30 s had hundreds of its own pairs, passing by rather than through each other, taken for
crossings, which threw the ball 13 m up. So the solve takes only the own pairs closer than
their thickness: at the step's start (a fold lying on itself), and at the end of each solve,
x + h (v + dv) (a fold pressed shut within the step: a heavy cube dropped at 5 m/s onto a
folded cloth pushed one layer through the other with the start's pairs alone); where a solve
ends with pairs the contact set lacks, they join it and that Newton iteration is solved again
from where it started (MOST_OWN_REDOS times at most). Why again rather than one Newton
iteration more: relinearized about an estimate with a layer pushed through, the next
iterations drove that cube's step to 21 m/s and tangled the cloth for good.

Which pairs: those of the post-step pass's list (surface_collisions.py) where it still holds
at those positions, else of a list renewed there. Either holds every pair in contact, so the
set, sorted, does not depend on when or how a list was found: a run resumed from a saved
state steps bit for bit as the one that went on (the farther pairs a list may also hold did
not: 6 mm after one step of a folded cloth pressed by a cube, a copy of the state against the
run).
"""
import numpy as np

from .._jit import kernel
from ..proximity import edge_distance, point_triangle_distance
from ..surface_collisions import pairs_at

MOST_OWN_REDOS = 4   # times a step may solve a Newton iteration again for its own pairs


@kernel
def any_self_collision(model):
    """Whether some body with a surface collides with itself (else it has no own pairs)."""
    return model.surface_triangles.shape[0] > 0 and model.body_self_collision.any()


@kernel
def own_pairs_touching(model, x, pairs):
    """(point-triangle pairs, edge-edge pairs) of one body closer than its thickness at x,
    sorted, and the list they came from: ``pairs`` where it holds at x, else one renewed
    there (which the step hands on to the post-step pass: the renewal is not paid twice)."""
    if not any_self_collision(model):
        return np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), pairs
    pairs = pairs_at(model, x, pairs)
    return (sorted_rows(own_touching(model, x, pairs[0], True), model.surface_triangles.shape[0]),
            sorted_rows(own_touching(model, x, pairs[1], False), model.surface_edges.shape[0]),
            pairs)


@kernel
def own_touching(model, x, pairs, point_triangle):
    """The rows of ``pairs`` (point-triangle if ``point_triangle``, else edge-edge) of one body
    that are closer than its thickness at x."""
    body, thickness = model.particle_body, model.body_thickness
    triangles, edges = model.surface_triangles, model.surface_edges
    corners = np.empty((3, 3))
    keep = np.zeros(pairs.shape[0], np.bool_)
    for k in range(pairs.shape[0]):
        if point_triangle:
            p, first = pairs[k, 0], triangles[pairs[k, 1], 0]
            gap = point_triangle_distance(x, triangles, pairs[k, 0], pairs[k, 1], corners)
        else:
            p, first = edges[pairs[k, 0], 0], edges[pairs[k, 1], 0]
            gap = edge_distance(x, edges, pairs[k, 0], pairs[k, 1])
        keep[k] = body[p] == body[first] and gap < thickness[body[p]]
    return pairs[keep]


@kernel
def sorted_rows(rows, base):
    """The rows, each once, sorted (rows (i, j) with 0 <= j < base)."""
    keys = np.empty(rows.shape[0], np.int64)
    for k in range(rows.shape[0]):
        keys[k] = rows[k, 0] * base + rows[k, 1]
    keys = np.unique(keys)
    unique = np.empty((keys.shape[0], 2), np.int64)
    for k in range(keys.shape[0]):
        unique[k, 0], unique[k, 1] = keys[k] // base, keys[k] % base
    return unique


@kernel
def grown_own_pairs(model, x_k, pairs, own_points, own_edges):
    """(own point pairs, own edge pairs, whether they grew, the list at x_k): those given and
    those in contact at the estimate x_k (own_pairs_touching)."""
    more_points, more_edges, pairs = own_pairs_touching(model, x_k, pairs)
    points = sorted_rows(np.concatenate((own_points, more_points)),
                         model.surface_triangles.shape[0])
    edges = sorted_rows(np.concatenate((own_edges, more_edges)), model.surface_edges.shape[0])
    grew = points.shape[0] > own_points.shape[0] or edges.shape[0] > own_edges.shape[0]
    return points, edges, grew, pairs
