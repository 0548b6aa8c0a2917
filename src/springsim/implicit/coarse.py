"""A coarse space for the conjugate-gradient solve: the two-level preconditioner.

Why: block Jacobi (cg.py) moves information one spring per iteration, so a load that must cross
a stiff body in one step takes as many iterations as the body is wide, several times over. A
50 x 50 cape whose shoulders move took 500 a step (benchmarks/preconditioner.py). The
cure is a coarse space: the particles are grouped into aggregates of a few neighbours along the
springs (smoothed-aggregation AMG's first phase, Vanek, Mandel and Brezina 1996), and every
aggregate moves as one in the three directions. The preconditioner is additive,

    z = S D^-1 r + S P A_c^-1 P^T S r,   A_c = P^T (S A S + H) P,

D the diagonal blocks, S the constraints' filter (constraints.filtered), P the aggregates'
piecewise-constant prolongation, H = (I - S) times each constrained particle's own diagonal
scale. Additive, so it is symmetric positive definite whatever A is and costs no products with
A beyond conjugate gradients' own. A solve turns to it only after cg.TWO_LEVEL_AFTER
iterations without converging: building A_c and its factor costs about ten iterations, which an
easy solve need not pay. A_c sees the constraints: a pinned particle holds its
aggregate, a contact holds it along the normal (without H an aggregate of contacts that share a
tilted normal would make A_c singular along it).

A_c is small and banded (a model whose A_c would cost more than MAX_FACTOR_FLOPS to factor
is aggregated again, from the aggregates' graph): the aggregates are numbered in reverse
Cuthill-McKee order, and its Cholesky factor is computed inside the band, in plain loops (the
same bits whatever the number of threads; LAPACK's threaded factorization need not give them).
"""
from typing import NamedTuple

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import reverse_cuthill_mckee

from .._jit import inline_kernel, kernel
from .constraints import FREE, filtered

MAX_FACTOR_FLOPS = 2e7   # a coarse matrix dearer to factor than this is aggregated again
MIN_PARTICLES = 1000     # a smaller model solves as fast without (benchmarks/preconditioner.py)


class CoarseSpace(NamedTuple):
    """Each particle's aggregate and the coarse matrix's shape (count 0: no coarse space)."""

    aggregate: np.ndarray   # (P,) int64: each particle's aggregate, -1 for one on no spring
    count: int              # aggregates
    bandwidth: int          # the largest |I - J| of two coupled aggregates


@kernel
def no_coarse_space(particles):
    """The space of a solve that stays block Jacobi (no aggregates)."""
    return CoarseSpace(np.full(particles, -1, np.int64), 0, 0)


def build_coarse_space(particles: int, springs: np.ndarray, near: np.ndarray) -> CoarseSpace:
    """The aggregates of a model's particles (module doc), grown along the springs that
    ``near`` marks (a cloth's structural and shear springs: its bend springs would make
    aggregates twice as wide, which the measured solves liked less), numbered for a narrow
    band of the coarse matrix, whose couplings are all ``springs`` (S, 2)."""
    springs = np.asarray(springs, np.int64).reshape(-1, 2)
    if particles < MIN_PARTICLES or not near.any():
        return no_coarse_space(particles)
    aggregate = aggregates(_adjacency(particles, springs[near]))
    while True:
        space = _numbered(aggregate, springs)
        width = 3 * space.bandwidth + 3
        if 3 * space.count * width * width <= MAX_FACTOR_FLOPS:
            return space
        aggregate = space.aggregate
        grouped = aggregates(_adjacency(space.count, _links(aggregate, springs)))
        aggregate = np.where(aggregate >= 0, grouped[np.maximum(aggregate, 0)], -1)


def _links(aggregate: np.ndarray, springs: np.ndarray) -> np.ndarray:
    """The pairs of distinct aggregates that a spring couples."""
    links = aggregate[springs]
    return links[(links[:, 0] >= 0) & (links[:, 1] >= 0) & (links[:, 0] != links[:, 1])]


