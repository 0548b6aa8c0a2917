"""Broad phase of surface contact: the (point, triangle) and (edge, edge) pairs that may touch.

Every triangle's and edge's bounding box, grown by the search ``reach``, goes into a uniform grid
whose cells are a third as wide as the largest grown box (CELLS_PER_BOX), each box in the one
cell of its low corner (the ball grid of broadphase.py is sized from the largest ball instead).
A point looks for the boxes that hold it in the cells from which a box can reach it (its own and
up to 3 below it along each axis); an edge, for the boxes that overlap its own, likewise. Each
pair is met once. The grid is rebuilt from the positions on every call, a counting sort by
cell; the cost grows like the shapes' count, not their product.

Which pairs count: a point and a triangle, or two edges, of two bodies; or of one body that
collides with itself, leaving out a point and a triangle with a corner that is the point or its
neighbour along a surface edge, and two edges with ends that are the same or neighbours
(contact_shapes.neighbour_arrays says why).
Pairs come sorted (point, then triangle; lower edge, then higher), so the narrow phase sees them
in one canonical order however the grid is laid out.
"""
import math

import numpy as np

from ._jit import kernel
from .broadphase import MAX_CELLS_PER_PARTICLE, cell_coordinate, grid_cell_size
from .geometry import closest_on_segments, closest_on_triangle

GRID_CELLS = 65536    # cells a search's grid may have whatever the shapes' count (0.5 MB)
CELLS_PER_BOX = 3.0   # grid cells across the largest box: the searches of a 100 x 100 and a
                      # 25 x 25 cloth took 0.8 and 0.88 of their time with 1 cell at 2, 0.73
                      # and 0.82 at 3 (more are capped by MAX_CELLS_PER_PARTICLE there)


@kernel
def surface_pairs(model, x, beyond, self_beyond):
    """((K, 2) point-triangle pairs (particle, triangle row), (L, 2) edge-edge pairs (edge
    rows, lower first)) closer than their rest distance (the mean of their bodies' thickness)
    plus ``beyond`` (m), or ``self_beyond`` for pairs of one body."""
    triangles, edges = model.surface_triangles, model.surface_edges
    thickest = 0.0
    for b in range(model.body_thickness.shape[0]):
        thickest = max(thickest, model.body_thickness[b])
    reach = thickest + max(beyond, self_beyond)
    triangle_boxes = shape_boxes(x, triangles, reach)
    edge_boxes = shape_boxes(x, edges, reach)
    points = point_triangle_pairs(model, x, triangle_boxes, beyond, self_beyond)
    return points, edge_edge_pairs(model, x, edge_boxes, reach, beyond, self_beyond)


@kernel
def shape_boxes(x, shapes, reach):
    """(N, 6) boxes (low x, y, z, high x, y, z) of the shapes (rows of particle numbers), grown
    by ``reach`` on every side."""
    boxes = np.empty((shapes.shape[0], 6))
    for s in range(shapes.shape[0]):
        for c in range(3):
            low = high = x[shapes[s, 0], c]
            for k in range(1, shapes.shape[1]):
                value = x[shapes[s, k], c]
                low, high = min(low, value), max(high, value)
            boxes[s, c], boxes[s, 3 + c] = low - reach, high + reach
    return boxes


