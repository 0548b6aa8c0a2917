"""Backward Euler's Newton iterations, solved again where the adjoint needs them, and the adjoint
of one iteration (adjoints.ImplicitEulerAdjoint).

A step without contact solves with the forward's own matrix and CG (``ForwardSolver``): the
pinned particles' rows filtered out as in the forward, A = M + h c - h dF/dv - h^2 dF/dx
(clamped), the forward's tolerance. The adjoint is the derivative of the linearized step,
treating the forward's solves as exact: the CG residuals are the gradient's error, of the
tolerance's order. A step with terrain contact (implicit_replay.py) assembles A as a sparse
matrix (``system_matrix``) and solves its reduced systems directly (``solve_reduced``: sparse LU
up to DIRECT_LIMIT unknowns, CG to ADJOINT_TOLERANCE beyond).
"""
import numpy as np
from scipy import sparse
from scipy.sparse import linalg

from .physics import (
    geometry,
    spring_forces,
    spring_forces_vjp,
    stiffness_coefficients,
    stiffness_product,
    stiffness_product_vjp,
    system_product_vjp,
)
from . import terms

ADJOINT_TOLERANCE = 1e-12   # relative residual of the adjoint's CG solves
# unknowns up to which a sparse LU solves (exact, and quick there); beyond, CG: a body's 3D
# lattice fills LU's factors in (performance page, "Gradients")
DIRECT_LIMIT = 1000


class ForwardSolver:
    """The forward's own matrix and solve for the adjoint's systems: the block pattern, the
    assembly and the filtered, block-Jacobi-preconditioned CG of implicit/ (cg.contact_cg), so
    that the adjoint solves with the very matrix the step solved with, as fast. It stops at the
    forward's tolerance: the forward's own solves leave an error of that order in the gradient
    already (docs/guide/gradients.md measures both)."""

    def __init__(self, model, integrator):
        from ..collision.contact_sets.solve import no_contacts
        from ..implicit.constraints import FREE, PINNED
        from ..implicit.spring_terms import spring_terms_like

        self.arrays = model.arrays
        self.layout = layout = integrator.solve_layout(model)
        count = model.particle_count
        x = np.zeros((count, 3))
        self.blocks = np.empty((layout.diagonal.column.shape[0], 3, 3))
        self.terms = spring_terms_like(layout.runs, layout.run_entries, layout.loose_pairs, x)
        self.contacts = no_contacts()
        self.kind = np.where(model.pinned, PINNED, FREE).astype(np.int8)
        self.normal = np.zeros((count, 3))
        self.work = [np.zeros((count, 3)) for _ in range(4)]
        self.unused_rhs = np.zeros((count, 3))
        self.tolerance = integrator.cg_tolerance
        self.max_iterations = integrator.cg_max_iterations
        self.iterations = 0   # CG iterations, for diagnostics

    def assemble(self, physical, x, v, h):
        """The system matrix A at the estimate (x, v) (kept for ``solve``); v enters through the
        terms' blocks alone (the wind's)."""
        from ..implicit.jacobian import assemble_diagonal_and_terms

        assemble_diagonal_and_terms(self.arrays, self.layout, x, 1.0, h, h * h,
                                    self.blocks, self.terms)
        terms.add_forward_blocks(self, physical, x, v, h)

    def solve(self, rhs, contacts=None):
        """u with A u = rhs on the free particles (zero on the pinned ones); A with the active
        penalty ``contacts`` (contact_sets.SolveContacts) if given."""
        from ..implicit.cg import CGWork, FilteredSystem, contact_cg

        u = np.zeros_like(rhs)
        contacts = self.contacts if contacts is None else contacts
        system = FilteredSystem(self.layout.diagonal, self.blocks, self.terms, contacts,
                                self.layout.coarse, self.kind, self.normal)
        done, _ = contact_cg(system, np.ascontiguousarray(rhs), u, self.tolerance,
                             self.max_iterations, 0.0, CGWork(*self.work))
        self.iterations += done
        return u


