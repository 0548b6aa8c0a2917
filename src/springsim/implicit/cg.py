"""Filtered, Jacobi-preconditioned conjugate gradients (Baraff and Witkin 1998, section 5.3).

Solves A u = b for the components of u that no constraint fixes: every search direction is
filtered (``constraints.filter_constrained``), so the constrained components keep their starting
value. A must be symmetric positive definite on the free components (see jacobian.py).

Rounding: filtering b - A u leaves ~1e-16 |b| in the constrained components, which no filtered
direction can reduce. Once the free part is solved, that is the whole residual; its filtered,
preconditioned image is rounding with next to no curvature, the step along it is huge, and it
moves u's constrained components by the rounding the filter left (a held contact was driven
0.09 m/s into its plane). So the residual is filtered again after every update, and the goal is
never below tolerance |b|: relative to the starting residual alone it is rounding whenever a
solve starts at its answer (a held contact, whose friction damper cancels the load along the
surface). The integrator also restores the constrained components after each solve
(``constraints.hold_all_constrained``).
"""
import math

from .._jit import kernel
from .constraints import filter_constrained
from .jacobian import block_multiply

# N s: a reference below this is zero (nothing to solve); its square would underflow the goal
MIN_REFERENCE = 1e-150


@kernel
def dot(u, w):
    total = 0.0
    for i in range(u.shape[0]):
        total += u[i, 0] * w[i, 0] + u[i, 1] * w[i, 1] + u[i, 2] * w[i, 2]
    return total


@kernel
def precondition(pattern, blocks, r, out):
    """out = r / diag(A), entry by entry (Jacobi)."""
    for i in range(r.shape[0]):
        slot = pattern.diagonal_slot[i]
        for c in range(3):
            out[i, c] = r[i, c] / blocks[slot, c, c]


@kernel
def filtered_cg(pattern, blocks, b, kind, normal, u, tolerance, max_iterations, reference_norm,
                r, s, c, q):
    """Improve ``u`` until |S (b - A u)| <= tolerance * reference (or max_iterations pass).

    The reference is ``reference_norm`` if positive, else the larger of the starting residual
    |S (b - A u)| and |b| (module doc), and at least MIN_REFERENCE. r, s, c, q are work arrays
    shaped like u. Returns (iterations, reference norm used).
    """
    block_multiply(pattern, blocks, u, q)
    for i in range(u.shape[0]):
        for k in range(3):
            r[i, k] = b[i, k] - q[i, k]
    filter_constrained(kind, normal, r)
    residual_squared = dot(r, r)
    reference = reference_norm
    if not reference > 0.0:
        reference = max(math.sqrt(residual_squared), math.sqrt(dot(b, b)), MIN_REFERENCE)
    goal = (tolerance * reference) ** 2
    precondition(pattern, blocks, r, s)
    filter_constrained(kind, normal, s)
    c[:] = s
    delta = dot(r, s)
    for iteration in range(max_iterations):
        if not residual_squared > goal:   # also stops on NaN, which the divergence check reports
            return iteration, reference
        block_multiply(pattern, blocks, c, q)
        filter_constrained(kind, normal, q)
        curvature = dot(c, q)
        if not curvature > 0.0:
            return iteration, reference
        alpha = delta / curvature
        for i in range(u.shape[0]):
            for k in range(3):
                u[i, k] += alpha * c[i, k]
                r[i, k] -= alpha * q[i, k]
        filter_constrained(kind, normal, r)   # q's rounding, kept out of the residual
        precondition(pattern, blocks, r, s)
        filter_constrained(kind, normal, s)
        delta_new = dot(r, s)
        beta = delta_new / delta
        delta = delta_new
        for i in range(u.shape[0]):
            for k in range(3):
                c[i, k] = s[i, k] + beta * c[i, k]
        residual_squared = dot(r, r)
    return max_iterations, reference