@kernel
def box_grid(boxes, least_cells):
    """A uniform grid of the boxes, each in the one cell that holds its low corner, with cells
    1 / CELLS_PER_BOX as wide as the largest box (wider where they would be more than
    MAX_CELLS_PER_PARTICLE a box and ``least_cells``):
    (origin, cell size, dims, cell_start, members, their boxes, the largest box size along
    x, y and z); cell (ix, iy, iz) is number (ix dims[1] + iy) dims[2] + iz and holds the
    boxes members[cell_start[c]:cell_start[c + 1]], ascending. A box then overlaps a region
    [low, high] only if its cell lies between those of low - the largest size and high, along
    each axis (``region_cells``), and each is met once. Why along each axis: a cloth lying
    flat has boxes as thin as the search's reach across it, and the region then reaches as
    few cells below it."""
    count = boxes.shape[0]
    origin, extent = np.zeros(3), np.zeros(3)
    largest = np.zeros(3)
    for c in range(3):
        low, high = np.inf, -np.inf
        for b in range(count):
            low, high = min(low, boxes[b, c]), max(high, boxes[b, 3 + c])
            largest[c] = max(largest[c], boxes[b, 3 + c] - boxes[b, c])
        if np.abs(low) < np.inf and np.abs(high) < np.inf:   # else (NaN, inf) one cell
            origin[c], extent[c] = low, high - low
        if not largest[c] < np.inf:
            largest[c] = 1.0
    # at least GRID_CELLS: a small mesh (cloth-balls's 1,800 edges) had its cells doubled
    # by the per-box cap once it draped in 3D, and searched 7% slower
    cell = grid_cell_size(extent, largest.max() / CELLS_PER_BOX,
                          max(MAX_CELLS_PER_PARTICLE * count, least_cells))
    dims = np.empty(3, np.int64)
    for c in range(3):
        dims[c] = int(extent[c] / cell) + 1
    home = np.empty(count, np.int64)
    cell_start = np.zeros(dims[0] * dims[1] * dims[2] + 1, np.int64)
    for b in range(count):
        home[b] = ((cell_coordinate(boxes[b, 0], origin[0], cell, dims[0]) * dims[1]
                    + cell_coordinate(boxes[b, 1], origin[1], cell, dims[1])) * dims[2]
                   + cell_coordinate(boxes[b, 2], origin[2], cell, dims[2]))
        cell_start[home[b] + 1] += 1
    for number in range(1, cell_start.shape[0]):
        cell_start[number] += cell_start[number - 1]
    cursor = cell_start[:-1].copy()
    members = np.empty(count, np.int64)
    for b in range(count):   # in box order: each cell's members ascend
        members[cursor[home[b]]] = b
        cursor[home[b]] += 1
    # the members' boxes in the same order: a query then reads them from contiguous memory
    member_boxes = np.empty((count, 6))
    for k in range(count):
        for c in range(6):
            member_boxes[k, c] = boxes[members[k], c]
    return origin, cell, dims, cell_start, members, member_boxes, largest


@kernel
def region_cells(low0, low1, low2, high0, high1, high2, origin, cell, dims, largest):
    """The first and last cell along x, y and z whose boxes (box_grid) may overlap the region
    [low, high] (``largest``: the largest box size along each axis)."""
    return (cell_coordinate(low0 - largest[0], origin[0], cell, dims[0]),
            cell_coordinate(high0, origin[0], cell, dims[0]),
            cell_coordinate(low1 - largest[1], origin[1], cell, dims[1]),
            cell_coordinate(high1, origin[1], cell, dims[1]),
            cell_coordinate(low2 - largest[2], origin[2], cell, dims[2]),
            cell_coordinate(high2, origin[2], cell, dims[2]))


@kernel
def point_triangle_pairs(model, x, boxes, beyond, self_beyond):
    """The (point, triangle) pairs whose grown triangle box holds the point (module doc)."""
    if model.surface_triangles.shape[0] == 0:
        return np.empty((0, 2), np.int64)
    grid = box_grid(boxes, GRID_CELLS)
    found = np.empty((model.surface_points.shape[0] + 64, 2), np.int64)
    count = collect_point_pairs(model, x, boxes, beyond, self_beyond, grid, found)
    if count > found.shape[0]:   # a crowded step: now the count is known
        found = np.empty((count, 2), np.int64)
        collect_point_pairs(model, x, boxes, beyond, self_beyond, grid, found)
    found = found[:count]
    # a point's triangles come cell by cell: sorted by (point, triangle)
    return found[np.argsort(found[:, 0] * model.surface_triangles.shape[0] + found[:, 1])]


