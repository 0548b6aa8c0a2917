"""A sheet that lies unfolded has no pair of its own within reach: the proof that spares a
self-colliding cloth its pair search.

Project the sheet (one self-colliding surface that is a topological disk: a cloth) on the plane
across its mean normal, the sum of its triangles' area vectors. If every triangle keeps its
orientation there and the boundary stays a simple curve, the projection is one to one: a disk
mapped by positive triangles onto a region whose boundary curve winds once covers that region
once (the degree argument).

The pair search (collision/broad_phase/surfaces.py) takes a point p and a triangle of one body only
if no corner is p or a neighbour of p, and two edges only if no end of one is an end of the other
or its neighbour. In a one-to-one projection, such a point lies outside the triangle and such edges
do not cross, so each pair's distance there is the distance from some particle p to an edge (r, s)
with neither r nor s in N[p] (p and its neighbours). The projection shortens every distance, so the
pair is at least that far apart in space too. Let U(p) be the triangles with a corner in N[p]: a
neighbourhood of p. The straight way from p to such an edge leaves U(p) through one of its edges
with no end in N[p] (``ring_edges``, listed for p when the model is built: sheet_arrays.py), or
leaves the sheet through a boundary edge of U(p) and comes back in through a boundary edge with
no end in N[p]. So no pair of the sheet is closer than ``reach`` if

- every triangle faces the mean normal and the boundary does not cross itself,
- every particle is at least ``reach`` from its ring edges in the projection,
- every particle with a boundary corner in U(p) is at least ``reach`` from the boundary edges
  with no end in N[p].

What it gives: a flat square grid cloth has its ring edges sqrt(2) spacings from each particle
against a reach of 0.75 spacing (rest plus skin, collision/pipeline.py.SKIN), so it passes while it
does not fold over or crumple to half its spacing in the projection (a swinging, rippling
cloth mostly does not; where its free corner turns over, the proof fails, and within its bare
thickness, keeping.unfolded_now_or_searched, it rarely does). A check costs a few passes over
the triangles and the ring edges, about twelve a particle, a small part of a search. Anything
it cannot prove goes to the search; it never finds a pair, so where it passes, the result is
the search's: no pair.
"""
import math

import numpy as np

from ..._jit import kernel
from ..broad_phase.grid import box_grid, region_cells
from ...geometry.closest_points import area_vector, triangle_normal
from .sheet_arrays import in_closed_neighbourhood


FACING = 1e-9     # a triangle faces the axis if its normal's cosine to it is above this
AXIS_TURNS = 8    # turns of the axis at most, where the mean normal does not do
TURN_BELOW = 0.4  # the triangles whose cosine to the axis is below this pull it
TURN = 0.5        # by this share of their mean unit normal
STEEP = 0.3       # the turns stop once every triangle's cosine to the axis is this high


@kernel
def lies_unfolded(triangles, ring_start, ring_edges, boundary, near_boundary, neighbour_start,
                  neighbours, x, reach):
    """Whether the sheet (the model's ``sheet_*`` arrays) has no pair of its own closer than
    ``reach`` at x (module doc). False where it cannot tell (NaN included), and without a
    sheet. The axis is the mean normal, else (a corner turned over, or the projection crowded
    where the sheet stands steep to it) that axis turned towards the triangles that face it
    least, until all face it at STEEP or more."""
    if boundary.shape[0] == 0:
        return False
    a0, a1, a2 = mean_normal(triangles, x)
    sheet = (triangles, ring_start, ring_edges, boundary, near_boundary, neighbour_start,
             neighbours)
    if unfolded_along(sheet, x, reach, a0, a1, a2):
        return True
    turned = False
    for turn in range(AXIS_TURNS):
        worst, p0, p1, p2 = least_facing(triangles, x, a0, a1, a2)
        if not worst < STEEP:
            break
        a0, a1, a2 = unit(a0 + TURN * p0, a1 + TURN * p1, a2 + TURN * p2)
        turned = True
    return turned and unfolded_along(sheet, x, reach, a0, a1, a2)


@kernel
def unfolded_along(sheet, x, reach, a0, a1, a2):
    """Whether the module doc's three conditions hold in the projection along the unit axis a."""
    triangles, ring_start, ring_edges, boundary, near_boundary, neighbour_start, neighbours = sheet
    if not all_facing(triangles, x, a0, a1, a2):
        return False
    flat = projected(x, a0, a1, a2)
    return rings_clear(ring_start, ring_edges, flat, reach) \
        and boundary_clear(boundary, near_boundary, neighbour_start, neighbours, flat, reach)


