"""The lattice cells that carry a mesh body: every cell its surface passes through, and every cell
whose centre is inside it.

- The lattice: cubic cells of side ``spacing``, as many along each axis as cover the mesh's
  bounding box, centred on that box (a box whose sides are whole multiples of the spacing has
  its faces on lattice planes, and its lattice is the cube's).
- Surface cells (a conservative voxelization): a cell is kept when a triangle of the surface
  passes through its inside (shrunk by ``TOUCH`` x spacing, so that a face lying on a lattice
  plane, as a box's do, keeps the cells on its inner side only, which the winding number keeps),
  by the separating-axis test of a triangle and a box (Akenine-Möller 2001: the box's three
  axes, the triangle's normal, and the nine products of their edges); and the cell holding each
  vertex, where no kept cell does. Every vertex then lies in a kept cell, however thin the part it
  belongs to: a leg thinner than a cell still gets cells, and particles, of its own.
- Inside cells: a cell is kept when the generalized winding number of the surface at its centre
  (Jacobson et al. 2013, libigl's ``fast_winding_number``) is 1/2 or more in size: 1 inside a
  closed surface, 0 outside, and in between about a hole, so that open, overlapping and
  self-intersecting surfaces fill where a person would say they are solid. Its size, because a
  surface wound inside out has -1 inside.
- The particles are the corners of the kept cells, so every kept cell is full (all eight corners
  are particles), numbered in lattice order (x slowest, z fastest) as the cube's are.
"""
from typing import NamedTuple

import numpy as np

TOUCH = 1e-6          # of the spacing: a triangle this close to a cell touches it
PAIRS_PER_CHUNK = 1 << 21   # (triangle, cell) pairs tested at once, to bound the memory


class Grid(NamedTuple):
    origin: np.ndarray    # (3,) m: the corner of cell (0, 0, 0)
    spacing: float        # m
    cells: np.ndarray     # (3,) int64: cells along each axis

    def points(self) -> np.ndarray:
        """(3,) lattice points along each axis."""
        return self.cells + 1


class Filled(NamedTuple):
    grid: Grid
    kept: np.ndarray      # (cells) bool: the cells that carry the body
    index: np.ndarray     # (points) int64: particle number of each lattice point, or -1
    positions: np.ndarray  # (n, 3) m, in particle order


def grid_for(vertices: np.ndarray, spacing: float) -> Grid:
    """The cells covering the vertices' box, centred on it (a side within TOUCH of a whole number
    of spacings takes that number)."""
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    cells = np.maximum(np.ceil((high - low) / spacing - TOUCH), 1).astype(np.int64)
    origin = 0.5 * (low + high) - 0.5 * cells * spacing
    return Grid(origin, float(spacing), cells)


def box_points(vertices: np.ndarray, spacing: float) -> float:
    """Lattice points of the box (as a float: it may be astronomically many)."""
    return float(np.prod(grid_for(vertices, spacing).points().astype(float)))


def fill(vertices: np.ndarray, triangles: np.ndarray, spacing: float) -> Filled:
    """The kept cells of the surface (vertices, triangles) at ``spacing`` and their corners."""
    grid = grid_for(vertices, spacing)
    kept = surface_cells(vertices, triangles, grid) | inside_cells(vertices, triangles, grid)
    cell, found = locate(vertices, kept, grid)
    kept[tuple(cell[~found].T)] = True
    corner = np.zeros(tuple(grid.points()), bool)
    for a, b, c in np.ndindex(2, 2, 2):
        corner[a:a + kept.shape[0], b:b + kept.shape[1], c:c + kept.shape[2]] |= kept
    index = np.full(corner.shape, -1, np.int64)
    index[corner] = np.arange(np.count_nonzero(corner))
    positions = grid.origin + np.argwhere(corner) * grid.spacing
    return Filled(grid, kept, index, positions)


def inside_cells(vertices, triangles, grid: Grid) -> np.ndarray:
    """(cells) bool: the cells whose centre has a winding number of size 1/2 or more."""
    centres = grid.origin + (np.indices(tuple(grid.cells)).reshape(3, -1).T + 0.5) * grid.spacing
    return (np.abs(winding_numbers(vertices, triangles, centres)) >= 0.5).reshape(tuple(grid.cells))


