"""Springs in runs: the layout that lets the spring loop run as SIMD code.

A lattice body's springs come in families that share the offset between their two particle
numbers: in a cube of N per edge, particle p is joined to p + 1, p + N, p + N^2, p + N + 1, ...
A *run* is a stretch of one family with one parameter group, the springs
    (first + i, first + i + offset),   i = 0 .. count - 1.
Along a run both ends of the springs walk two contiguous stretches of memory, so the force loop
needs no gather or scatter and the compiler vectorizes it (benchmarks/spring_loop.py times it
against the plain loop, the copies to and from columns included). A place in a run
with no spring, such as the end of a lattice row, is a *hole*: it has a negative rest length and
gives no force. Springs that fit in no run stay in a plain list (``loose_springs``).

The kernels work on *columns*: positions, velocities and forces as nine rows of length P
(x, y, z, vx, vy, vz, fx, fy, fz), the layout SIMD loads want, plus three rows of scratch.

Threads: the particles are cut into ``partition_count`` fixed partitions of at least the
model's ``spring_partition`` particles (ModelArrays; PARTITION unless a Simulation asks for
another: one partition for fewer than twice that), each owning its rows of the columns. The
partitions, not the threads, fix the order of every sum; a small partition makes a small model
take the same paths as a large one (tests/test_threads.py). A partition adds the forces of the
springs whose first end it owns to both ends, except the second ends that lie in a later
partition; then each partition adds those springs' forces to its own second ends, computing
them again. No row is written by two partitions and every row sums its terms in the same order
whatever the number of threads, so results are bit-identical for any count. The springs
computed twice are those within the largest offset of a partition's start (2 N^2 in a cube of
N per edge, its bend springs): on the 100^3 cube about 10% of them. A partition smaller than the
largest offset is still exact: a spring's second end may lie any number of partitions later.
"""
from typing import NamedTuple

import numpy as np
from numba import prange

from ._jit import inline_kernel, kernel
from .errors import require
from .springs import spring_force_factor

MAX_GAP = 32        # a longer gap between neighbours of one family starts a new run
MIN_RUN = 8         # shorter runs cost more in loop overhead than they save: loose springs
TILE = 2048         # particles per tile: all runs cross one tile while its columns are in cache
COLUMNS = 12        # rows of ``columns``: x, y, z, vx, vy, vz, fx, fy, fz, 3 rows of scratch
PARTITION = 65536   # particles per partition of the force loop, at least, unless the model's
                    # spring_partition says otherwise (module doc)
LARGEST_PARTITION = 2 ** 62   # any larger is one partition whatever the model; an int64 holds it


def build_spring_runs(springs: np.ndarray, group: np.ndarray, rest_length: np.ndarray) -> dict:
    """Runs of the springs (S, 2), keyed as in ModelArrays: ``spring_runs`` (R, 5) rows of
    (first, offset, count, start, group), ``run_rest_length`` (run r's springs are its entries
    start .. start + count - 1; holes negative) and ``loose_springs`` (spring numbers)."""
    if len(springs) == 0:
        return {"spring_runs": np.empty((0, 5), np.int64), "run_rest_length": np.empty(0),
                "loose_springs": np.empty(0, np.uint32)}
    a = np.minimum(springs[:, 0], springs[:, 1]).astype(np.int64)
    offset = np.abs(springs[:, 1].astype(np.int64) - springs[:, 0].astype(np.int64))
    order = np.lexsort((a, group, offset))
    a, offset, group = a[order], offset[order], group[order]
    same_family = (np.diff(offset) == 0) & (np.diff(group) == 0)
    # a second spring on the same pair would need the same place in a run: it stays loose
    repeated = np.r_[False, same_family & (np.diff(a) == 0)]
    loose = order[repeated]
    order, a, offset, group = order[~repeated], a[~repeated], offset[~repeated], group[~repeated]
    new_segment = np.r_[True, (np.diff(offset) != 0) | (np.diff(group) != 0)
                        | (np.diff(a) > MAX_GAP)]
    segment = np.cumsum(new_segment) - 1
    starts = np.flatnonzero(new_segment)
    stops = np.r_[starts[1:], len(a)]
    is_run = stops - starts >= MIN_RUN
    run_number = np.cumsum(is_run) - 1
    starts, stops = starts[is_run], stops[is_run]

    first = a[starts]
    count = a[stops - 1] - first + 1
    start = np.cumsum(count) - count
    runs = np.stack([first, offset[starts], count, start, group[starts].astype(np.int64)], axis=1)
    member = is_run[segment]
    run = run_number[segment[member]]
    run_rest_length = np.full(int(count.sum()), -1.0)
    run_rest_length[start[run] + a[member] - first[run]] = rest_length[order[member]]
    loose = np.r_[loose, order[~member]]
    return {"spring_runs": runs.reshape(-1, 5).astype(np.int64), "run_rest_length": run_rest_length,
            "loose_springs": np.sort(loose).astype(np.uint32)}   # unsigned: no wrap-around checks