def _numbered(aggregate: np.ndarray, springs: np.ndarray) -> CoarseSpace:
    """The aggregates renumbered in reverse Cuthill-McKee order, and the band that gives."""
    count = int(aggregate.max() + 1)
    links = _links(aggregate, springs)
    order = np.asarray(reverse_cuthill_mckee(_adjacency(count, links), symmetric_mode=True),
                       np.int64)
    renumber = np.empty(count, np.int64)
    renumber[order] = np.arange(count)
    aggregate = np.where(aggregate >= 0, renumber[np.maximum(aggregate, 0)], -1)
    links = renumber[links]
    bandwidth = int(np.abs(links[:, 0] - links[:, 1]).max()) if len(links) else 0
    return CoarseSpace(aggregate.astype(np.int64), count, bandwidth)


def _adjacency(count: int, pairs: np.ndarray):
    pairs = np.asarray(pairs, np.int64).reshape(-1, 2)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1]])
    columns = np.concatenate([pairs[:, 1], pairs[:, 0]])
    return coo_matrix((np.ones(len(rows)), (rows, columns)), shape=(count, count)).tocsr()


def aggregates(graph) -> np.ndarray:
    """(n,) each node's aggregate, -1 for a node with no neighbour: a node whose neighbours
    are all free starts an aggregate with them; a node left over joins a neighbour's; what is
    still left groups with its free neighbours."""
    n = graph.shape[0]
    start, neighbours = graph.indptr, graph.indices
    aggregate = np.full(n, -1, np.int64)
    count = 0
    for node in range(n):
        around = neighbours[start[node]:start[node + 1]]
        if len(around) and aggregate[node] < 0 and (aggregate[around] < 0).all():
            aggregate[node] = count
            aggregate[around] = count
            count += 1
    for node in np.flatnonzero(aggregate < 0):
        around = neighbours[start[node]:start[node + 1]]
        joined = around[aggregate[around] >= 0]
        if len(joined):
            aggregate[node] = aggregate[joined[0]]
    for node in np.flatnonzero(aggregate < 0):
        around = neighbours[start[node]:start[node + 1]]
        if len(around):
            free = around[aggregate[around] < 0]
            aggregate[node] = count
            aggregate[free] = count
            count += 1
    return aggregate


# --- the coarse matrix, each solve --------------------------------------------------------------
# Band storage, upper half: band[i, d] = A_c[i, i + d], d <= width = 3 bandwidth + 2 (the
# farthest two unknowns of coupled aggregates). It is a tenth of the dense matrix, and the
# factorization's updates run along its rows, in loops that compile to vector code.

@kernel
def band_width(coarse):
    return 3 * coarse.bandwidth + 2


@kernel
def projectors(kind, normal):
    """S_i of every particle as a 3 x 3 matrix: constraints.filtered applied to the unit
    vectors, column by column."""
    out = np.zeros((kind.shape[0], 3, 3))
    for i in range(kind.shape[0]):
        n0, n1, n2 = normal[i, 0], normal[i, 1], normal[i, 2]
        out[i, 0, 0], out[i, 1, 0], out[i, 2, 0] = filtered(kind[i], n0, n1, n2, 1.0, 0.0, 0.0)
        out[i, 0, 1], out[i, 1, 1], out[i, 2, 1] = filtered(kind[i], n0, n1, n2, 0.0, 1.0, 0.0)
        out[i, 0, 2], out[i, 1, 2], out[i, 2, 2] = filtered(kind[i], n0, n1, n2, 0.0, 0.0, 1.0)
    return out


