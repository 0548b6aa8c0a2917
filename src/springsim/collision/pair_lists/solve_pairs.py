"""Which surface pairs backward Euler's solve takes as candidate contacts in a step.

The post-step pass (collision/pipeline.py) sees where a step ended; a solve that knows nothing
of the surfaces can carry a point farther through a surface in one step than that pass can push
back, and a cube dropped onto another at 1/30 s would sink into it. So implicit_euler makes
surface contacts stiff one-sided penalty springs of its solve, like the ball contacts
(penalty.py: the contact set, linearization and active set shared by both). What it needs
first is the pairs a step can bring into contact, found here.

A step moves two particles i and j apart or together by at most h |v_i - v_j| <= 2 h max_k |v_k -
u| for any velocity u (the triangle inequality); u = the centre of the surface points' velocity box
makes the bound small for bodies moving together (a falling cloth) and 2 h V for two bodies
approaching at V each. Pairs are searched (broad_phase/surfaces.surface_pairs) on the predicted
positions x + h v with reach = each pair's rest distance + that bound + SURFACE_REACH_SLACK of the
largest thickness, for what the solve's velocity change adds. A model without surface contact
returns at once.

A body's own pairs (a cloth's folds) are not searched here, but taken from the post-step pass's
list, those in contact at the step's start and at the end of each solve: own_pairs.py says
why.

The search (collision/broad_phase/surfaces.py, several times the cost of a step where nothing
touches) is not run every step: it reaches SKIN thicknesses farther, and its list is kept (in the
state: State.solve_pairs) while it still holds every pair a step needs. Two points' distance
changes by at most 2 max_k |d_k - c| for displacements d since the search and any c (c = the middle
of their box), so the list holds every pair within the reach now as long as reach + 2 max_k |d_k -
c| <= the reach it was found with. A kept list has more candidates than a fresh one, in the same
order; the extra ones are farther than the reach, which the solve does not close, so they stay
inactive and the results are the same (unless a solve moves a pair past its slack).
"""
import math

from numba.typed import List
import numpy as np

from ..._jit import kernel
from ..broad_phase.surfaces import surface_pairs
from . import EDGES, POINTS, SolvePairList
from .keeping import SKIN, spread_since


SURFACE_REACH_SLACK = 0.5   # share of the largest thickness added to the reach a step needs
NO_SELF_CONTACT = -np.inf   # the search distance that finds no pair of one body


@kernel
def kept_surface_pairs(x):
    """Room for the kept pair list, none found yet (a SolvePairList)."""
    pairs = List()
    pairs.append(np.empty((0, 2), np.int64))
    pairs.append(np.empty((0, 2), np.int64))
    # zeros, not empty: a saved state's bytes depend on nothing but the run
    return SolvePairList(pairs, np.zeros_like(x), np.full(1, -1.0))


@kernel
def find_surface_pairs(model, x, v, h, kept):
    """(point-triangle pairs (K, 2), edge-edge pairs (L, 2)) the step may bring within their
    rest distance: the ``kept`` list (kept_surface_pairs) while it holds them all, else a fresh
    search, kept (module doc); none without surface contact."""
    if model.surface_triangles.shape[0] == 0 or one_body(model):
        return np.empty((0, 2), np.int64), np.empty((0, 2), np.int64)
    thickest = 0.0
    for b in range(model.body_thickness.shape[0]):
        thickest = max(thickest, model.body_thickness[b])
    closing = 2.0 * h * velocity_spread(model.surface_points, v)
    reach = thickest * SURFACE_REACH_SLACK + closing   # beyond each pair's rest distance
    predicted = np.empty_like(x)
    for i in range(x.shape[0]):
        for c in range(3):
            predicted[i, c] = x[i, c] + h * v[i, c]
    if reach + 2.0 * spread_since(model.surface_points, predicted, kept.found_at) <= kept.reach[0]:
        return kept.pairs[POINTS], kept.pairs[EDGES]
    kept.reach[0] = reach + SKIN * thickest
    # a body's own folds are left to the post-step pass (module doc): no pair of one body
    points, edges = surface_pairs(model, predicted, kept.reach[0], NO_SELF_CONTACT)
    kept.pairs[POINTS], kept.pairs[EDGES] = points, edges
    kept.found_at[:] = predicted
    return points, edges


@kernel
def one_body(model):
    """Whether every surface belongs to one body: then the solve has no pair to look for."""
    body = model.particle_body
    first = body[model.surface_points[0]]
    for p in model.surface_points:
        if body[p] != first:
            return False
    return True


@kernel
def velocity_spread(points, v):
    """max_k |v_k - u| over the points, u the centre of their velocity box (m/s)."""
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    for p in points:
        for c in range(3):
            low[c], high[c] = min(low[c], v[p, c]), max(high[c], v[p, c])
    spread = 0.0
    for p in points:
        spread = max(spread, math.sqrt((v[p, 0] - 0.5 * (low[0] + high[0])) ** 2
                                       + (v[p, 1] - 0.5 * (low[1] + high[1])) ** 2
                                       + (v[p, 2] - 0.5 * (low[2] + high[2])) ** 2))
    return spread
