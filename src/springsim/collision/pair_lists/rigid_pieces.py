"""Whether a kept pair list still holds after a motion that is rigid piece by piece.

A pair list found at positions y holds every pair of surface shapes (a point and a triangle, two
edges) closer than their rest distance plus the skin s. It still holds at positions x if no pair
that was farther then has come within its rest distance since. keeping.spread_since
bounds how much any distance has shrunk by the spread of the displacements x - y, which a
translation leaves at zero but a rotation does not: a 4 m cloth swinging at 1/60 s turns by a few
degrees a step, its points move apart by several thicknesses from each other, and the list was
thrown away every step (the 100 x 100 cloth-hang searched at 193 of 199 steps, finding nothing).

Distances do not shrink under a rotation, so this check compares x with a rigid motion of y
instead. If each particle i of a set has |x_i - (R y_i + t)| <= e for one rotation R and shift t,
two shapes of the set with closest points then at distance d (weights w, w' summing to one) are
now at least

    |sum w x - sum w' x| >= |R (sum w y - sum w' y)| - 2 e >= d - 2 e

apart (t cancels; R keeps lengths). One motion does not fit a whole cloth that swings and bends,
but one per window of a grid does: the windows are the blocks of 2 x 2 x 2 cells (L wide, on the
positions then), overlapping, and a pair of shapes lies in one if all its corners are within L of
each other along each axis, which holds if d + 2 delta < L (delta: the longest surface edge then).
Each window's motion is the best rigid fit of its particles (Kabsch, from sums kept per cell:
best_rotation), and e its particles' largest residual |x_i - R y_i - t|. Any rotation would
do: the residual is measured, not assumed small.

Levels: the cells of level 0 are L_0 = FINEST x (2 delta + rest + s) wide, and its pairs
(d < L_0 - 2 delta) may shrink by s, as the skin allows; each next level's cells are LEVEL_RATIO
times wider, and it takes the pairs that no finer level holds (d >= L_(k-1) - 2 delta), which may
shrink by L_(k-1) - 2 delta - rest; the last level is one cell around everything. Right after
level 0 that last level is tried with level 1's budget, the smallest: where one motion fits the
whole surface that well, the levels between need no look. A level costs four passes over the
surface particles (its grid's bounds, each particle's cell, its cells' sums, and each
particle's residual in its 8 windows) and a fit per window: about a tenth of a search. A
swinging cloth then searches at about half the steps it would with the spread alone
(keeping.RIGID_CHECK_STEPS says when the check is tried); where it still searches, its free
edge whips and bends faster than a rigid fit per window follows.
"""
import math

import numpy as np

from ..._jit import kernel
from ..broad_phase.grid import cell_coordinate, grid_cell_size


FINEST = 1.5        # the finest cells are this many times wider than the pairs they must take


LEVEL_RATIO = 3.0   # a level's cells are this many times wider than the finest pairs it takes


SQUARINGS = 16      # of best_rotation's matrix: its 65,536th power


MAX_CELLS = 512     # a level's grid has at most this many cells (wider cells where it would not)


@kernel
def moved_rigidly(points, edges, thickness, skin, now, then):
    """Whether every pair of surface shapes farther than rest + ``skin`` apart at ``then`` is
    still farther than rest apart at ``now`` (module doc; False where it cannot tell, NaN
    included). ``points``: the surface particles; ``edges``: the surface edges (their longest
    then bounds the shapes' size); ``thickness``: the bodies' (the thickest bounds rest)."""
    longest = longest_edge(edges, then)
    thickest = 0.0
    for b in range(thickness.shape[0]):
        thickest = max(thickest, thickness[b])
    width = FINEST * (2.0 * longest + thickest + skin)
    allowed = skin
    finest = True
    while True:
        one_cell, width = level_shrinks_at_most(points, now, then, width, allowed)
        if width < 0.0:
            return False
        if one_cell:
            return True
        allowed = width - 2.0 * longest - thickest   # the next level's pairs were this far
        if not allowed > 0.0:
            return False
        if finest and level_shrinks_at_most(points, now, then, np.inf, allowed)[1] > 0.0:
            return True   # one motion for all fits within the smallest coarser budget
        finest = False
        width *= LEVEL_RATIO


@kernel
def longest_edge(edges, y):
    longest = 0.0
    for e in range(edges.shape[0]):
        a, b = edges[e, 0], edges[e, 1]
        longest = max(longest, (y[a, 0] - y[b, 0]) ** 2 + (y[a, 1] - y[b, 1]) ** 2
                      + (y[a, 2] - y[b, 2]) ** 2)
    return math.sqrt(longest)


