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

Ball-particle contacts (ball_contact.py) are not in the fixed block pattern: ``system_multiply``
adds their product to the assembled matrix's, and the Jacobi preconditioner their diagonal.
``filtered_cg`` is the solve without them.

Momentum: every spring, damper and contact term of A acts on its two particles with opposite
signs, so the exact solution changes the momentum by the external impulses alone; the residual
that the tolerance leaves does not (its sum over particles, ~tolerance |b|, is momentum gained or
lost). When no particle is constrained, ``conserve_momentum`` follows each solve with a correction
along the three rigid translations T (the Galerkin step u += T (T^T A T)^-1 T^T r, which can only
lower the error's A-norm): it makes the residual sum to zero, so an unconstrained system
conserves momentum to rounding. With pins or terrain contacts momentum is not conserved anyway,
and the solve is left as it is.
"""
import math

import numpy as np

from .._jit import kernel
from .ball_contact import add_contact_diagonal, add_contact_product, no_ball_contacts
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
def system_multiply(pattern, blocks, contacts, u, out):
    """out = A u: the assembled blocks and the active ball-particle contacts."""
    block_multiply(pattern, blocks, u, out)
    add_contact_product(contacts, u, out)


@kernel
def system_diagonal(pattern, blocks, contacts, diagonal):
    """diagonal = the diagonal entries of A (blocks and contacts), shaped like u."""
    for i in range(diagonal.shape[0]):
        slot = pattern.diagonal_slot[i]
        for c in range(3):
            diagonal[i, c] = blocks[slot, c, c]
    add_contact_diagonal(contacts, diagonal)


@kernel
def precondition(diagonal, r, out):
    """out = r / diag(A), entry by entry (Jacobi)."""
    for i in range(r.shape[0]):
        for c in range(3):
            out[i, c] = r[i, c] / diagonal[i, c]


@kernel
def filtered_cg(pattern, blocks, b, kind, normal, u, tolerance, max_iterations, reference_norm,
                r, s, c, q):
    """``contact_cg`` for the assembled matrix alone (no ball-particle contacts)."""
    return contact_cg(pattern, blocks, no_ball_contacts(), b, kind, normal, u, tolerance,
                      max_iterations, reference_norm, r, s, c, q)


@kernel
def contact_cg(pattern, blocks, contacts, b, kind, normal, u, tolerance, max_iterations,
               reference_norm, r, s, c, q):
    """Improve ``u`` until |S (b - A u)| <= tolerance * reference (or max_iterations pass), A the
    assembled blocks plus the active ``contacts`` (ball_contact.py).

    The reference is ``reference_norm`` if positive, else the larger of the starting residual
    |S (b - A u)| and |b| (module doc), and at least MIN_REFERENCE. r, s, c, q are work arrays
    shaped like u. Returns (iterations, reference norm used).
    """
    diagonal = np.empty_like(u)
    system_diagonal(pattern, blocks, contacts, diagonal)
    system_multiply(pattern, blocks, contacts, u, q)
    for i in range(u.shape[0]):
        for k in range(3):
            r[i, k] = b[i, k] - q[i, k]
    filter_constrained(kind, normal, r)
    residual_squared = dot(r, r)
    reference = reference_norm
    if not reference > 0.0:
        reference = max(math.sqrt(residual_squared), math.sqrt(dot(b, b)), MIN_REFERENCE)
    goal = (tolerance * reference) ** 2
    precondition(diagonal, r, s)
    filter_constrained(kind, normal, s)
    c[:] = s
    delta = dot(r, s)
    for iteration in range(max_iterations):
        if not residual_squared > goal:   # also stops on NaN, which the divergence check reports
            return iteration, reference
        system_multiply(pattern, blocks, contacts, c, q)
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
        precondition(diagonal, r, s)
        filter_constrained(kind, normal, s)
        delta_new = dot(r, s)
        beta = delta_new / delta
        delta = delta_new
        for i in range(u.shape[0]):
            for k in range(3):
                c[i, k] = s[i, k] + beta * c[i, k]
        residual_squared = dot(r, r)
    return max_iterations, reference


@kernel
def conserve_momentum(pattern, blocks, contacts, b, kind, u, q):
    """If no particle is constrained, shift u by the uniform velocity change that leaves the
    residual b - A u summing to zero in each direction (module doc); q is a work array."""
    for i in range(kind.shape[0]):
        if kind[i] != 0:   # constraints.FREE
            return
    system_multiply(pattern, blocks, contacts, u, q)
    for c in range(3):
        # T^T A T: springs and contacts cancel between their two particles, leaving the masses
        # and drag; its off-diagonal entries are rounding and are left out
        translated = 0.0
        for slot in range(blocks.shape[0]):
            translated += blocks[slot, c, c]
        residual = 0.0
        for i in range(u.shape[0]):
            residual += b[i, c] - q[i, c]
        if translated > 0.0:
            shift = residual / translated
            for i in range(u.shape[0]):
                u[i, c] += shift
