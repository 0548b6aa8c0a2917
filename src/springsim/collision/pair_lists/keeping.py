"""The surface pair list kept between steps (a Verlet list), and the one rule for when it holds.

A list found at positions y (broad_phase/surfaces.py, SKIN thinnest thicknesses beyond contact)
holds every pair within reach until the surface particles have moved apart by half the skin
since (moving together does not count: ``list_holds``). A step where nothing touches then costs
a pass over the surface particles (two where the displacements' box is too large to decide).
Where they have moved apart (a cloth that swings turns by degrees a step at large steps),
``renewed_surface_pairs`` tries, cheapest first:
- one self-colliding sheet (a cloth alone, or with balls) that lies unfolded has no pair of
  its own within reach, proven from its projection on its mean normal
  (unfolded_sheet.lies_unfolded, far cheaper than a search): the list is then empty, as the
  search's would be;
- a list at most RIGID_CHECK_STEPS steps old is still kept if the motion since is rigid piece
  by piece: within half the skin of a rigid fit in every window of the finest grid, and within
  more in coarser ones, for farther pairs (rigid_pieces.moved_rigidly, which does what the
  spread does with a rotation per window of the surface). An older list is searched again
  instead: where the spread keeps a list for long, a search costs less than checking every
  step past that;
- where the sheet lies unfolded within its bare thickness (not the skin too), an empty list
  for that step alone (``unfolded_now_or_searched``);
- else a search.
A list found afresh gives the same contacts (the narrow phase decides), so results do not
depend on when it was found, with one exception: a point carried through a face by between one
and two rest distances is caught (the side test of narrow_phase/after_step.py), but a kept list
only promises the pairs within one rest distance, so whether that point is caught can depend on
when the list was found. That is why the list is part of the state (state.State.pairs).
"""
import math

import numpy as np

from ..._jit import inline_kernel, kernel
from ..broad_phase.surfaces import surface_pairs
from .rigid_pieces import moved_rigidly
from . import PairList
from .unfolded_sheet import lies_unfolded


SKIN = 2.0          # the search reaches this many times the thinnest surface beyond contact
RIGID_CHECK_STEPS = 8   # a list is checked for piecewise rigid motion up to this many steps old


@kernel
def surface_skin(model):
    """How far beyond contact the pair search reaches (m): SKIN times the thinnest surface."""
    return skin_of(model.body_thickness)


@kernel
def skin_of(thickness):
    """SKIN times the thinnest of the bodies' ``thickness`` (m; zero: no surface)."""
    thinnest = np.inf
    for b in range(thickness.shape[0]):
        if thickness[b] > 0.0:
            thinnest = min(thinnest, thickness[b])
    return SKIN * thinnest


@kernel
def no_surface_pairs(model, x):
    """The pair list of a model without surface contact (or before the first search)."""
    return PairList(np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), np.empty((0, 3)),
                    np.zeros(1, np.int64))


@kernel
def start_surface_pairs(model, x):
    """The pair list for the state x (a PairList)."""
    if model.surface_triangles.shape[0] == 0:
        return no_surface_pairs(model, x)
    skin = surface_skin(model)
    if sheet_lies_unfolded(model, x, skin):   # the search would find nothing
        return no_pairs_at(x)
    return unfolded_now_or_searched(model, x, skin)


@inline_kernel
def pairs_at(model, x, pairs):
    """The pair list at x: ``pairs`` while it still holds there (``list_holds``), else one
    renewed there (``renewed_surface_pairs``; NaN too: a search copes with it). The one rule for
    a list after a step, at a call's start and at a Newton estimate, so that all three agree.
    Inlined: where the list holds, no call takes the model."""
    if list_holds(model.surface_points, model.body_thickness, x, pairs.found_at):
        return pairs
    return renewed_surface_pairs(model, x, pairs)


@kernel
def renewed_surface_pairs(model, x, pairs):
    """The pair list at x once the spread no longer keeps ``pairs`` (list_holds): none where
    the sheet lies unfolded (the cheaper proof), ``pairs`` where the motion since was rigid by
    pieces and the list is at most RIGID_CHECK_STEPS steps old, else
    ``unfolded_now_or_searched``."""
    skin = surface_skin(model)
    if sheet_lies_unfolded(model, x, skin):
        return no_pairs_at(x)
    if pairs.age[0] <= RIGID_CHECK_STEPS \
            and moved_rigidly(model.surface_points, model.surface_edges, model.body_thickness,
                              skin, x, pairs.found_at):
        return pairs
    return unfolded_now_or_searched(model, x, skin)