@kernel
def level_shrinks_at_most(points, now, then, width, allowed):
    """(whether the grid of cells ``width`` wide, widened to at most MAX_CELLS, has one cell;
    the width used, or -1 if some window's pairs may have shrunk by more than ``allowed``)."""
    origin, width, dims = level_grid(points, then, width)
    if width < 0.0:
        return False, -1.0
    cell_of = np.empty((points.shape[0], 3), np.int64)
    for k in range(points.shape[0]):
        for c in range(3):
            cell_of[k, c] = cell_coordinate(then[points[k], c], origin[c], width, dims[c])
    sums = cell_sums(points, now, then, origin, cell_of, dims)
    rotation, shift = window_motions(sums, dims)
    worst = worst_residual(points, now, then, origin, cell_of, dims, rotation, shift)
    one_cell = dims[0] * dims[1] * dims[2] == 1
    if not 2.0 * worst <= allowed:   # NaN too
        return one_cell, -1.0
    return one_cell, width


@kernel
def level_grid(points, then, width):
    """The grid of a level: (lowest corner, cell width, cells along x, y, z); width -1 if the
    positions are not finite."""
    low, high = np.full(3, np.inf), np.full(3, -np.inf)
    dims = np.ones(3, np.int64)
    for p in points:
        for c in range(3):
            if not abs(then[p, c]) < np.inf:   # min and max would pass over a NaN
                return low, -1.0, dims
            low[c], high[c] = min(low[c], then[p, c]), max(high[c], then[p, c])
    width = grid_cell_size(high - low, width, MAX_CELLS)   # doubled while there are too many
    for c in range(3):
        dims[c] = int((high[c] - low[c]) / width) + 1
    return low, width, dims


@kernel
def window_number(i, j, k, dims):
    """Window (i, j, k) holds cells i..i+1, j..j+1, k..k+1 (i from -1 to dims[0] - 1)."""
    return ((i + 1) * (dims[1] + 1) + j + 1) * (dims[2] + 1) + k + 1


@kernel
def cell_sums(points, now, then, origin, cell_of, dims):
    """Per cell: (count, sum y, sum x, sum x y^T) with both positions taken from the grid's
    origin (sums (C, 16))."""
    sums = np.zeros((dims[0] * dims[1] * dims[2], 16))
    for k in range(points.shape[0]):
        p = points[k]
        row = sums[(cell_of[k, 0] * dims[1] + cell_of[k, 1]) * dims[2] + cell_of[k, 2]]
        row[0] += 1.0
        for c in range(3):
            row[1 + c] += then[p, c] - origin[c]
            row[4 + c] += now[p, c] - origin[c]
        for r in range(3):
            for c in range(3):
                row[7 + 3 * r + c] += (now[p, r] - origin[r]) * (then[p, c] - origin[c])
    return sums


@kernel
def window_motions(sums, dims):
    """Each window's rigid motion (R, t), x ~ R y + t from the origin: the best fit (Kabsch)
    of the particles of its 2 x 2 x 2 cells (the identity for an empty window)."""
    windows = (dims[0] + 1) * (dims[1] + 1) * (dims[2] + 1)
    rotation = np.zeros((windows, 3, 3))
    shift = np.zeros((windows, 3))
    total = np.empty(16)
    covariance = np.empty((3, 3))
    for i in range(-1, dims[0]):
        for j in range(-1, dims[1]):
            for k in range(-1, dims[2]):
                for s in range(16):
                    total[s] = 0.0
                for a in range(max(i, 0), min(i + 2, dims[0])):
                    for b in range(max(j, 0), min(j + 2, dims[1])):
                        for c in range(max(k, 0), min(k + 2, dims[2])):
                            cell = (a * dims[1] + b) * dims[2] + c
                            for s in range(16):
                                total[s] += sums[cell, s]
                w = window_number(i, j, k, dims)
                count = total[0]
                if count > 0.0:
                    for r in range(3):
                        for c in range(3):   # sum (x - mean x)(y - mean y)^T
                            covariance[r, c] = (total[7 + 3 * r + c]
                                                - total[4 + r] * total[1 + c] / count)
                best_rotation(covariance if count > 0.0 else np.zeros((3, 3)), rotation[w])
                for r in range(3):
                    shift[w, r] = (total[4 + r] - rotation[w, r, 0] * total[1]
                                   - rotation[w, r, 1] * total[2]
                                   - rotation[w, r, 2] * total[3]) / max(count, 1.0)
    return rotation, shift


