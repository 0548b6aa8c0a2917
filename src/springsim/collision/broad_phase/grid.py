"""The uniform grid of the broad phase: cell arithmetic, and a grid of boxes.

Two searches sort what they look up into a grid rebuilt from the positions on every call (a
counting sort by cell, so the cost grows like the shapes' count, not their product): the balls'
grid of points (broad_phase/balls.py), with cells as wide as the largest ball, and ``box_grid``,
where each grown box of a surface shape lies in the cell of its low corner (surfaces.py,
collision/pair_lists/unfolded_sheet.py). Both cap their cells per member (MAX_CELLS_PER_PARTICLE): a particle far away
would otherwise make the grid, and its memory, huge.
"""
import numpy as np

from ..._jit import kernel


# The grid never has more cells than this many per particle (a particle far away would otherwise
# make the bounding box, and the cell array, huge); cells grow instead.
MAX_CELLS_PER_PARTICLE = 8


@kernel
def grid_cell_size(extent, cell_size, max_cells):
    """``cell_size``, doubled until the box of size ``extent`` has at most ``max_cells`` cells
    (a particle far away would otherwise make the grid, and its memory, huge)."""
    if not cell_size > 0.0:
        cell_size = 1.0
    while ((extent[0] / cell_size + 1.0) * (extent[1] / cell_size + 1.0)
           * (extent[2] / cell_size + 1.0) > max_cells):
        cell_size *= 2.0
    return cell_size


@kernel
def cell_number(x0, x1, x2, origin, cell_size, dims):
    ix = cell_coordinate(x0, origin[0], cell_size, dims[0])
    iy = cell_coordinate(x1, origin[1], cell_size, dims[1])
    iz = cell_coordinate(x2, origin[2], cell_size, dims[2])
    return (ix * dims[1] + iy) * dims[2] + iz


@kernel
def cell_coordinate(value, origin, cell_size, dim):
    """The cell index of ``value`` along one axis, clamped to the grid (NaN goes to 0)."""
    q = (value - origin) / cell_size
    if not q >= 0.0:
        return 0
    if q >= dim:
        return dim - 1
    return int(q)


@kernel
def cell_range(centre, reach, origin, cell_size, dim):
    """First and last cell along one axis that [centre - reach, centre + reach] overlaps.

    The reach is padded by a millionth so that rounding never leaves out a particle lying on
    its edge; the distance test decides, so searching a little further changes no result.
    """
    padded = reach * (1.0 + 1e-6)
    return (cell_coordinate(centre - padded, origin, cell_size, dim),
            cell_coordinate(centre + padded, origin, cell_size, dim))


GRID_CELLS = 65536    # cells a search's grid may have whatever the shapes' count (0.5 MB)


CELLS_PER_BOX = 3.0   # grid cells across the largest box (the fastest search: benchmarks/)


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