@inline_kernel
def add_filtered_block(band, row, column, filters, p, blocks, slot, q, sign, free_row, free_column):
    """A_c's rows 3 row.. and columns 3 column.. += sign S_p blocks[slot] S_q (``filters`` every
    particle's S: projectors), upper half only (the lower half comes as the transposed block).
    A free particle's S is I: skipped. Plain loops: numba hands a 3 x 3 matrix product to BLAS,
    a microsecond a call. Whole arrays and indices, not rows: a row taken out is a view, with a
    reference count up and down."""
    r0, c0 = 3 * row, 3 * column
    if c0 + 2 < r0:
        return
    for a in range(3):
        for b in range(3):
            d = c0 + b - r0 - a
            if d < 0:
                continue
            if free_row and free_column:
                band[r0 + a, d] += sign * blocks[slot, a, b]
                continue
            total = 0.0
            for k in range(3):
                for m in range(3):
                    total += filters[p, a, k] * blocks[slot, k, m] * filters[q, m, b]
            band[r0 + a, d] += sign * total


@kernel
def coarse_matrix(coarse, pattern, blocks, terms, kind, normal):
    """A_c = P^T (S A S + H) P (module doc) in band storage; ball contacts left out."""
    runs, run_coefficients, loose_pairs, loose_coefficients, columns = terms
    aggregate = coarse.aggregate
    band = np.zeros((3 * coarse.count, band_width(coarse) + 1))
    filters = projectors(kind, normal)
    held = np.empty((1, 3, 3))
    for i in range(kind.shape[0]):
        if aggregate[i] < 0:
            continue
        if kind[i] != FREE:   # what S filters out, held at the particle's own stiffness
            diagonal = blocks[pattern.diagonal_slot[i]]
            scale = (diagonal[0, 0] + diagonal[1, 1] + diagonal[2, 2]) / 3.0
            for a in range(3):
                for b in range(3):
                    held[0, a, b] = scale * ((1.0 if a == b else 0.0) - filters[i, a, b])
            add_filtered_block(band, aggregate[i], aggregate[i], filters, i, held, 0, i, 1.0,
                               True, True)
        for slot in range(pattern.row_start[i], pattern.row_start[i + 1]):
            j = pattern.column[slot]
            if aggregate[j] >= 0:
                add_filtered_block(band, aggregate[i], aggregate[j], filters, i, blocks, slot, j,
                                   1.0, kind[i] == FREE, kind[j] == FREE)
    # each spring checked here, and its inline calls handed whole arrays with nothing to return
    # early from: so LLVM takes out the reference counts of the arrays they are handed (with the
    # check in add_spring and rows as views, a spring counted 16; the 100 x 100 cloth's A_c took
    # 9.0 ms to build instead of 1.8: CHANGELOG, issue 56)
    block = np.empty((1, 3, 3))
    for r in range(runs.shape[0]):
        first, offset, count, start = runs[r, 0], runs[r, 1], runs[r, 2], runs[r, 3]
        for k in range(count):
            a, b = first + k, first + k + offset
            if aggregate[a] >= 0 and aggregate[b] >= 0:
                spring_block_of(run_coefficients, start + k, block)
                add_spring(band, aggregate[a], aggregate[b], kind[a] == FREE, kind[b] == FREE,
                           filters, a, b, block)
    for k in range(loose_pairs.shape[0]):
        a, b = loose_pairs[k, 0], loose_pairs[k, 1]
        if aggregate[a] >= 0 and aggregate[b] >= 0:
            spring_block_of(loose_coefficients, k, block)
            add_spring(band, aggregate[a], aggregate[b], kind[a] == FREE, kind[b] == FREE,
                       filters, a, b, block)
    return band


@inline_kernel
def spring_block_of(coefficients, k, block):
    """block[0] = C = p l l^T + q I of the spring whose coefficients are column k."""
    p, q = coefficients[0, k], coefficients[1, k]
    for a in range(3):
        for b in range(3):
            block[0, a, b] = p * coefficients[2 + a, k] * coefficients[2 + b, k]
        block[0, a, a] += q


