"""The uniform grid of the broad phase: its cell arithmetic, its counting sort, and its two
layouts, particles as points (PointGrid) and shapes as boxes (BoxGrid).

Two searches sort what they look up into a grid rebuilt from the positions on every call (a
counting sort by cell, so the cost grows like the shapes' count, not their product): the balls'
grid of points (broad_phase/balls.py), with cells as wide as the largest ball, and ``box_grid``,
where each grown box of a surface shape lies in the cell of its low corner (surfaces.py,
collision/pair_lists/unfolded_sheet.py). Both cap their cells per member (MAX_CELLS_PER_PARTICLE):
a particle far away would otherwise make the grid, and its memory, huge.

Why two layouts of one grid rather than every shape as a box: the balls' search runs every step
over every particle (a cloth's thousands of points) and reads their positions alone; stored as
boxes, each point would be six numbers written and read every step instead of three.
"""
from typing import NamedTuple

import numpy as np

from ..._jit import kernel


class PointGrid(NamedTuple):
    """Particles sorted by cell (``build_grid``)."""

    origin: np.ndarray      # (3,) m: the low corner of cell (0, 0, 0)
    cell_size: float        # m
    dims: np.ndarray        # (3,) int64: cells along x, y and z
    cell_start: np.ndarray  # (C + 1,) int64: cell c holds members[cell_start[c]:cell_start[c + 1]]
    members: np.ndarray     # (N,) int64: particle numbers, ascending within each cell
    member_x: np.ndarray    # (N, 3) m: their positions, in the same order


class BoxGrid(NamedTuple):
    """Boxes sorted by the cell of their low corner (``box_grid``)."""

    origin: np.ndarray        # (3,) m: the low corner of cell (0, 0, 0)
    cell_size: float          # m
    dims: np.ndarray          # (3,) int64: cells along x, y and z
    cell_start: np.ndarray    # (C + 1,) int64: cell c holds members[cell_start[c]:...[c + 1]]
    members: np.ndarray       # (N,) int64: box numbers, ascending within each cell
    member_boxes: np.ndarray  # (N, 6) m: their boxes (low x, y, z, high x, y, z), in that order
    largest: np.ndarray       # (3,) m: the largest box size along x, y and z


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
    a BoxGrid; cell (ix, iy, iz) is number (ix dims[1] + iy) dims[2] + iz and holds the boxes
    members[cell_start[c]:cell_start[c + 1]], ascending. A box then overlaps a region
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
    # at least ``least_cells``: the per-box cap alone doubles a small mesh's cells once it drapes
    # in 3D, and its search slows down
    cell = grid_cell_size(extent, largest.max() / CELLS_PER_BOX,
                          max(MAX_CELLS_PER_PARTICLE * count, least_cells))
    dims = np.empty(3, np.int64)
    for c in range(3):
        dims[c] = int(extent[c] / cell) + 1
    home = np.empty(count, np.int64)
    for b in range(count):
        home[b] = cell_number(boxes[b, 0], boxes[b, 1], boxes[b, 2], origin, cell, dims)
    cell_start, members = sorted_by_cell(home, dims[0] * dims[1] * dims[2])
    # the members' boxes in the same order: a query then reads them from contiguous memory
    member_boxes = np.empty((count, 6))
    for k in range(count):
        for c in range(6):
            member_boxes[k, c] = boxes[members[k], c]
    return BoxGrid(origin, cell, dims, cell_start, members, member_boxes, largest)


@kernel
def sorted_by_cell(cell_of, cell_count):
    """(cell_start, order): a counting sort of items by their cell ``cell_of``; cell c holds
    the items order[cell_start[c]:cell_start[c + 1]], in their own order (stable), so that each
    cell's members ascend. Linear in the items and cells: the grids are rebuilt every call."""
    cell_start = np.zeros(cell_count + 1, np.int64)
    for k in range(cell_of.shape[0]):
        cell_start[cell_of[k] + 1] += 1
    for cell in range(1, cell_start.shape[0]):
        cell_start[cell] += cell_start[cell - 1]
    cursor = cell_start[:-1].copy()
    order = np.empty(cell_of.shape[0], np.int64)
    for k in range(cell_of.shape[0]):
        order[cursor[cell_of[k]]] = k
        cursor[cell_of[k]] += 1
    return cell_start, order


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
def build_grid(x, members, cell_size):
    """A uniform grid of the particles ``members`` (a PointGrid).

    Cell (ix, iy, iz) is number ``(ix * dims[1] + iy) * dims[2] + iz``; its particles are
    ``members[cell_start[c]:cell_start[c + 1]]`` (ascending), with their positions alongside so
    that a search reads memory in order. Consecutive z cells are consecutive in memory, so a
    search reads a whole run of z cells at once.
    """
    count = members.shape[0]
    origin, extent = bounding_box(x, members)
    cell_size = grid_cell_size(extent, cell_size, MAX_CELLS_PER_PARTICLE * count + 64)
    dims = np.empty(3, np.int64)
    for c in range(3):
        dims[c] = int(extent[c] / cell_size) + 1
    cell_of = np.empty(count, np.int64)
    for k in range(count):
        i = members[k]
        cell_of[k] = cell_number(x[i, 0], x[i, 1], x[i, 2], origin, cell_size, dims)
    cell_start, order = sorted_by_cell(cell_of, dims[0] * dims[1] * dims[2])
    sorted_members = np.empty(count, np.int64)
    sorted_x = np.empty((count, 3))
    for slot in range(count):
        i = members[order[slot]]
        sorted_members[slot] = i
        sorted_x[slot, 0], sorted_x[slot, 1], sorted_x[slot, 2] = x[i, 0], x[i, 1], x[i, 2]
    return PointGrid(origin, cell_size, dims, cell_start, sorted_members, sorted_x)


@kernel
def bounding_box(x, members):
    """Lowest corner and size (m) of the box around the members' positions.

    NaN positions are left out (every comparison with NaN is false). If a position is infinite
    the box is too: then the box collapses to a point and the grid to one cell, which stays exact
    (every member is tested) for the one step before the divergence check stops the simulation.
    """
    x_low = y_low = z_low = np.inf
    x_high = y_high = z_high = -np.inf
    for i in members:
        if x[i, 0] < x_low:
            x_low = x[i, 0]
        if x[i, 0] > x_high:
            x_high = x[i, 0]
        if x[i, 1] < y_low:
            y_low = x[i, 1]
        if x[i, 1] > y_high:
            y_high = x[i, 1]
        if x[i, 2] < z_low:
            z_low = x[i, 2]
        if x[i, 2] > z_high:
            z_high = x[i, 2]
    origin = np.array([x_low, y_low, z_low])
    extent = np.array([x_high - x_low, y_high - y_low, z_high - z_low])
    for c in range(3):
        if not (np.abs(origin[c]) < np.inf and extent[c] < np.inf):
            origin[c] = extent[c] = 0.0
    return origin, extent