@kernel
def best_rotation(covariance, out):
    """Into ``out``, a rotation R that maps the positions then close to now: the best (Kabsch),
    as the unit quaternion q of largest q^T N q (Horn 1987; N from the cross-covariance
    sum (x - mean x)(y - mean y)^T): M = N + s I (s bounds N's most negative eigenvalue, so
    M >= 0) squared SQUARINGS times is a multiple of the projection on M's top eigenvectors,
    and its longest column one of them, however close the next eigenvalue comes (a strip of
    particles nearly on a line, whose turn about the line is weakly determined; the power
    method from one vector stalled there). The identity where there is nothing to fit (or NaN).
    The check measures the residual of whatever rotation this gives, so an inexact one costs
    tightness, not correctness, and it costs a fraction of an SVD."""
    sxx, sxy, sxz = covariance[0, 0], covariance[1, 0], covariance[2, 0]
    syx, syy, syz = covariance[0, 1], covariance[1, 1], covariance[2, 1]
    szx, szy, szz = covariance[0, 2], covariance[1, 2], covariance[2, 2]
    m = np.empty((4, 4))
    m[0, 0], m[0, 1], m[0, 2], m[0, 3] = sxx + syy + szz, syz - szy, szx - sxz, sxy - syx
    m[1, 1], m[1, 2], m[1, 3] = sxx - syy - szz, sxy + syx, szx + sxz
    m[2, 2], m[2, 3] = -sxx + syy - szz, syz + szy
    m[3, 3] = -sxx - syy + szz
    for r in range(4):
        for c in range(r):
            m[r, c] = m[c, r]
    shift = 0.0   # Gershgorin: no eigenvalue of N lies below -shift
    for r in range(4):
        shift = max(shift, abs(m[r, 0]) + abs(m[r, 1]) + abs(m[r, 2]) + abs(m[r, 3]))
    for r in range(4):
        m[r, r] += shift
    square = np.empty((4, 4))
    for _ in range(SQUARINGS):
        size = 0.0
        for r in range(4):
            for c in range(4):
                square[r, c] = (m[r, 0] * m[0, c] + m[r, 1] * m[1, c] + m[r, 2] * m[2, c]
                                + m[r, 3] * m[3, c])
                size += square[r, c] * square[r, c]
        size = math.sqrt(size)
        if not 0.0 < size < np.inf:   # nothing to fit, or NaN
            out[:, :] = np.eye(3)
            return
        for r in range(4):
            for c in range(4):
                m[r, c] = square[r, c] / size
    longest, column = -1.0, 0
    for c in range(4):
        length = m[0, c] ** 2 + m[1, c] ** 2 + m[2, c] ** 2 + m[3, c] ** 2
        if length > longest:
            longest, column = length, c
    size = math.sqrt(longest)
    w, x, y, z = m[0, column] / size, m[1, column] / size, m[2, column] / size, m[3, column] / size
    out[0, 0], out[0, 1], out[0, 2] = (w * w + x * x - y * y - z * z, 2.0 * (x * y - w * z),
                                       2.0 * (x * z + w * y))
    out[1, 0], out[1, 1], out[1, 2] = (2.0 * (x * y + w * z), w * w - x * x + y * y - z * z,
                                       2.0 * (y * z - w * x))
    out[2, 0], out[2, 1], out[2, 2] = (2.0 * (x * z - w * y), 2.0 * (y * z + w * x),
                                       w * w - x * x - y * y + z * z)


@kernel
def worst_residual(points, now, then, origin, cell_of, dims, rotation, shift):
    """The largest |x - (R y + t)| of any particle against the motion of any window that holds
    it (NaN if any is)."""
    worst = 0.0
    for k in range(points.shape[0]):
        p = points[k]
        y0, y1, y2 = then[p, 0] - origin[0], then[p, 1] - origin[1], then[p, 2] - origin[2]
        x0, x1, x2 = now[p, 0] - origin[0], now[p, 1] - origin[1], now[p, 2] - origin[2]
        for i in range(cell_of[k, 0] - 1, cell_of[k, 0] + 1):
            for j in range(cell_of[k, 1] - 1, cell_of[k, 1] + 1):
                for l in range(cell_of[k, 2] - 1, cell_of[k, 2] + 1):
                    w = window_number(i, j, l, dims)
                    r = rotation[w]
                    d0 = x0 - shift[w, 0] - r[0, 0] * y0 - r[0, 1] * y1 - r[0, 2] * y2
                    d1 = x1 - shift[w, 1] - r[1, 0] * y0 - r[1, 1] * y1 - r[1, 2] * y2
                    d2 = x2 - shift[w, 2] - r[2, 0] * y0 - r[2, 1] * y1 - r[2, 2] * y2
                    off = d0 * d0 + d1 * d1 + d2 * d2
                    if not off <= worst:   # NaN too
                        worst = off
                        if not off < np.inf:
                            return np.nan   # and kept: a later finite one must not replace it
    return math.sqrt(worst)