@kernel
def least_facing(triangles, x, a0, a1, a2):
    """The least cosine of a triangle's normal to the unit axis a, and the mean unit normal of
    the triangles below TURN_BELOW (zero if none)."""
    worst = np.inf
    p0 = p1 = p2 = 0.0
    count = 0
    for t in range(triangles.shape[0]):
        n0, n1, n2 = triangle_normal(x, triangles[t, 0], triangles[t, 1], triangles[t, 2])
        cosine = n0 * a0 + n1 * a1 + n2 * a2
        worst = min(worst, cosine)
        if cosine < TURN_BELOW:
            p0, p1, p2, count = p0 + n0, p1 + n1, p2 + n2, count + 1
    if count > 0:
        p0, p1, p2 = p0 / count, p1 / count, p2 / count
    return worst, p0, p1, p2


@kernel
def unit(v0, v1, v2):
    """v / |v| (NaN where v is zero or not finite)."""
    size = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if not (size > 0.0 and size < np.inf):
        return np.nan, np.nan, np.nan
    return v0 / size, v1 / size, v2 / size


@kernel
def mean_normal(triangles, x):
    """The unit sum of the triangles' area vectors (NaN where it is zero)."""
    a0 = a1 = a2 = 0.0
    for t in range(triangles.shape[0]):
        n0, n1, n2 = area_vector(x, triangles[t, 0], triangles[t, 1], triangles[t, 2])
        a0, a1, a2 = a0 + n0, a1 + n1, a2 + n2
    return unit(a0, a1, a2)


@kernel
def all_facing(triangles, x, a0, a1, a2):
    """Whether every triangle's normal has a cosine above FACING with the unit axis a."""
    for t in range(triangles.shape[0]):
        n0, n1, n2 = area_vector(x, triangles[t, 0], triangles[t, 1], triangles[t, 2])
        along = n0 * a0 + n1 * a1 + n2 * a2
        if not (along > 0.0 and along * along > FACING * FACING * (n0 * n0 + n1 * n1 + n2 * n2)):
            return False
    return True


@kernel
def projected(x, a0, a1, a2):
    """(P, 2) the particles' coordinates in the plane across the unit axis a."""
    if abs(a0) < 0.9:   # e1 = a x (1, 0, 0), else a x (0, 1, 0): never near parallel to a
        e0, e1, e2 = 0.0, a2, -a1
    else:
        e0, e1, e2 = -a2, 0.0, a0
    size = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    e0, e1, e2 = e0 / size, e1 / size, e2 / size
    f0, f1, f2 = a1 * e2 - a2 * e1, a2 * e0 - a0 * e2, a0 * e1 - a1 * e0   # a x e
    flat = np.empty((x.shape[0], 2))
    for p in range(x.shape[0]):
        flat[p, 0] = x[p, 0] * e0 + x[p, 1] * e1 + x[p, 2] * e2
        flat[p, 1] = x[p, 0] * f0 + x[p, 1] * f1 + x[p, 2] * f2
    return flat


@kernel
def rings_clear(ring_start, ring_edges, flat, reach):
    """Whether every particle is at least ``reach`` from its ring edges in the projection."""
    limit = reach * reach
    for p in range(ring_start.shape[0] - 1):
        for k in range(ring_start[p], ring_start[p + 1]):
            if not segment_clear(flat, p, ring_edges[k, 0], ring_edges[k, 1], limit):
                return False
    return True


@kernel
def segment_clear(flat, p, r, s, limit):
    """Whether point p is at least sqrt(limit) from the segment (r, s) in the plane (not if
    any is NaN). Without a division: beside the segment, |w|^2 - (w.d)^2 / |d|^2 >= limit."""
    d0, d1 = flat[s, 0] - flat[r, 0], flat[s, 1] - flat[r, 1]
    w0, w1 = flat[p, 0] - flat[r, 0], flat[p, 1] - flat[r, 1]
    along, length, from_r = w0 * d0 + w1 * d1, d0 * d0 + d1 * d1, w0 * w0 + w1 * w1
    if along <= 0.0:
        return from_r >= limit
    if along >= length:
        return (w0 - d0) ** 2 + (w1 - d1) ** 2 >= limit
    return from_r * length - along * along >= limit * length


