"""The springs' off-diagonal blocks of the backward-Euler matrix, applied without being stored.

Every spring s = (a, b) adds a symmetric 3 x 3 block C_s = p l l^T + q I (jacobian.py: p from the
damper and the stiffness along the spring, q from the stiffness across it) to the diagonal blocks
(a, a) and (b, b), and -C_s to (a, b) and (b, a). Stored as blocks, the off-diagonal part is four 3
x 3 blocks (288 bytes) per spring, and a matrix-vector product streams all of it. Here the solve
keeps only the diagonal blocks (``pattern.diagonal_pattern``) and, per spring, the five numbers p,
q, l (40 bytes), and the product adds -C_s u_b to a and -C_s u_a to b itself.

The springs are laid out in runs, as the force loop has them (spring_runs.py): along a run both
ends walk contiguous memory, so the product runs as SIMD code on ``columns`` (u in rows 0-2,
the product in rows 3-5, scratch in rows 6-8), tile by tile. The few loose springs take a plain
loop. The terms of one solve are the tuple
    (runs (R, 5), run_coefficients (5, E), loose_pairs (L, 2), loose_coefficients (5, L), columns)
with the coefficients rows p, q, l_x, l_y, l_z (a hole of a run: all zero).
"""
import numpy as np

from .._jit import inline_kernel, kernel
from ..spring_runs import TILE

TERM_ROWS = 9   # rows of the work columns: u, the product, scratch


@kernel
def no_spring_terms():
    """No terms: a matrix whose blocks are all stored (pattern.build_block_pattern)."""
    return (np.empty((0, 5), np.int64), np.empty((5, 0)), np.empty((0, 2), np.int64),
            np.empty((5, 0)), np.empty((TERM_ROWS, 0)))


@kernel
def spring_terms_like(runs, run_entries, loose_pairs, x):
    """Terms (coefficients to be assembled) for the runs and loose springs of a model."""
    return (runs, np.zeros((5, run_entries)), loose_pairs, np.zeros((5, loose_pairs.shape[0])),
            np.empty((TERM_ROWS, x.shape[0])))


@kernel
def add_spring_products(terms, u, out):
    """out += the springs' off-diagonal blocks times u (module doc)."""
    runs, run_coefficients, loose_pairs, loose_coefficients, columns = terms
    if runs.shape[0] > 0:
        for i in range(u.shape[0]):
            for c in range(3):
                columns[c, i] = u[i, c]
                columns[3 + c, i] = 0.0
        add_run_products(runs, run_coefficients, columns)
        for i in range(u.shape[0]):
            for c in range(3):
                out[i, c] += columns[3 + c, i]
    add_loose_products(loose_pairs, loose_coefficients, u, out)


@kernel
def add_run_products(runs, coefficients, columns):
    """Rows 3-5 of the columns += the run springs' off-diagonal blocks times rows 0-2, tile by
    tile."""
    for tile in range(0, columns.shape[1], TILE):
        for r in range(runs.shape[0]):
            first, offset, count, start = runs[r, 0], runs[r, 1], runs[r, 2], runs[r, 3]
            low, high = max(first, tile), min(first + count, tile + TILE)
            if low < high:
                add_stretch_products(columns, low, low + offset, high - low, coefficients,
                                     start + low - first)


@kernel
def add_loose_products(loose_pairs, coefficients, u, out):
    """out += the loose springs' off-diagonal blocks times u."""
    for k in range(loose_pairs.shape[0]):
        a, b = loose_pairs[k, 0], loose_pairs[k, 1]
        p, q = coefficients[0, k], coefficients[1, k]
        l0, l1, l2 = coefficients[2, k], coefficients[3, k], coefficients[4, k]
        lu_a = l0 * u[a, 0] + l1 * u[a, 1] + l2 * u[a, 2]
        lu_b = l0 * u[b, 0] + l1 * u[b, 1] + l2 * u[b, 2]
        out[a, 0] -= p * lu_b * l0 + q * u[b, 0]
        out[a, 1] -= p * lu_b * l1 + q * u[b, 1]
        out[a, 2] -= p * lu_b * l2 + q * u[b, 2]
        out[b, 0] -= p * lu_a * l0 + q * u[a, 0]
        out[b, 1] -= p * lu_a * l1 + q * u[a, 1]
        out[b, 2] -= p * lu_a * l2 + q * u[a, 2]


@inline_kernel
def add_stretch_products(columns, a, b, count, coefficients, entry):
    """Springs (a + i, b + i), i < count, whose coefficients start at ``entry``: C u_b
    (C = p l l^T + q I) off row a + i, C u_a off row b + i, each row read as a contiguous
    slice."""
    e = entry
    p, q = coefficients[0, e:e + count], coefficients[1, e:e + count]
    l0, l1 = coefficients[2, e:e + count], coefficients[3, e:e + count]
    l2 = coefficients[4, e:e + count]
    x_a, y_a, z_a = columns[0, a:a + count], columns[1, a:a + count], columns[2, a:a + count]
    x_b, y_b, z_b = columns[0, b:b + count], columns[1, b:b + count], columns[2, b:b + count]
    out_x, out_y, out_z = columns[3, a:a + count], columns[4, a:a + count], columns[5, a:a + count]
    tx, ty, tz = columns[6, :count], columns[7, :count], columns[8, :count]
    for i in range(count):
        lu_b = p[i] * (l0[i] * x_b[i] + l1[i] * y_b[i] + l2[i] * z_b[i])
        out_x[i] -= lu_b * l0[i] + q[i] * x_b[i]
        out_y[i] -= lu_b * l1[i] + q[i] * y_b[i]
        out_z[i] -= lu_b * l2[i] + q[i] * z_b[i]
        lu_a = p[i] * (l0[i] * x_a[i] + l1[i] * y_a[i] + l2[i] * z_a[i])
        tx[i] = lu_a * l0[i] + q[i] * x_a[i]
        ty[i] = lu_a * l1[i] + q[i] * y_a[i]
        tz[i] = lu_a * l2[i] + q[i] * z_a[i]
    # the b rows in a loop of their own: b + i may be a + j of another i (spring_runs.py)
    out_x, out_y, out_z = columns[3, b:b + count], columns[4, b:b + count], columns[5, b:b + count]
    for i in range(count):
        out_x[i] -= tx[i]
        out_y[i] -= ty[i]
        out_z[i] -= tz[i]


@kernel
def spring_terms_trace(terms, c):
    """The sum over all springs of C_s[c, c] (for cg.conserve_momentum)."""
    runs, run_coefficients, loose_pairs, loose_coefficients, columns = terms
    total = 0.0
    for coefficients in (run_coefficients, loose_coefficients):
        for k in range(coefficients.shape[1]):
            total += coefficients[0, k] * coefficients[2 + c, k] ** 2 + coefficients[1, k]
    return total
