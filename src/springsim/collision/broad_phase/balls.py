"""The balls' broad phase: the overlapping (ball, particle) pairs, found without testing every
pair. (The surfaces' pairs are surfaces.py's; both feed the post-step pass, collision/pipeline.py,
and the solve's contact set, contact_sets/solve.py.)

A contact is a pair (a, b) where a is a ball, b any other particle (a ball or a point) and
|x_a - x_b| < r_a + r_b. A ball-ball contact is listed once, from the lower-numbered ball. Pairs
come in one canonical order, by ball and then by partner (both ascending particle numbers),
whichever method found them, so that both methods give bit-identical simulations.

- ``brute_force_pairs`` tests every ball against every particle: the cheapest for a few balls
  (cloth-balls tests 4 x 629).
- ``grid_pairs`` sorts the particles into uniform grids (a counting sort by cell, rebuilt every
  step) with cells as wide as the largest ball, one grid for the points (particles of radius 0:
  cloth and cube particles) and one for the balls, and tests each ball only against the members of
  the cells it can reach: a point within its radius (at most 2 x 2 x 2 cells), another ball within
  the sum of both radii (at most 3 x 3 x 3 cells). The cost grows like particles plus balls, not
  like their product.
"""
import numpy as np

from ..._jit import kernel
from .grid import build_grid, cell_range


# Above this many ball-particle tests a step, the grid is cheaper than testing every pair.
BRUTE_FORCE_PAIR_LIMIT = 20_000


@kernel
def find_contacts(x, radius, balls, ball_slot):
    """(K, 2) contact pairs (ball, partner) in canonical order, by whichever method is cheaper."""
    if balls.shape[0] * x.shape[0] <= BRUTE_FORCE_PAIR_LIMIT:
        return brute_force_pairs(x, radius, balls, ball_slot)
    return grid_pairs(x, radius, balls, ball_slot)


@kernel
def brute_force_pairs(x, radius, balls, ball_slot):
    """Every contact, by testing every ball against every particle."""
    capacity = first_capacity(balls)
    while True:
        owner, partner = np.empty(capacity, np.int64), np.empty(capacity, np.int64)
        count = 0
        for a in balls:
            for b in range(x.shape[0]):
                if is_partner(ball_slot, a, b) and overlaps(x, radius, a, b):
                    if count < capacity:
                        owner[count], partner[count] = a, b
                    count += 1
        if count <= capacity:
            return as_pairs(owner, partner, count)
        capacity = count  # the buffers were too small: now the count is known


@kernel
def grid_pairs(x, radius, balls, ball_slot):
    """Every contact, by testing each ball against the particles of the grid cells it reaches.

    Points and balls go in two grids: a ball reaches a point within its own radius, but another
    ball within the sum of both radii, so each grid is searched no further than it needs.
    """
    largest_radius, point_grid, ball_grid = build_grids(x, radius, balls, ball_slot)
    capacity = first_capacity(balls)
    while True:
        owner, partner = np.empty(capacity, np.int64), np.empty(capacity, np.int64)
        count = 0
        for a in balls:
            first = count
            count = collect_partners(x, radius, point_grid, a, radius[a], -1, partner, count)
            # a ball-ball pair belongs to the lower-numbered ball
            count = collect_partners(x, radius, ball_grid, a, radius[a] + largest_radius, a,
                                     partner, count)
            owner[first:min(count, capacity)] = a
            # cells are visited in space order; sort to the canonical (particle number) order
            partner[first:min(count, capacity)].sort()
        if count <= capacity:
            return as_pairs(owner, partner, count)
        capacity = count  # the buffers were too small: now the count is known


@kernel
def first_capacity(balls):
    """Room for the pairs on the first try: enough for a ball wrapped in cloth (a few dozen
    contacts); a crowded step that needs more counts its pairs and tries once more."""
    return 64 * balls.shape[0] + 64


@kernel
def build_grids(x, radius, balls, ball_slot):
    """The largest ball radius, and grids of the points and of the balls with cells as wide as
    the largest ball."""
    largest_radius = 0.0
    for a in balls:
        largest_radius = max(largest_radius, radius[a])
    cell_size = 2.0 * largest_radius
    point_grid = build_grid(x, np.flatnonzero(ball_slot < 0), cell_size)
    ball_grid = build_grid(x, balls, cell_size)
    return largest_radius, point_grid, ball_grid


@kernel
def search_size(x, radius, balls, ball_slot):
    """How many distance tests grid_pairs makes (its cost, for tests and tuning)."""
    largest_radius, point_grid, ball_grid = build_grids(x, radius, balls, ball_slot)
    tests = 0
    for a in balls:
        tests += population(x, point_grid, a, radius[a])
        tests += population(x, ball_grid, a, radius[a] + largest_radius)
    return tests


@kernel
def population(x, grid, a, reach):
    """How many grid members lie in the cells within ``reach`` of particle a."""
    origin, cell_size, dims, cell_start, members, member_x = grid
    x_low, x_high = cell_range(x[a, 0], reach, origin[0], cell_size, dims[0])
    y_low, y_high = cell_range(x[a, 1], reach, origin[1], cell_size, dims[1])
    z_low, z_high = cell_range(x[a, 2], reach, origin[2], cell_size, dims[2])
    count = 0
    for ix in range(x_low, x_high + 1):
        for iy in range(y_low, y_high + 1):
            first = (ix * dims[1] + iy) * dims[2]
            count += cell_start[first + z_high + 1] - cell_start[first + z_low]
    return count


@kernel
def collect_partners(x, radius, grid, a, reach, after, partner, count):
    """Append to ``partner`` (while it has room) the grid's particles numbered above ``after``
    that touch ball a, searching the cells within ``reach`` of it; return the new count, room or
    not."""
    origin, cell_size, dims, cell_start, members, member_x = grid
    x_low, x_high = cell_range(x[a, 0], reach, origin[0], cell_size, dims[0])
    y_low, y_high = cell_range(x[a, 1], reach, origin[1], cell_size, dims[1])
    z_low, z_high = cell_range(x[a, 2], reach, origin[2], cell_size, dims[2])
    xa, ya, za, ra = x[a, 0], x[a, 1], x[a, 2], radius[a]
    for ix in range(x_low, x_high + 1):
        for iy in range(y_low, y_high + 1):
            first = (ix * dims[1] + iy) * dims[2]
            for k in range(cell_start[first + z_low], cell_start[first + z_high + 1]):
                dx, dy, dz = xa - member_x[k, 0], ya - member_x[k, 1], za - member_x[k, 2]
                b = members[k]
                contact = ra + radius[b]
                if dx * dx + dy * dy + dz * dz < contact * contact and b > after:
                    if count < partner.shape[0]:
                        partner[count] = b
                    count += 1
    return count


@kernel
def as_pairs(owner, partner, count):
    pairs = np.empty((count, 2), np.int64)
    for k in range(count):
        pairs[k, 0], pairs[k, 1] = owner[k], partner[k]
    return pairs


@kernel
def is_partner(ball_slot, a, b):
    """Whether ball a owns the pair (a, b): b is another particle, and not a lower ball."""
    return b != a and (ball_slot[b] < 0 or b > a)


@kernel
def overlaps(x, radius, a, b):
    dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
    reach = radius[a] + radius[b]
    return dx * dx + dy * dy + dz * dz < reach * reach