@kernel
def unfolded_now_or_searched(model, x, skin):
    """None for this step alone where the sheet lies unfolded within its bare thickness (the
    contacts at x need no more: no_pairs_this_step), else a fresh search ``skin`` beyond
    contact. Why: a swinging, rippling cloth crowds its projection somewhere once the reach
    holds the skin too (a hanging cloth's turned-over corner), and each such step would search,
    finding nothing, where its proof within the thickness alone holds. Why not within two
    thicknesses, as far as the narrow phase catches a point carried through a face: most of
    those steps fail that, while a sheet whose projection is one to one has no edge through any
    of its triangles at x, nothing to push back; the list promises what a kept one does
    (module doc)."""
    if sheet_lies_unfolded(model, x, 0.0):
        return no_pairs_this_step(x)
    return searched_surface_pairs(model, x, skin)


@kernel
def no_pairs_at(x):
    """An empty pair list found at x."""
    return PairList(np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), x.copy(),
                    np.zeros(1, np.int64))


@kernel
def no_pairs_this_step(x):
    """An empty pair list for the contacts at x alone: no pair is within its rest distance
    there, but none is promised beyond it, so nothing may keep it: its positions are NaN
    (list_holds fails on them) and its age is past the rigid check's."""
    return PairList(np.empty((0, 2), np.int64), np.empty((0, 2), np.int64),
                    np.full_like(x, np.nan), np.full(1, RIGID_CHECK_STEPS + 1, np.int64))


@kernel
def searched_surface_pairs(model, x, skin):
    """The pair list of a search at x, ``skin`` beyond contact."""
    points, edges = surface_pairs(model, x, skin, skin)
    return PairList(points, edges, x.copy(), np.zeros(1, np.int64))


@kernel
def sheet_lies_unfolded(model, x, skin):
    """Whether one self-colliding sheet is the only surface and has no pair within its
    thickness plus ``skin`` at x (collision/pair_lists/unfolded_sheet.py; False without such a
    sheet)."""
    return lies_unfolded(model.surface_triangles, model.sheet_ring_start, model.sheet_ring_edges,
                         model.sheet_boundary, model.sheet_near_boundary, model.neighbour_start,
                         model.neighbours, x, model.body_thickness.max() + skin)


@kernel
def list_holds(points, thickness, x, then):
    """Whether a pair list found at the positions ``then`` still holds every pair within
    reach: the surface points have moved apart by less than the skin since (``spread_since``;
    NaN fails). First the half diagonal of the displacements' box, which bounds the spread
    from above and takes one pass instead of two; the spread only where that bound is too
    large. Arrays, not the model: it runs every step, and a step where nothing touches is to
    make no call that takes the model's ~50 arrays."""
    allowed = 0.5 * skin_of(thickness)
    low0, low1, low2, high0, high1, high2, total = displacement_box(points, x, then)
    if not abs(total) < np.inf:   # NaN or inf somewhere: min and max may have passed over it
        return False
    if (high0 - low0) ** 2 + (high1 - low1) ** 2 + (high2 - low2) ** 2 <= (2.0 * allowed) ** 2:
        return True
    return spread_about(points, x, then, low0, low1, low2, high0, high1, high2) <= allowed


@kernel
def spread_since(points, now, then):
    """max_k |d_k - c| over the points, d_k = now - then, c the middle of the d's box (m); NaN
    if any is, which keeps no list. Two points' distance changes by at most |d_p - d_q|, which
    is at most twice this for any c: with c the middle of the displacements, a cloth or a body
    that moves as a whole keeps its pair list. (Scalars, not small arrays, in the loops: this
    runs every step, and it is the whole cost of contact where nothing touches.)"""
    low0, low1, low2, high0, high1, high2, total = displacement_box(points, now, then)
    if not abs(total) < np.inf:   # min and max may have passed over a NaN
        return np.nan
    return spread_about(points, now, then, low0, low1, low2, high0, high1, high2)


@kernel
def displacement_box(points, now, then):
    """The box of the displacements d_k = now - then over the points (low x, y, z, high x, y,
    z), and the sum of all their components (NaN or inf if any is)."""
    low0 = low1 = low2 = np.inf
    high0 = high1 = high2 = -np.inf
    total = 0.0
    for p in points:
        d0, d1, d2 = now[p, 0] - then[p, 0], now[p, 1] - then[p, 1], now[p, 2] - then[p, 2]
        low0, high0 = min(low0, d0), max(high0, d0)
        low1, high1 = min(low1, d1), max(high1, d1)
        low2, high2 = min(low2, d2), max(high2, d2)
        total += d0 + d1 + d2
    return low0, low1, low2, high0, high1, high2, total


@kernel
def spread_about(points, now, then, low0, low1, low2, high0, high1, high2):
    """max_k |d_k - c|, c the middle of the displacements' box (displacement_box)."""
    c0, c1, c2 = 0.5 * (low0 + high0), 0.5 * (low1 + high1), 0.5 * (low2 + high2)
    farthest = 0.0
    for p in points:
        apart = ((now[p, 0] - then[p, 0] - c0) ** 2 + (now[p, 1] - then[p, 1] - c1) ** 2
                 + (now[p, 2] - then[p, 2] - c2) ** 2)
        farthest = max(farthest, apart)
    return math.sqrt(farthest)