class RunLayout(NamedTuple):
    """Springs in runs whatever their parameters: ``runs`` (R, 5) as build_spring_runs gives
    them (their group column 0), the spring at each entry (-1: a hole) and the springs in no
    run. For kernels that take each spring's parameters by its number, so that springs of
    different constants share a run: a cloth's material gives its border springs other
    constants than its inner ones (and rounding splits those), which cut the model's own runs
    of one group into short pieces."""

    runs: np.ndarray
    entry_spring: np.ndarray
    loose: np.ndarray


def run_layout(a: np.ndarray, b: np.ndarray) -> RunLayout:
    """The runs of springs (a, b), whatever their parameters (one group)."""
    numbers = np.arange(len(a), dtype=float)   # carried through the runs as their "rest length"
    runs = build_spring_runs(np.stack([a, b], axis=1), np.zeros(len(a), np.int64), numbers)
    return RunLayout(runs["spring_runs"], runs["run_rest_length"].astype(np.int64),
                     runs["loose_springs"].astype(np.int64))


def checked_partition(partition) -> int:
    """``partition`` as a model's ``spring_partition`` (module doc), refused in one line unless
    it is a whole number of particles from 1 to 2^62."""
    require(isinstance(partition, (int, np.integer)) and not isinstance(partition, bool)
            and 1 <= partition <= LARGEST_PARTITION, "spring_partition", partition,
            f"must be a whole number of particles from 1 to 2^62 (default {PARTITION})")
    return int(partition)