@kernel
def boundary_clear(boundary, near_boundary, neighbour_start, neighbours, flat, reach):
    """Whether the projected boundary is a simple curve (no two of its edges cross, and two
    that follow each other do not fold back) and every particle near it is at least ``reach``
    from its edges with no end in N[p]. The boundary edges go into a grid (grid.box_grid),
    their boxes grown by ``reach``."""
    boxes = np.zeros((boundary.shape[0], 6))
    for g in range(boundary.shape[0]):
        r, s = boundary[g, 0], boundary[g, 1]
        for c in range(2):
            boxes[g, c] = min(flat[r, c], flat[s, c]) - reach
            boxes[g, 3 + c] = max(flat[r, c], flat[s, c]) + reach
    grid = box_grid(boxes, 0)   # a few hundred boxes: as few cells as the per-box cap gives
    found = np.empty(boundary.shape[0], np.int64)
    limit = reach * reach
    for p in near_boundary:
        for k in range(boxes_around(grid, flat[p, 0], flat[p, 1], flat[p, 0], flat[p, 1], found)):
            r, s = boundary[found[k], 0], boundary[found[k], 1]
            if not (in_closed_neighbourhood(p, r, neighbour_start, neighbours)
                    or in_closed_neighbourhood(p, s, neighbour_start, neighbours)
                    or segment_clear(flat, p, r, s, limit)):
                return False
    for g in range(boundary.shape[0]):
        for k in range(boxes_around(grid, boxes[g, 0] + reach, boxes[g, 1] + reach,
                                    boxes[g, 3] - reach, boxes[g, 4] - reach, found)):
            h = found[k]
            if h > g and edges_meet(flat, boundary[g, 0], boundary[g, 1], boundary[h, 0],
                                    boundary[h, 1]):
                return False
    return True


@kernel
def boxes_around(grid, low0, low1, high0, high1, found):
    """Write to ``found`` the boxes of the grid (grid.box_grid, flat: z = 0) that overlap
    the rectangle; returns how many."""
    origin, cell, dims, cell_start, members, member_boxes, largest = grid
    x0, x1, y0, y1, z0, z1 = region_cells(low0, low1, 0.0, high0, high1, 0.0, origin, cell,
                                          dims, largest)
    count = 0
    for ix in range(x0, x1 + 1):
        for iy in range(y0, y1 + 1):
            first = (ix * dims[1] + iy) * dims[2]
            for k in range(cell_start[first + z0], cell_start[first + z1 + 1]):
                if member_boxes[k, 0] <= high0 and low0 <= member_boxes[k, 3] \
                        and member_boxes[k, 1] <= high1 and low1 <= member_boxes[k, 4]:
                    found[count] = members[k]
                    count += 1
    return count


@kernel
def edges_meet(flat, a, b, c, d):
    """Whether boundary edges (a, b) and (c, d) meet anywhere but at a shared end: cross or
    touch, or, one following the other, fold back along it (NaN meets)."""
    if b == c or d == a:   # one follows the other: they meet only if they fold back
        if d == a:
            a, b, c, d = c, d, a, b
        u0, u1 = flat[a, 0] - flat[b, 0], flat[a, 1] - flat[b, 1]
        w0, w1 = flat[d, 0] - flat[c, 0], flat[d, 1] - flat[c, 1]
        cross, dot = u0 * w1 - u1 * w0, u0 * w0 + u1 * w1
        # parallel within rounding and the same way: they overlap (a turn below 1e-12 radians
        # is taken for none, so that rounding never hides a fold)
        return not (abs(cross) > 1e-12 * math.sqrt((u0 * u0 + u1 * u1) * (w0 * w0 + w1 * w1))
                    or dot < 0.0)
    o1, o2 = orientation(flat, a, b, c), orientation(flat, a, b, d)
    o3, o4 = orientation(flat, c, d, a), orientation(flat, c, d, b)
    if not (abs(o1) + abs(o2) + abs(o3) + abs(o4) < np.inf):
        return True
    return min(o1, o2) <= 0.0 <= max(o1, o2) and min(o3, o4) <= 0.0 <= max(o3, o4)


@kernel
def orientation(flat, a, b, c):
    """Twice the signed area of the projected triangle (a, b, c)."""
    return ((flat[b, 0] - flat[a, 0]) * (flat[c, 1] - flat[a, 1])
            - (flat[b, 1] - flat[a, 1]) * (flat[c, 0] - flat[a, 0]))