def winding_numbers(vertices, triangles, points) -> np.ndarray:
    import igl

    if len(points) == 0:
        return np.zeros(0)
    return igl.fast_winding_number(np.ascontiguousarray(vertices, float),
                                   np.ascontiguousarray(triangles, np.int64),
                                   np.ascontiguousarray(points, float))


def surface_cells(vertices, triangles, grid: Grid) -> np.ndarray:
    """(cells) bool: the cells whose inside a triangle passes through (module doc)."""
    local = (vertices - grid.origin) / grid.spacing
    last = grid.cells - 1
    kept = np.zeros(tuple(grid.cells), bool)
    corners = local[triangles]                                   # (T, 3 corners, 3)
    low = np.clip(np.floor(corners.min(axis=1) - TOUCH).astype(np.int64), 0, last)
    high = np.clip(np.floor(corners.max(axis=1) + TOUCH).astype(np.int64), 0, last)
    span = high - low + 1
    count = np.prod(span, axis=1)
    start = 0
    while start < len(triangles):
        # as many triangles as keep this chunk's pairs within PAIRS_PER_CHUNK (one at least)
        stop = start + max(1, int(np.searchsorted(np.cumsum(count[start:]), PAIRS_PER_CHUNK)))
        rows = np.repeat(np.arange(start, stop), count[start:stop])
        first = np.repeat(np.cumsum(count[start:stop]) - count[start:stop], count[start:stop])
        offset = np.arange(len(rows)) - first                    # which cell of the triangle's box
        s = span[rows]
        cell = low[rows] + np.stack([offset // (s[:, 1] * s[:, 2]), offset // s[:, 2] % s[:, 1],
                                     offset % s[:, 2]], axis=1)
        touching = triangle_touches_box(corners[rows] - (cell + 0.5)[:, None, :], 0.5 - TOUCH)
        kept[tuple(cell[touching].T)] = True
        start = stop
    return kept


def triangle_touches_box(p: np.ndarray, half: float) -> np.ndarray:
    """(N,) bool: does the triangle (N, 3 corners, 3), relative to a cube's centre, overlap the
    cube of half-side ``half``? The box's own axes are the caller's (the candidate cells are
    those overlapping the triangle's bounding box); here the normal and the nine edge axes."""
    edges = [p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]]
    touching = np.ones(len(p), bool)
    normal = np.cross(edges[0], -edges[2])
    reach = half * np.abs(normal).sum(axis=1)
    touching &= np.abs(np.einsum("ij,ij->i", normal, p[:, 0])) <= reach
    for edge in edges:
        for axis in range(3):
            unit = np.zeros(3)
            unit[axis] = 1.0
            direction = np.cross(unit, edge)                     # (N, 3)
            projected = np.einsum("nkc,nc->nk", p, direction)
            reach = half * np.abs(direction).sum(axis=1)
            touching &= (projected.min(axis=1) <= reach) & (projected.max(axis=1) >= -reach)
    return touching


def full_cells(index: np.ndarray) -> np.ndarray:
    """(C, 3) lattice coordinates of the cells whose eight corners are all particles."""
    kept = index >= 0
    full = np.ones(tuple(n - 1 for n in index.shape), bool)
    for a, b, c in np.ndindex(2, 2, 2):
        full &= kept[a:a + full.shape[0], b:b + full.shape[1], c:c + full.shape[2]]
    return np.argwhere(full)


def locate(points: np.ndarray, kept: np.ndarray, grid: Grid):
    """((V, 3) cells, (V,) found): the kept cell holding each point, where there is one: its own
    cell, or where the point lies within TOUCH of a cell's side, a kept neighbour across it;
    where none is kept, the point's own cell (found False)."""
    local = (points - grid.origin) / grid.spacing
    last = grid.cells - 1
    own = np.clip(np.floor(local).astype(np.int64), 0, last)
    cell = own.copy()
    found = kept[tuple(own.T)]
    for step in np.ndindex(3, 3, 3):
        if found.all():
            break
        rows = np.flatnonzero(~found)
        other = np.clip(own[rows] + np.array(step) - 1, 0, last)
        near = np.all(np.abs(local[rows] - np.clip(local[rows], other, other + 1)) <= TOUCH,
                      axis=1) & kept[tuple(other.T)]
        cell[rows[near]] = other[near]
        found[rows[near]] = True
    return cell, found