@inline_kernel
def add_spring(band, row, column, free_row, free_column, filters, a, b, block):
    """A spring's off-diagonal blocks -C (a, b) and (b, a) into A_c, C = block[0] (a hole of a
    run: C = 0); row and column: the aggregates of its particles a and b (both in one)."""
    add_filtered_block(band, row, column, filters, a, block, 0, b, -1.0, free_row, free_column)
    add_filtered_block(band, column, row, filters, b, block, 0, a, -1.0, free_column, free_row)


@kernel
def band_cholesky(band):
    """U with U^T U = A_c, in place (band storage, above). Returns False if A_c is not
    positive definite (to rounding)."""
    n, width = band.shape[0], band.shape[1] - 1
    for j in range(n):
        pivot = band[j, 0]
        if not pivot > 0.0:
            return False
        root = np.sqrt(pivot)
        band[j, 0] = root
        last = min(width, n - 1 - j)
        for d in range(1, last + 1):
            band[j, d] /= root
        for d in range(1, last + 1):
            f = band[j, d]
            if f == 0.0:
                continue
            row, above = band[j + d], band[j]
            for e in range(last + 1 - d):
                row[e] -= f * above[d + e]
    return True


@kernel
def coarse_factor(coarse, pattern, blocks, terms, kind, normal):
    """The Cholesky factor of A_c for this solve, or an empty one where there is no coarse
    space or A_c is not positive definite (the solve then goes on with block Jacobi alone)."""
    if coarse.count == 0:
        return np.zeros((0, 0))
    factor = coarse_matrix(coarse, pattern, blocks, terms, kind, normal)
    if not band_cholesky(factor):
        return np.zeros((0, 0))
    return factor


@kernel
def add_coarse_correction(coarse, factor, kind, normal, r, s, work):
    """s += S P A_c^-1 P^T r (r filtered already); returns r . s afterwards."""
    aggregate = coarse.aggregate
    work[:] = 0.0
    for i in range(r.shape[0]):
        g = aggregate[i]
        if g >= 0:
            for c in range(3):
                work[3 * g + c] += r[i, c]
    band_solve(factor, work)
    delta = 0.0
    for i in range(r.shape[0]):
        g = aggregate[i]
        if g >= 0:
            e0, e1, e2 = filtered(kind[i], normal[i, 0], normal[i, 1], normal[i, 2],
                                  work[3 * g], work[3 * g + 1], work[3 * g + 2])
            s[i, 0] += e0
            s[i, 1] += e1
            s[i, 2] += e2
        delta += r[i, 0] * s[i, 0] + r[i, 1] * s[i, 1] + r[i, 2] * s[i, 2]
    return delta


@kernel
def band_solve(factor, y):
    """y = (U^T U)^-1 y, U the band Cholesky factor. Both sweeps work on a row of U and the
    stretch of y below it as contiguous views, which the compiler vectorizes; the backward
    sweep's dot product keeps four running sums, since one sum in a fixed order is a chain
    of dependent additions that cannot be (benchmarks/solve_layout.py times both)."""
    n, width = factor.shape[0], factor.shape[1] - 1
    for j in range(n):   # U^T z = y
        row = factor[j]
        value = y[j] / row[0]
        y[j] = value
        m = min(width, n - 1 - j)
        below, coefficients = y[j + 1:j + 1 + m], row[1:1 + m]
        for d in range(m):
            below[d] -= coefficients[d] * value
    for j in range(n - 1, -1, -1):   # U x = z
        row = factor[j]
        m = min(width, n - 1 - j)
        below, coefficients = y[j + 1:j + 1 + m], row[1:1 + m]
        t0 = t1 = t2 = t3 = 0.0
        d = 0
        while d + 4 <= m:
            t0 += coefficients[d] * below[d]
            t1 += coefficients[d + 1] * below[d + 1]
            t2 += coefficients[d + 2] * below[d + 2]
            t3 += coefficients[d + 3] * below[d + 3]
            d += 4
        while d < m:
            t0 += coefficients[d] * below[d]
            d += 1
        y[j] = (y[j] - ((t0 + t1) + (t2 + t3))) / row[0]