@kernel
def partition_count(particles, partition=PARTITION):
    """The number of partitions of the force loop (module doc): fixed by the particle count and
    the model's ``spring_partition`` (PARTITION unless given)."""
    return max(1, particles // partition)


@inline_kernel
def to_columns(x, v, columns):
    """Positions and velocities into rows 0-5 of the columns, and zero forces into rows 6-8.
    (Indexed in two dimensions: with the rows as separate views, Numba's threaded version of
    this loop wrote zeros everywhere.)"""
    for i in prange(x.shape[0]):
        for c in range(3):
            columns[c, i] = x[i, c]
            columns[3 + c, i] = v[i, c]
            columns[6 + c, i] = 0.0


@inline_kernel
def from_columns(columns, force):
    """force = the force rows (6-8) of the columns."""
    fx, fy, fz = columns[6], columns[7], columns[8]
    for i in prange(force.shape[0]):
        force[i, 0], force[i, 1], force[i, 2] = fx[i], fy[i], fz[i]


@inline_kernel
def add_run_forces(model, columns):
    """Add the force of every spring in a run to the force rows of the columns, partition by
    partition (module doc) and within one tile by tile."""
    # as locals: a threaded loop takes what it reads as arguments, and the model's nested
    # tables (term_tables) cannot be one
    runs, rest_length = model.spring_runs, model.run_rest_length
    group_ks, group_kd = model.group_ks, model.group_kd
    particles = columns.shape[1]
    partitions = partition_count(particles, model.spring_partition)
    for k in prange(partitions):
        start, stop = k * particles // partitions, (k + 1) * particles // partitions
        for tile in range(start, stop, TILE):
            tile_stop = min(tile + TILE, stop)
            for r in range(runs.shape[0]):
                first, offset, count = runs[r, 0], runs[r, 1], runs[r, 2]
                # the part of the run whose first ends lie in this tile
                low, high = max(first, tile), min(first + count, tile_stop)
                if low < high:
                    entries = rest_length[runs[r, 3] + low - first:runs[r, 3] + high - first]
                    group = runs[r, 4]
                    add_stretch_forces(columns, low, low + offset, high - low, entries,
                                       group_ks[group], group_kd[group], stop)
    for k in prange(1, partitions):
        start, stop = k * particles // partitions, (k + 1) * particles // partitions
        for r in range(runs.shape[0]):
            first, offset, count = runs[r, 0], runs[r, 1], runs[r, 2]
            # the springs from an earlier partition whose second ends lie in this one
            low, high = max(first, start - offset), min(first + count, start, stop - offset)
            if low < high:
                entries = rest_length[runs[r, 3] + low - first:runs[r, 3] + high - first]
                group = runs[r, 4]
                add_crossing_forces(columns, low, low + offset, high - low, entries,
                                    group_ks[group], group_kd[group])


@inline_kernel
def add_stretch_forces(columns, a, b, count, rest_length, ks, kd, stop):
    """Springs (a + i, b + i) for i < count: each row read at a and at b as a contiguous slice;
    the second ends at or past ``stop`` (another partition's) are left out."""
    # scratch in the rows of the first ends: this partition's own
    fx, fy, fz = columns[9, a:a + count], columns[10, a:a + count], columns[11, a:a + count]
    stretch_forces(columns, a, b, count, rest_length, ks, kd, fx, fy, fz)
    fx_a, fy_a, fz_a = columns[6, a:a + count], columns[7, a:a + count], columns[8, a:a + count]
    for i in range(count):
        fx_a[i] += fx[i]
        fy_a[i] += fy[i]
        fz_a[i] += fz[i]
    subtract_from_second_ends(columns, b, max(0, min(count, stop - b)), fx, fy, fz)


@inline_kernel
def add_crossing_forces(columns, a, b, count, rest_length, ks, kd):
    """Springs (a + i, b + i) for i < count: the force on the second ends alone."""
    # scratch in the rows of the second ends: this partition's own
    fx, fy, fz = columns[9, b:b + count], columns[10, b:b + count], columns[11, b:b + count]
    stretch_forces(columns, a, b, count, rest_length, ks, kd, fx, fy, fz)
    subtract_from_second_ends(columns, b, count, fx, fy, fz)


@inline_kernel
def stretch_forces(columns, a, b, count, rest_length, ks, kd, fx, fy, fz):
    """(fx, fy, fz)[i] = the force on a + i of spring (a + i, b + i), i < count."""
    x_a, y_a, z_a = columns[0, a:a + count], columns[1, a:a + count], columns[2, a:a + count]
    x_b, y_b, z_b = columns[0, b:b + count], columns[1, b:b + count], columns[2, b:b + count]
    vx_a, vy_a, vz_a = columns[3, a:a + count], columns[4, a:a + count], columns[5, a:a + count]
    vx_b, vy_b, vz_b = columns[3, b:b + count], columns[4, b:b + count], columns[5, b:b + count]
    for i in range(count):
        dx, dy, dz = x_a[i] - x_b[i], y_a[i] - y_b[i], z_a[i] - z_b[i]
        factor = spring_force_factor(dx, dy, dz, vx_a[i] - vx_b[i], vy_a[i] - vy_b[i],
                                     vz_a[i] - vz_b[i], rest_length[i], ks, kd)
        if rest_length[i] >= 0.0:
            fx[i], fy[i], fz[i] = factor * dx, factor * dy, factor * dz
        else:   # a hole: no spring, so no force (not even NaN from a non-finite end)
            fx[i], fy[i], fz[i] = 0.0, 0.0, 0.0


@inline_kernel
def subtract_from_second_ends(columns, b, count, fx, fy, fz):
    """Force rows at b + i -= (fx, fy, fz)[i], i < count: in a loop of its own, since b + i may
    be a + j of another i, which the loop over the springs could not vectorize across."""
    fx_b, fy_b, fz_b = columns[6, b:b + count], columns[7, b:b + count], columns[8, b:b + count]
    for i in range(count):
        fx_b[i] -= fx[i]
        fy_b[i] -= fy[i]
        fz_b[i] -= fz[i]
