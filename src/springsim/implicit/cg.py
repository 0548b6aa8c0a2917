"""Filtered, block-Jacobi-preconditioned conjugate gradients (Baraff and Witkin 1998, section 5.3).

The preconditioner is the inverse of each particle's 3 x 3 diagonal block (Baraff and Witkin
take its diagonal entries alone): it undoes the coupling of a particle's three components by the
springs it holds, which the plain diagonal leaves to the iterations.

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

A solve that block Jacobi does not finish in TWO_LEVEL_AFTER iterations adds a coarse space of
aggregates to the preconditioner (coarse.py says why and how) and goes on from where it is.

Ball-particle contacts (penalty.py) are not in the fixed block pattern: ``system_multiply``
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
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from ..collision.response.penalty import add_contact_blocks, add_contact_product
from ..collision.contact_sets.solve import no_contacts
from .coarse import add_coarse_correction, coarse_factor, no_coarse_space
from .constraints import FREE, filter_constrained, filtered
from .jacobian import block_multiply
from .spring_terms import (add_loose_products, add_run_products, add_spring_products,
                           no_spring_terms, spring_terms_trace)

# N s: a reference below this is zero (nothing to solve); its square would underflow the goal
MIN_REFERENCE = 1e-150
# block-Jacobi iterations after which a solve that has not converged builds its coarse space
# (coarse.py) and goes on two-level: a solve that converges sooner never pays for building it,
# which costs about what ten iterations do (benchmarks/preconditioner.py)
TWO_LEVEL_AFTER = 25


class FilteredSystem(NamedTuple):
    """A u = b as the solves take it: the stored blocks (``pattern``, ``blocks``), the springs'
    ``terms`` (spring_terms.py), the active penalty ``contacts`` (penalty.py), the ``coarse``
    space (coarse.py), and the constraints' filter S: each particle's ``kind`` and ``normal``
    (constraints.py)."""

    pattern: tuple
    blocks: np.ndarray
    terms: tuple
    contacts: tuple
    coarse: tuple
    kind: np.ndarray
    normal: np.ndarray


class CGWork(NamedTuple):
    """The work arrays of a solve, each shaped like u."""

    r: np.ndarray   # the filtered residual S (b - A u)
    s: np.ndarray   # the preconditioned residual
    c: np.ndarray   # the search direction
    q: np.ndarray   # its product S A c


@kernel
def dot(u, w):
    total = 0.0
    for i in range(u.shape[0]):
        total += u[i, 0] * w[i, 0] + u[i, 1] * w[i, 1] + u[i, 2] * w[i, 2]
    return total


@kernel
def system_multiply(pattern, blocks, terms, contacts, u, out):
    """out = A u: the stored blocks, the springs' terms that are not stored (spring_terms.py)
    and the active ball-particle contacts."""
    block_multiply(pattern, blocks, u, out)
    add_spring_products(terms, u, out)
    add_contact_product(contacts, u, out)


@kernel
def inverse_diagonal_blocks(pattern, blocks, contacts, count):
    """The inverse of every diagonal block of A (stored blocks and contacts), (count, 3, 3):
    each block is symmetric positive definite, inverted by cofactors (exactly symmetric)."""
    m = np.empty((count, 3, 3))
    for i in range(count):
        m[i] = blocks[pattern.diagonal_slot[i]]
    add_contact_blocks(contacts, m)
    for i in range(count):
        a, b, c, d, e, f = m[i, 0, 0], m[i, 0, 1], m[i, 0, 2], m[i, 1, 1], m[i, 1, 2], m[i, 2, 2]
        c00, c01, c02 = d * f - e * e, c * e - b * f, b * e - c * d
        c11, c12, c22 = a * f - c * c, b * c - a * e, a * d - b * b
        scale = 1.0 / (a * c00 + b * c01 + c * c02)
        m[i, 0, 0], m[i, 1, 1], m[i, 2, 2] = scale * c00, scale * c11, scale * c22
        m[i, 0, 1] = m[i, 1, 0] = scale * c01
        m[i, 0, 2] = m[i, 2, 0] = scale * c02
        m[i, 1, 2] = m[i, 2, 1] = scale * c12
    return m


@kernel
def precondition(inverse, r, out):
    """out = the inverse diagonal blocks times r (block Jacobi)."""
    for i in range(r.shape[0]):
        r0, r1, r2 = r[i, 0], r[i, 1], r[i, 2]
        for c in range(3):
            out[i, c] = inverse[i, c, 0] * r0 + inverse[i, c, 1] * r1 + inverse[i, c, 2] * r2


@kernel
def filtered_cg(pattern, blocks, b, kind, normal, u, tolerance, max_iterations, work):
    """``contact_cg`` for the assembled matrix alone (no ball-particle contacts, no coarse
    space), its reference the larger of the starting residual and |b|."""
    system = FilteredSystem(pattern, blocks, no_spring_terms(), no_contacts(),
                            no_coarse_space(u.shape[0]), kind, normal)
    return contact_cg(system, b, u, tolerance, max_iterations, 0.0, work)


@kernel
def contact_cg(system, b, u, tolerance, max_iterations, reference_norm, work):
    """Improve ``u`` until |S (b - A u)| <= tolerance * reference (or max_iterations pass), A the
    ``system``'s (a FilteredSystem: the stored blocks plus the springs' terms and the active
    contacts), preconditioned by block Jacobi, and after TWO_LEVEL_AFTER iterations also by
    the system's coarse space if it has aggregates.

    The reference is ``reference_norm`` if positive, else the larger of the starting residual
    |S (b - A u)| and |b| (module doc), and at least MIN_REFERENCE. ``work``: a CGWork.
    Returns (iterations, reference norm used).
    """
    pattern, blocks, terms, contacts, coarse = (system.pattern, system.blocks, system.terms,
                                                system.contacts, system.coarse)
    kind, normal = system.kind, system.normal
    r, s, c, q = work.r, work.s, work.c, work.q
    inverse = inverse_diagonal_blocks(pattern, blocks, contacts, u.shape[0])
    system_multiply(pattern, blocks, terms, contacts, u, q)
    for i in range(u.shape[0]):
        for k in range(3):
            r[i, k] = b[i, k] - q[i, k]
    filter_constrained(kind, normal, r)
    residual_squared = dot(r, r)
    reference = reference_norm
    if not reference > 0.0:
        reference = max(math.sqrt(residual_squared), math.sqrt(dot(b, b)), MIN_REFERENCE)
    goal = (tolerance * reference) ** 2
    precondition(inverse, r, s)
    filter_constrained(kind, normal, s)
    delta = dot(r, s)
    c[:] = s
    beta = 0.0   # the first direction is s itself
    factor, coarse_work, two_level = np.zeros((0, 0)), np.zeros(0), False
    for iteration in range(max_iterations):
        if not residual_squared > goal:   # also stops on NaN, which the divergence check reports
            return iteration, reference
        if iteration == TWO_LEVEL_AFTER and coarse.count > 0:
            factor = coarse_factor(coarse, pattern, blocks, terms, kind, normal)
            two_level = factor.shape[0] > 0
            if two_level:   # start again from u, along the two-level preconditioned residual
                coarse_work = np.zeros(factor.shape[0])
                precondition(inverse, r, s)
                filter_constrained(kind, normal, s)
                delta = add_coarse_correction(coarse, factor, kind, normal, r, s, coarse_work)
                beta = 0.0
        curvature = search_product(pattern, blocks, terms, contacts, kind, normal, s, beta, c, q)
        if not curvature > 0.0:
            return iteration, reference
        delta_new, residual_squared = cg_update(kind, normal, inverse, delta / curvature, c, q,
                                                u, r, s)
        if two_level:
            delta_new = add_coarse_correction(coarse, factor, kind, normal, r, s, coarse_work)
        beta = delta_new / delta
        delta = delta_new
    return max_iterations, reference


@kernel
def search_product(pattern, blocks, terms, contacts, kind, normal, s, beta, c, q):
    """The new search direction c = s + beta c and its filtered product q = S A c; returns c . q.

    With only the diagonal blocks stored (block i in slot i) and the springs in runs, in three
    passes over the particles rather than five: c is made while it is copied into the springs'
    columns, with the diagonal blocks' product as the start of the sum (spring_terms.py), and q
    is filtered and dotted while it is copied out. The same sums as system_multiply and
    filter_and_dot, added in another order."""
    runs, run_coefficients, loose_pairs, loose_coefficients, columns = terms
    count = s.shape[0]
    if pattern.column.shape[0] != count or runs.shape[0] == 0:
        for i in range(count):
            for k in range(3):
                c[i, k] = s[i, k] + beta * c[i, k]
        system_multiply(pattern, blocks, terms, contacts, c, q)
        return filter_and_dot(kind, normal, q, c)
    for i in range(count):
        c0, c1, c2 = s[i, 0] + beta * c[i, 0], s[i, 1] + beta * c[i, 1], s[i, 2] + beta * c[i, 2]
        c[i, 0], c[i, 1], c[i, 2] = c0, c1, c2
        columns[0, i], columns[1, i], columns[2, i] = c0, c1, c2
        columns[3, i] = blocks[i, 0, 0] * c0 + blocks[i, 0, 1] * c1 + blocks[i, 0, 2] * c2
        columns[4, i] = blocks[i, 1, 0] * c0 + blocks[i, 1, 1] * c1 + blocks[i, 1, 2] * c2
        columns[5, i] = blocks[i, 2, 0] * c0 + blocks[i, 2, 1] * c1 + blocks[i, 2, 2] * c2
    add_run_products(runs, run_coefficients, columns)
    # particles as rows again, for the scattered pairs: views of the same columns
    direction, product = columns[0:3].T, columns[3:6].T
    add_loose_products(loose_pairs, loose_coefficients, direction, product)
    add_contact_product(contacts, direction, product)
    total = 0.0
    for i in range(count):
        q0, q1, q2 = filtered(kind[i], normal[i, 0], normal[i, 1], normal[i, 2], columns[3, i],
                              columns[4, i], columns[5, i])
        q[i, 0], q[i, 1], q[i, 2] = q0, q1, q2
        total += c[i, 0] * q0 + c[i, 1] * q1 + c[i, 2] * q2
    return total


@kernel
def mass_start(system, b, inverse_mass, guess, u, work):
    """u += alpha_1 S guess, then u += alpha_2 S M^-1 r, r = S (b - A u), each alpha the one
    that lowers the error's A-norm most along its direction (none if the direction has no
    curvature), A and S the ``system``'s (a FilteredSystem). An all-zero guess is skipped.
    ``work``: a CGWork (its r, s and q).

    Why M^-1 r: the block-Jacobi preconditioner divides by the springs' stiffness too, so a
    smooth load (gravity on a falling body: every particle's velocity changes by h g) takes
    conjugate gradients as many iterations as the load takes to cross the body, one neighbour
    per iteration. M^-1 r is the velocity change the load gives when the springs do not resist
    it, exact for a uniform one: a falling cube's solve needs a few iterations after it instead
    of as many as the cube is wide (benchmarks/implicit_scale.py counts them).
    Why a guess (the last step's velocity change): under a steady load consecutive steps change
    the velocities alike. Taken as a direction with its best length, not as the start itself, it
    is never worse than none: a resting cube's last change is round-off, which as a start cost
    3.6 more iterations a step."""
    pattern, blocks, terms, contacts = system.pattern, system.blocks, system.terms, system.contacts
    kind, normal = system.kind, system.normal
    r, s, q = work.r, work.s, work.q
    system_multiply(pattern, blocks, terms, contacts, u, q)
    for i in range(u.shape[0]):
        for k in range(3):
            r[i, k] = b[i, k] - q[i, k]
    filter_constrained(kind, normal, r)
    if dot(guess, guess) > 0.0:
        s[:] = guess
        filter_constrained(kind, normal, s)
        step_along(pattern, blocks, terms, contacts, kind, normal, u, r, s, q)
    for i in range(u.shape[0]):
        for k in range(3):
            s[i, k] = inverse_mass[i] * r[i, k]
    filter_constrained(kind, normal, s)
    step_along(pattern, blocks, terms, contacts, kind, normal, u, r, s, q)


@kernel
def step_along(pattern, blocks, terms, contacts, kind, normal, u, r, s, q):
    """u += alpha s and r -= alpha S A s, alpha = s . r / s . A s: the best step along the
    filtered direction s for the residual r = S (b - A u) (none if s has no curvature)."""
    system_multiply(pattern, blocks, terms, contacts, s, q)
    filter_constrained(kind, normal, q)
    curvature = dot(s, q)
    if curvature > 0.0:
        alpha = dot(s, r) / curvature
        for i in range(u.shape[0]):
            for k in range(3):
                u[i, k] += alpha * s[i, k]
                r[i, k] -= alpha * q[i, k]


@kernel
def filter_and_dot(kind, normal, q, c):
    """q = S q; returns c . q."""
    total = 0.0
    for i in range(q.shape[0]):
        q0, q1, q2 = filtered(kind[i], normal[i, 0], normal[i, 1], normal[i, 2], q[i, 0],
                              q[i, 1], q[i, 2])
        q[i, 0], q[i, 1], q[i, 2] = q0, q1, q2
        total += c[i, 0] * q0 + c[i, 1] * q1 + c[i, 2] * q2
    return total


@kernel
def cg_update(kind, normal, inverse, alpha, c, q, u, r, s):
    """One pass for the rest of an iteration: u += alpha c, r -= alpha q, filtered again (q's
    rounding, kept out of the residual), s = S P r (P the preconditioner). Returns (r . s, r . r).
    """
    delta = residual_squared = 0.0
    for i in range(u.shape[0]):
        n0, n1, n2 = normal[i, 0], normal[i, 1], normal[i, 2]
        for k in range(3):
            u[i, k] += alpha * c[i, k]
        r0, r1, r2 = filtered(kind[i], n0, n1, n2, r[i, 0] - alpha * q[i, 0],
                              r[i, 1] - alpha * q[i, 1], r[i, 2] - alpha * q[i, 2])
        r[i, 0], r[i, 1], r[i, 2] = r0, r1, r2
        s0, s1, s2 = filtered(kind[i], n0, n1, n2,
                              inverse[i, 0, 0] * r0 + inverse[i, 0, 1] * r1 + inverse[i, 0, 2] * r2,
                              inverse[i, 1, 0] * r0 + inverse[i, 1, 1] * r1 + inverse[i, 1, 2] * r2,
                              inverse[i, 2, 0] * r0 + inverse[i, 2, 1] * r1 + inverse[i, 2, 2] * r2)
        s[i, 0], s[i, 1], s[i, 2] = s0, s1, s2
        delta += r0 * s0 + r1 * s1 + r2 * s2
        residual_squared += r0 * r0 + r1 * r1 + r2 * r2
    return delta, residual_squared


@kernel
def conserve_momentum(pattern, blocks, terms, contacts, b, kind, u, q):
    """If no particle is constrained, shift u by the uniform velocity change that leaves the
    residual b - A u summing to zero in each direction (module doc); q is a work array."""
    for i in range(kind.shape[0]):
        if kind[i] != FREE:
            return
    system_multiply(pattern, blocks, terms, contacts, u, q)
    for c in range(3):
        # T^T A T: springs and contacts cancel between their two particles, leaving the masses
        # and drag; its off-diagonal entries are rounding and are left out
        translated = -2.0 * spring_terms_trace(terms, c)   # their (a, b) and (b, a) blocks
        for slot in range(blocks.shape[0]):
            translated += blocks[slot, c, c]
        residual = 0.0
        for i in range(u.shape[0]):
            residual += b[i, c] - q[i, c]
        if translated > 0.0:
            shift = residual / translated
            for i in range(u.shape[0]):
                u[i, c] += shift
