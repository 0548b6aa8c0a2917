"""A self-colliding body's own pairs among backward Euler's contacts: those in contact at the
step's start and, as the Newton estimates show them, those the step brings into contact.

Why not searched like the pairs of two bodies (solve_pairs.py): searched with the step's
reach, a hanging cloth finds every particle within a few thicknesses of hundreds of its own
triangles (a step then costs tens of times more), and a cloth hit by a fast ball has hundreds of
its own pairs passing by rather than through each other, which taken for crossings threw the
ball up. So the solve takes only the own pairs closer than
their thickness: at the step's start (a fold lying on itself), and at the end of each solve,
x + h (v + dv) (a fold pressed shut within the step: a heavy cube dropped at 5 m/s onto a
folded cloth pushed one layer through the other with the start's pairs alone); where a solve
ends with pairs the contact set lacks, they join it and that Newton iteration is solved again
from where it started (MOST_OWN_REDOS times at most). Why again rather than one Newton
iteration more: relinearized about an estimate with a layer pushed through, the next
iterations drove that cube's step to 21 m/s and tangled the cloth for good.

Which pairs: those of the post-step pass's list (collision/pipeline.py) where it still holds
at those positions, else of a list renewed there. Either holds every pair in contact, so the
set, sorted, does not depend on when or how a list was found: a run resumed from a saved
state steps bit for bit as the one that went on (the farther pairs a list may also hold did
not: 6 mm after one step of a folded cloth pressed by a cube, a copy of the state against the
run).
"""
from typing import NamedTuple

import numpy as np

from ..._jit import kernel
from ..narrow_phase.stencils import edge_distance, point_triangle_distance
from .keeping import pairs_at


MOST_OWN_REDOS = 4   # times a step may solve a Newton iteration again for its own pairs


class OwnPairs(NamedTuple):
    """A self-colliding body's own pairs in contact, each sorted and listed once."""

    points: np.ndarray   # (K, 2) int64: (surface particle, surface triangle row)
    edges: np.ndarray    # (L, 2) int64: (edge row, edge row)


@kernel
def any_self_collision(model):
    """Whether some body with a surface collides with itself (else it has no own pairs)."""
    return model.surface_triangles.shape[0] > 0 and model.body_self_collision.any()


@kernel
def own_pairs_touching(model, x, pairs):
    """(the pairs of one body closer than its thickness at x: OwnPairs, the list they came
    from: ``pairs`` where it holds at x, else one renewed there, which the step hands on to the
    post-step pass, so that the renewal is not paid twice)."""
    if not any_self_collision(model):
        return OwnPairs(np.empty((0, 2), np.int64), np.empty((0, 2), np.int64)), pairs
    pairs = pairs_at(model, x, pairs)
    points = own_touching(model, x, pairs.points, True)
    edges = own_touching(model, x, pairs.edges, False)
    return OwnPairs(sorted_rows(points, model.surface_triangles.shape[0]),
                    sorted_rows(edges, model.surface_edges.shape[0])), pairs


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
def grown_own_pairs(model, x_k, pairs, own):
    """(OwnPairs: ``own`` and those in contact at the estimate x_k (own_pairs_touching),
    whether they grew, the list at x_k)."""
    more, pairs = own_pairs_touching(model, x_k, pairs)
    points = sorted_rows(np.concatenate((own.points, more.points)),
                         model.surface_triangles.shape[0])
    edges = sorted_rows(np.concatenate((own.edges, more.edges)), model.surface_edges.shape[0])
    grew = points.shape[0] > own.points.shape[0] or edges.shape[0] > own.edges.shape[0]
    return OwnPairs(points, edges), grew, pairs