def spring_blocks(physical, x, h):
    """Every spring's block of A at x (S, 3, 3): C = p l l^T + q I, p = h kd + h^2 (its stiffness
    along), q = h^2 (its stiffness across); none for a spring of zero length."""
    springs = geometry(physical, x)
    along, across, _, _, _ = stiffness_coefficients(physical, springs)
    real = springs.length > 0.0
    p = (h * physical.kd + h * h * along) * real
    q = h * h * across * real
    l = springs.unit
    return p[:, None, None] * l[:, :, None] * l[:, None, :] + q[:, None, None] * np.eye(3)


def system_matrix(physical, x, v, h):
    """A at the estimate (x, v) as a sparse (3P, 3P) matrix: the diagonal masses and drag,
    every spring's block C = p l l^T + q I added to (a, a), (b, b) and subtracted from (a, b),
    (b, a), and the terms' entries."""
    count = x.shape[0]
    blocks = spring_blocks(physical, x, h)
    a, b = physical.a, physical.b
    rows, cols, values = [], [], []
    for i, j, sign in ((a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)):
        rows.append((3 * i[:, None, None] + np.arange(3)[None, :, None]).repeat(3, axis=2))
        cols.append((3 * j[:, None, None] + np.arange(3)[None, None, :]).repeat(3, axis=1))
        values.append(sign * blocks)
    diagonal = np.repeat(physical.solve_mass + h * physical.drag, 3)
    rows.append(np.arange(3 * count))
    cols.append(np.arange(3 * count))
    values.append(diagonal)
    for term_rows, term_cols, term_values in terms.matrix_entries(physical, x, v, h):
        rows.append(term_rows)
        cols.append(term_cols)
        values.append(term_values)
    matrix = sparse.coo_matrix((np.concatenate([v.ravel() for v in values]),
                                (np.concatenate([r.ravel() for r in rows]),
                                 np.concatenate([c.ravel() for c in cols]))),
                               shape=(3 * count, 3 * count))
    return matrix.tocsr()


def solve_reduced(matrix, rhs, held, basis):
    """u with Q^T (A u - rhs) = 0 and u = Q w + held: the components ``basis`` (Q, orthonormal
    columns) spans solved, the others held (gradients/implicit_contact.py's constraints)."""
    reduced = (basis.T @ matrix @ basis).tocsc()
    b = basis.T @ (rhs.ravel() - matrix @ held.ravel())
    if not b.any():
        return held.copy()
    if b.size <= DIRECT_LIMIT:
        # the matrix is symmetric: an ordering of A + A^T fills in less than COLAMD's
        w = linalg.spsolve(reduced, b, permc_spec="MMD_AT_PLUS_A")
    else:
        diagonal = reduced.diagonal()
        preconditioner = linalg.LinearOperator(reduced.shape, matvec=lambda r: r / diagonal)
        w, _ = linalg.cg(reduced, b, rtol=ADJOINT_TOLERANCE, atol=0.0, maxiter=10 * b.size,
                         M=preconditioner)
    return (basis @ w).reshape(held.shape) + held


def rhs_vjp(physical, h, start, estimate, dv, first, lam, start_bar, estimate_bar, bar):
    """Add lam . d(newton_rhs)/d(x, v, x_k, v_k, parameters) into ``start_bar`` (x_bar, v_bar),
    ``estimate_bar`` (xk_bar, vk_bar) and ``bar``, for the step's ``start`` (x, v) and the
    Newton ``estimate`` (x_k, v_k); its -M dv term aside (the caller's: it also takes dv's
    cotangent)."""
    (x, v), (x_k, v_k) = start, estimate
    (x_bar, v_bar), (xk_bar, vk_bar) = start_bar, estimate_bar
    spring_forces_vjp(physical, x_k, v_k, h * lam, xk_bar, vk_bar, bar)
    free = physical.free
    bar.gravity += h * (physical.mass[free, None] * lam[free]).sum(axis=0)
    bar.mass += np.where(free, h * lam @ physical.gravity - np.einsum("ij,ij->i", lam, dv), 0.0)
    bar.drag -= h * np.einsum("ij,ij->i", lam, v_k)
    vk_bar -= h * physical.drag[:, None] * lam
    terms.external_forces_vjp(physical, x_k, v_k, h * lam, xk_bar, vk_bar, bar)
    if first:
        stiffness_product_vjp(physical, x, v, h * h * lam, x_bar, v_bar, bar)
        terms.first_iteration_rhs_vjp(physical, v, h, lam, v_bar, bar)


