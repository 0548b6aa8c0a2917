"""Backward Euler's Newton iterations, solved again where the adjoint needs them, and the adjoint
of one iteration (adjoints.ImplicitEulerAdjoint).

The linear solves here are on the free particles only (a pinned particle's rows are filtered out
of the forward solve: implicit/constraints.py), with the same matrix A = M + h c - h dF/dv
- h^2 dF/dx (clamped: physics.system_product) assembled as a sparse matrix. They are solved to
ADJOINT_TOLERANCE, far below the forward's CG tolerance: the adjoint is the derivative of the
linearized step, treating the forward solve as exact (its CG residual is the gradient's error,
of the tolerance's order).
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

ADJOINT_TOLERANCE = 1e-12   # relative residual of the adjoint's CG solves
DIRECT_LIMIT = 6000         # unknowns up to which a sparse LU solves (exact, and quick there)


def system_matrix(physical, x, h):
    """A at x as a sparse (3P, 3P) matrix: the diagonal masses and drag, and every spring's
    block C = p l l^T + q I added to (a, a), (b, b) and subtracted from (a, b), (b, a)."""
    count = x.shape[0]
    springs = geometry(physical, x)
    along, across, _, _, _ = stiffness_coefficients(physical, springs)
    real = springs.length > 0.0
    p = (h * physical.kd + h * h * along) * real
    q = h * h * across * real
    l = springs.unit
    blocks = p[:, None, None] * l[:, :, None] * l[:, None, :] + q[:, None, None] * np.eye(3)
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
    matrix = sparse.coo_matrix((np.concatenate([v.ravel() for v in values]),
                                (np.concatenate([r.ravel() for r in rows]),
                                 np.concatenate([c.ravel() for c in cols]))),
                               shape=(3 * count, 3 * count))
    return matrix.tocsr()


def solve_free(physical, matrix, rhs):
    """u with A u = rhs on the free particles' components, zero on the pinned ones."""
    free = np.repeat(physical.free, 3)
    reduced = matrix[free][:, free]
    b = rhs.ravel()[free]
    u = np.zeros(rhs.size)
    if not b.any():
        return u.reshape(rhs.shape)
    if b.size <= DIRECT_LIMIT:
        u[free] = linalg.spsolve(reduced.tocsc(), b)
    else:
        diagonal = reduced.diagonal()
        preconditioner = linalg.LinearOperator(reduced.shape, matvec=lambda r: r / diagonal)
        solution, _ = linalg.cg(reduced, b, rtol=ADJOINT_TOLERANCE, atol=0.0, maxiter=10 * b.size,
                                M=preconditioner)
        u[free] = solution
    return u.reshape(rhs.shape)


def solve_reduced(matrix, rhs, held, basis):
    """u with Q^T (A u - rhs) = 0 and u = Q w + held: the components ``basis`` (Q, orthonormal
    columns) spans solved, the others held (gradients/implicit_contact.py's constraints)."""
    reduced = (basis.T @ matrix @ basis).tocsc()
    b = basis.T @ (rhs.ravel() - matrix @ held.ravel())
    if not b.any():
        return held.copy()
    if b.size <= DIRECT_LIMIT:
        w = linalg.spsolve(reduced, b)
    else:
        diagonal = reduced.diagonal()
        preconditioner = linalg.LinearOperator(reduced.shape, matvec=lambda r: r / diagonal)
        w, _ = linalg.cg(reduced, b, rtol=ADJOINT_TOLERANCE, atol=0.0, maxiter=10 * b.size,
                         M=preconditioner)
    return (basis @ w).reshape(held.shape) + held


def rhs_vjp(physical, h, x, v, x_k, v_k, dv, first, lam, x_bar, v_bar, xk_bar, vk_bar, bar):
    """Add lam . d(newton_rhs)/d(x, v, x_k, v_k, parameters), its -M dv term aside (the
    caller's: it also takes dv's cotangent)."""
    spring_forces_vjp(physical, x_k, v_k, h * lam, xk_bar, vk_bar, bar)
    free = physical.free
    bar.gravity += h * (physical.mass[free, None] * lam[free]).sum(axis=0)
    bar.mass += np.where(free, h * lam @ physical.gravity - np.einsum("ij,ij->i", lam, dv), 0.0)
    bar.drag -= h * np.einsum("ij,ij->i", lam, v_k)
    vk_bar -= h * physical.drag[:, None] * lam
    if first:
        stiffness_product_vjp(physical, x, v, h * h * lam, x_bar, v_bar, bar)


def estimate(x, v, dv, h, first):
    """The Newton estimate (x_k, v_k): (x, v) in the first iteration, else x + h (v + dv)."""
    if first:
        return x, v
    v_k = v + dv
    return x + h * v_k, v_k


def newton_rhs(physical, h, x, v, dv, first):
    """r_k = h (F(x_k, v_k) + m g - c v_k) - M dv_k (+ h^2 dF/dx(x) v in the first)."""
    x_k, v_k = estimate(x, v, dv, h, first)
    external = (np.where(physical.free[:, None], physical.mass[:, None] * physical.gravity, 0.0)
                - physical.drag[:, None] * v_k)
    rhs = h * (spring_forces(physical, x_k, v_k) + external) - physical.solve_mass[:, None] * dv
    if first:
        rhs += h * h * stiffness_product(physical, x, v)
    return rhs


def newton_estimates(physical, h, x, v, dv_end, iterations, tolerance):
    """[dv_0 = 0, dv_1, ..., dv_K = dv_end]: the velocity changes after each Newton iteration,
    the last as the simulation computed it, the others solved again."""
    dv = [np.zeros_like(x)]
    for k in range(iterations - 1):
        x_k, _ = estimate(x, v, dv[-1], h, k == 0)
        rhs = newton_rhs(physical, h, x, v, dv[-1], k == 0)
        dv.append(dv[-1] + solve_free(physical, system_matrix(physical, x_k, h), rhs))
    dv.append(dv_end)
    return dv


def system_vjp_iteration(physical, h, x, v, dv, dv_next, first, dv_bar, x_bar, v_bar, bar):
    """The adjoint of dv_next = dv + A(x_k)^-1 r_k: adds the cotangents of x, v and the
    parameters, returns that of dv."""
    x_k, v_k = estimate(x, v, dv, h, first)
    matrix = system_matrix(physical, x_k, h)
    lam = solve_free(physical, matrix, dv_bar)          # A symmetric: A^-T = A^-1
    ddv = dv_next - dv
    xk_bar, vk_bar = np.zeros_like(x), np.zeros_like(x)
    # r_k's share
    rhs_vjp(physical, h, x, v, x_k, v_k, dv, first, lam, x_bar, v_bar, xk_bar, vk_bar, bar)
    dv_bar = dv_bar - physical.solve_mass[:, None] * lam
    # A_k's share: the cotangent of A is -lambda ddv^T
    system_product_vjp(physical, x_k, ddv, -lam, h, xk_bar, bar)
    x_bar += xk_bar
    v_bar += vk_bar
    if not first:   # x_k = x + h (v + dv), v_k = v + dv
        v_bar += h * xk_bar
        dv_bar = dv_bar + h * xk_bar + vk_bar
    return dv_bar