@kernel
def collect_point_pairs(model, x, boxes, beyond, self_beyond, grid, found):
    """Count the pairs, writing them to ``found`` while it has room."""
    origin, cell, dims, cell_start, members, member_boxes, largest = grid
    triangles = model.surface_triangles
    corners = np.empty((3, 3))
    count = 0
    for p in model.surface_points:
        x0, x1, y0, y1, z0, z1 = region_cells(x[p, 0], x[p, 1], x[p, 2], x[p, 0], x[p, 1],
                                              x[p, 2], origin, cell, dims, largest)
        for ix in range(x0, x1 + 1):
            for iy in range(y0, y1 + 1):
                first = (ix * dims[1] + iy) * dims[2]
                for k in range(cell_start[first + z0], cell_start[first + z1 + 1]):
                    t = members[k]
                    if inside_box(member_boxes, k, x[p, 0], x[p, 1], x[p, 2]) \
                            and may_touch_triangle(model.particle_body,
                                                   model.body_self_collision,
                                                   model.neighbour_start, model.neighbours,
                                                   triangles, p, t) \
                            and point_triangle_distance(x, triangles, p, t, corners) \
                            < search_distance(model.particle_body, model.body_thickness, p,
                                              triangles[t, 0], beyond, self_beyond):
                        if count < found.shape[0]:
                            found[count, 0], found[count, 1] = p, t
                        count += 1
    return count


@kernel
def inside_box(boxes, b, px, py, pz):
    return (boxes[b, 0] <= px <= boxes[b, 3] and boxes[b, 1] <= py <= boxes[b, 4]
            and boxes[b, 2] <= pz <= boxes[b, 5])


@kernel
def may_touch_triangle(body, self_collision, start, neighbours, triangles, p, t):
    """Whether point p and triangle t form a pair: they lie on two bodies, or on one that
    collides with itself and p is neither a corner nor a neighbour of one."""
    if body[p] != body[triangles[t, 0]]:
        return True
    if not self_collision[body[p]]:
        return False
    for k in range(3):
        if p == triangles[t, k] or joined(start, neighbours, p, triangles[t, k]):
            return False
    return True


@kernel
def joined(start, neighbours, p, q):
    """Whether particles p and q share a surface edge."""
    for k in range(start[p], start[p + 1]):
        if neighbours[k] >= q:   # ascending
            return neighbours[k] == q
    return False


@kernel
def edge_edge_pairs(model, x, boxes, reach, beyond, self_beyond):
    """The (edge, edge) pairs, lower row first, that share no particle and whose boxes come
    within ``reach`` (each box is grown by it: one grown box against the other's own)."""
    edges = model.surface_edges
    if edges.shape[0] == 0:
        return np.empty((0, 2), np.int64)
    grid = box_grid(boxes, GRID_CELLS)
    keys = np.empty(edges.shape[0] + 64, np.int64)
    count = collect_edge_keys(model, x, boxes, reach, beyond, self_beyond, grid, keys)
    if count > keys.shape[0]:   # a crowded step: now the count is known
        keys = np.empty(count, np.int64)
        collect_edge_keys(model, x, boxes, reach, beyond, self_beyond, grid, keys)
    keys = np.sort(keys[:count])   # each pair is met once, in the grid's order
    pairs = np.empty((keys.shape[0], 2), np.int64)
    for k in range(keys.shape[0]):
        pairs[k, 0], pairs[k, 1] = keys[k] // edges.shape[0], keys[k] % edges.shape[0]
    return pairs