def estimate(x, v, dv, h, first):
    """The Newton estimate (x_k, v_k): (x, v) in the first iteration, else x + h (v + dv)."""
    if first:
        return x, v
    v_k = v + dv
    return x + h * v_k, v_k


def newton_rhs(physical, h, x, v, dv, first):
    """r_k = h (F(x_k, v_k) + m g - c v_k) - M dv_k (+ h^2 dF/dx(x) v in the first); F with
    the terms' forces."""
    x_k, v_k = estimate(x, v, dv, h, first)
    external = (np.where(physical.free[:, None], physical.mass[:, None] * physical.gravity, 0.0)
                - physical.drag[:, None] * v_k + terms.external_forces(physical, x_k, v_k))
    rhs = h * (spring_forces(physical, x_k, v_k) + external) - physical.solve_mass[:, None] * dv
    if first:
        rhs += (h * h * stiffness_product(physical, x, v)
                + terms.first_iteration_rhs(physical, v, h))
    return rhs


def newton_estimates(physical, h, x, v, dv_end, iterations, solver):
    """[dv_0 = 0, dv_1, ..., dv_K = dv_end]: the velocity changes after each Newton iteration,
    the last as the simulation computed it, the others solved again (``solver``: a
    ForwardSolver). With dv_end None the last is solved again too."""
    dv = [np.zeros_like(x)]
    for k in range(iterations - (1 if dv_end is not None else 0)):
        x_k, v_k = estimate(x, v, dv[-1], h, k == 0)
        rhs = newton_rhs(physical, h, x, v, dv[-1], k == 0)
        solver.assemble(physical, x_k, v_k, h)
        dv.append(dv[-1] + solver.solve(rhs))
    if dv_end is not None:
        dv.append(dv_end)
    return dv


def system_vjp_iteration(physical, h, x, v, dv, dv_next, first, dv_bar, x_bar, v_bar, bar,
                         solver):
    """The adjoint of dv_next = dv + A(x_k)^-1 r_k: adds the cotangents of x, v and the
    parameters, returns that of dv."""
    x_k, v_k = estimate(x, v, dv, h, first)
    solver.assemble(physical, x_k, v_k, h)
    lam = solver.solve(dv_bar)          # A symmetric: A^-T = A^-1
    return iteration_vjp(physical, h, x, v, dv, dv_next - dv, first, lam, dv_bar, x_bar, v_bar,
                         bar)


def iteration_vjp(physical, h, x, v, dv, ddv, first, lam, dv_bar, x_bar, v_bar, bar):
    """system_vjp_iteration after its solve: ``lam`` = A^-1 dv_bar, ``ddv`` the iteration's
    solution. Adds the cotangents of x, v and the parameters, returns that of dv."""
    x_k, v_k = estimate(x, v, dv, h, first)
    xk_bar, vk_bar = np.zeros_like(x), np.zeros_like(x)
    # r_k's share
    rhs_vjp(physical, h, (x, v), (x_k, v_k), dv, first, lam, (x_bar, v_bar), (xk_bar, vk_bar),
            bar)
    dv_bar = dv_bar - physical.solve_mass[:, None] * lam
    # A_k's share: the cotangent of A is -lambda ddv^T
    system_product_vjp(physical, x_k, ddv, -lam, h, xk_bar, bar)
    terms.product_vjp(physical, x_k, v_k, h, ddv, -lam, xk_bar, vk_bar, bar)
    x_bar += xk_bar
    v_bar += vk_bar
    if not first:   # x_k = x + h (v + dv), v_k = v + dv
        v_bar += h * xk_bar
        dv_bar = dv_bar + h * xk_bar + vk_bar
    return dv_bar
