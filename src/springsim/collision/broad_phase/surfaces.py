"""The surfaces' broad phase: the (point, triangle) and (edge, edge) pairs that may touch.

Every triangle's and edge's bounding box, grown by the search ``reach``, goes into a uniform grid
whose cells are a third as wide as the largest grown box (CELLS_PER_BOX), each box in the one
cell of its low corner (grid.box_grid).
A point looks for the boxes that hold it in the cells from which a box can reach it (its own and
up to 3 below it along each axis); an edge, for the boxes that overlap its own, likewise. Each
pair is met once. The grid is rebuilt from the positions on every call, a counting sort by
cell; the cost grows like the shapes' count, not their product.

Which pairs count: a point and a triangle, or two edges, of two bodies; or of one body that
collides with itself, leaving out a point and a triangle with a corner that is the point or its
neighbour along a surface edge, and two edges with ends that are the same or neighbours
(shapes/surfaces.neighbour_arrays says why).
Pairs come sorted (point, then triangle; lower edge, then higher), so the narrow phase sees them
in one canonical order however the grid is laid out.
"""
import numpy as np

from ..._jit import kernel
from ..narrow_phase.stencils import edge_distance, point_triangle_distance
from .grid import cell_coordinate, GRID_CELLS, box_grid, region_cells


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
    edges, body = model.surface_edges, model.particle_body
    self_collision = model.body_self_collision
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