@kernel
def collect_edge_keys(model, x, boxes, reach, beyond, self_beyond, grid, keys):
    """Count the pairs (e, f) whose boxes overlap, writing e E + f to ``keys`` while it has
    room. Each pair is met from the edge whose box lies in the lower-numbered cell (the lower
    edge in one cell), so e searches only the cells from its own on (half the region: the
    search of the 100 x 100 cloth visited 2.6 million boxes to find 214,000 that overlap)."""
    origin, cell, dims, cell_start, members, member_boxes, largest = grid
    edges, body, self_collision = model.surface_edges, model.particle_body, model.body_self_collision
    start, neighbours = model.neighbour_start, model.neighbours
    own = np.empty((1, 6))
    count = 0
    for e in range(edges.shape[0]):
        for c in range(3):   # e's own box: its grown box shrunk back
            own[0, c], own[0, 3 + c] = boxes[e, c] + reach, boxes[e, 3 + c] - reach
        x0, x1, y0, y1, z0, z1 = region_cells(own[0, 0], own[0, 1], own[0, 2], own[0, 3],
                                              own[0, 4], own[0, 5], origin, cell, dims,
                                              largest)
        hx = cell_coordinate(boxes[e, 0], origin[0], cell, dims[0])   # e's cell (box_grid)
        hy = cell_coordinate(boxes[e, 1], origin[1], cell, dims[1])
        hz = cell_coordinate(boxes[e, 2], origin[2], cell, dims[2])
        after_home = cell_start[(hx * dims[1] + hy) * dims[2] + hz + 1]
        for ix in range(hx, x1 + 1):
            for iy in range(y0 if ix > hx else hy, y1 + 1):
                first = (ix * dims[1] + iy) * dims[2]
                low_z = z0 if ix > hx or iy > hy else hz
                for k in range(cell_start[first + low_z], cell_start[first + z1 + 1]):
                    f = members[k]
                    if (k >= after_home or f > e) and boxes_overlap(member_boxes, k, own) \
                            and may_touch_edge(body, self_collision, start, neighbours, edges,
                                               e, f) \
                            and edge_distance(x, edges, e, f) \
                            < search_distance(body, model.body_thickness, edges[e, 0],
                                              edges[f, 0], beyond, self_beyond):
                        if count < keys.shape[0]:
                            keys[count] = min(e, f) * edges.shape[0] + max(e, f)
                        count += 1
    return count


@kernel
def search_distance(body, thickness, p, q, beyond, self_beyond):
    """How far from each other particles p and q's shapes are searched (m): the distance
    their surfaces are kept apart (the mean of their bodies' thickness), plus ``beyond``, or
    ``self_beyond`` on one body."""
    rest = 0.5 * (thickness[body[p]] + thickness[body[q]])
    return rest + (self_beyond if body[p] == body[q] else beyond)


@kernel
def point_triangle_distance(x, triangles, p, t, corners):
    """The distance (m) from particle p to triangle t (``corners``: work space)."""
    for k in range(3):
        for c in range(3):
            corners[k, c] = x[triangles[t, k], c]
    w0, w1, w2 = closest_on_triangle(x[p], corners)
    total = 0.0
    for c in range(3):
        total += (x[p, c] - w0 * corners[0, c] - w1 * corners[1, c] - w2 * corners[2, c]) ** 2
    return math.sqrt(total)


@kernel
def edge_distance(x, edges, e, f):
    """The distance (m) between edges e and f."""
    a, b, c, d = edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]
    s, t = closest_on_segments(x[a], x[b], x[c], x[d])
    total = 0.0
    for k in range(3):
        total += ((1.0 - s) * x[a, k] + s * x[b, k] - (1.0 - t) * x[c, k] - t * x[d, k]) ** 2
    return math.sqrt(total)


@kernel
def boxes_overlap(boxes, f, own):
    for c in range(3):
        if boxes[f, c] > own[0, 3 + c] or own[0, c] > boxes[f, 3 + c]:
            return False
    return True


@kernel
def may_touch_edge(body, self_collision, start, neighbours, edges, e, f):
    """Whether edges e and f form a pair: they lie on two bodies, or on one that collides
    with itself and no end of one is an end of the other or its neighbour."""
    if body[edges[e, 0]] != body[edges[f, 0]]:
        return True
    if not self_collision[body[edges[e, 0]]]:
        return False
    for i in range(2):
        for j in range(2):
            p, q = edges[e, i], edges[f, j]
            if p == q or joined(start, neighbours, p, q):
                return False
    return True
