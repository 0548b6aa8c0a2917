"""Attachments (attachments.py) in the adjoint, as differentiable NumPy.

Binding a is a stencil of four particles n_a (the bound particle, then its triangle's corners)
and weights c_a that sum to zero: d = sum_j c_j x_{n_j} runs from the triangle's point to the
particle.

- A soft binding (stiffness k > 0, damping kd) is a spring of zero rest length,
  f_j = -c_j (k d + kd d'), in every force evaluation (``attachment_forces``); in backward
  Euler's matrix it is (h kd + h^2 k) c_i c_j I in block (n_i, n_j) (``attachment_product``,
  ``matrix_entries``), and -h^2 k c_j d'(v) in the first iteration's right-hand side. Its
  stiffness and damping are parameters (``attachments.N.stiffness``, ``.damping``).
- A hard binding is projected after every step (``hold``), binding after binding, sweep after
  sweep: each projection is the linear map x -> x - u (c . x), u_j = c_j / m_j / S,
  S = sum_i c_i^2 / m_i. Its adjoint (``hold_vjp``) applies the transposes in reverse order, and
  passes the masses their share through u; the sweeps are the forward's, found again by
  running the projection from the state before it.
"""
from typing import NamedTuple

import numpy as np

from ..attachments import HOLD_SWEEPS, HOLD_TOLERANCE
from ..terms.adjoint import AdjointTerm


def soft(physical) -> np.ndarray:
    return physical.attachment_stiffness > 0.0


def holds(physical) -> bool:
    """Whether some binding is hard."""
    return bool((~soft(physical)).any())


def stencils(physical, rows):
    return physical.attachment_nodes[rows], physical.attachment_weights[rows]


def gaps(physical, x, rows) -> np.ndarray:
    """d = sum_j c_j x_{n_j} for the bindings ``rows`` (positions or velocities), (R, 3)."""
    nodes, c = stencils(physical, rows)
    return np.einsum("kj,kjc->kc", c, x[nodes])


def spread(physical, rows, values, out) -> None:
    """out[n_j] += c_j values for each binding of ``rows`` (values (R, 3))."""
    nodes, c = stencils(physical, rows)
    np.add.at(out, nodes, c[:, :, None] * values[:, None, :])


def attachment_forces(physical, x, v) -> np.ndarray:
    """Every soft binding's forces (N), (P, 3) (attachments.add_attachment_forces)."""
    out = np.zeros_like(x)
    rows = np.flatnonzero(soft(physical))
    if len(rows):
        f = -(physical.attachment_stiffness[rows, None] * gaps(physical, x, rows)
              + physical.attachment_damping[rows, None] * gaps(physical, v, rows))
        spread(physical, rows, f, out)
    return out


def attachment_forces_vjp(physical, x, v, g, x_bar, v_bar, bar) -> None:
    """Add g . d(attachment_forces)/d(x, v, stiffness, damping)."""
    rows = np.flatnonzero(soft(physical))
    if not len(rows):
        return
    pull = gaps(physical, g, rows)   # sum_j c_j g_{n_j}: what f = -(k d + kd d') meets
    spread(physical, rows, -physical.attachment_stiffness[rows, None] * pull, x_bar)
    spread(physical, rows, -physical.attachment_damping[rows, None] * pull, v_bar)
    bar.attachment_stiffness[rows] -= np.einsum("kc,kc->k", pull, gaps(physical, x, rows))
    bar.attachment_damping[rows] -= np.einsum("kc,kc->k", pull, gaps(physical, v, rows))


def first_iteration_rhs(physical, v, h) -> np.ndarray:
    """The soft bindings' share of the first Newton iteration's right-hand side,
    h^2 (dF/dx) v = -h^2 k c_j d'(v)."""
    out = np.zeros_like(v)
    rows = np.flatnonzero(soft(physical))
    if len(rows):
        along = h * h * physical.attachment_stiffness[rows, None] * gaps(physical, v, rows)
        spread(physical, rows, -along, out)
    return out


def first_iteration_rhs_vjp(physical, v, h, g, v_bar, bar) -> None:
    rows = np.flatnonzero(soft(physical))
    if not len(rows):
        return
    pull = gaps(physical, g, rows)
    spread(physical, rows, -h * h * physical.attachment_stiffness[rows, None] * pull, v_bar)
    bar.attachment_stiffness[rows] -= h * h * np.einsum("kc,kc->k", pull,
                                                        gaps(physical, v, rows))


def coupling(physical, rows, h) -> np.ndarray:
    """Each soft binding's h kd + h^2 k: its blocks are that times c_i c_j I."""
    return h * physical.attachment_damping[rows] + h * h * physical.attachment_stiffness[rows]


def attachment_product(physical, u, h) -> np.ndarray:
    """The soft bindings' part of backward Euler's matrix times u, (P, 3)."""
    out = np.zeros_like(u)
    rows = np.flatnonzero(soft(physical))
    if len(rows):
        spread(physical, rows, coupling(physical, rows, h)[:, None] * gaps(physical, u, rows),
               out)
    return out


def attachment_product_vjp(physical, u, g, h, bar) -> None:
    """Add g . d(attachment_product(u))/d(stiffness, damping), u held fixed."""
    rows = np.flatnonzero(soft(physical))
    if not len(rows):
        return
    meet = np.einsum("kc,kc->k", gaps(physical, g, rows), gaps(physical, u, rows))
    bar.attachment_stiffness[rows] += h * h * meet
    bar.attachment_damping[rows] += h * meet


def matrix_entries(physical, h):
    """(rows, columns, values) of the soft bindings' blocks in the (3P, 3P) matrix."""
    rows = np.flatnonzero(soft(physical))
    nodes, c = stencils(physical, rows)
    size = coupling(physical, rows, h)[:, None, None] * c[:, :, None] * c[:, None, :]
    axis = np.arange(3)
    row = 3 * nodes[:, :, None, None] + axis
    column = 3 * nodes[:, None, :, None] + axis
    shape = (len(rows), 4, 4, 3)
    return (np.broadcast_to(row, shape).ravel(), np.broadcast_to(column, shape).ravel(),
            np.broadcast_to(size[:, :, :, None], shape).ravel())


def attachment_diagonal(physical, count, h) -> np.ndarray:
    """Each particle's diagonal block from its soft bindings, (P, 3, 3): (h kd + h^2 k) c^2 I."""
    out = np.zeros((count, 3, 3))
    rows = np.flatnonzero(soft(physical))
    nodes, c = stencils(physical, rows)
    np.add.at(out, nodes, (coupling(physical, rows, h)[:, None] * c * c)[:, :, None, None]
              * np.eye(3))
    return out


def attachment_diagonal_vjp(physical, h, weights, bar) -> None:
    """Add d(sum_i weights_i : attachment_diagonal_i)/d(stiffness, damping)."""
    rows = np.flatnonzero(soft(physical))
    nodes, c = stencils(physical, rows)
    trace = np.einsum("kjii,kj->k", weights[nodes], c * c)
    bar.attachment_stiffness[rows] += h * h * trace
    bar.attachment_damping[rows] += h * trace


class Held(NamedTuple):
    """What ``hold`` did, for ``hold_vjp``: the hard bindings it projected and their u
    (``hard_shares``), and per projection, in order, the binding and its gap before it moved,
    for positions and for velocities."""

    rows: np.ndarray   # (R,)
    u: np.ndarray      # (R, 4)
    x_moves: list      # [(binding, d (3,))]
    v_moves: list


def hard_shares(physical):
    """The hard bindings that can move (some corner with mass), in order, and each one's
    u = c m^-1 / S (R, 4) (module doc)."""
    rows = np.flatnonzero(~soft(physical))
    nodes, c = stencils(physical, rows)
    inverse = physical.inv_mass[nodes]
    share = np.einsum("kj,kj->k", c * c, inverse)
    moving = share > 0.0
    return rows[moving], c[moving] * inverse[moving] / share[moving, None]


def project(physical, x, rows, u):
    """x with every binding of ``rows`` projected as attachments.project_bindings does, and
    the moves it made."""
    x, moves = x.copy(), []
    nodes, c = stencils(physical, rows)
    for _ in range(HOLD_SWEEPS):
        worst = 0.0
        for k in range(len(rows)):
            d = c[k] @ x[nodes[k]]
            worst = max(worst, float(np.abs(d).max()))
            x[nodes[k]] -= u[k][:, None] * d
            moves.append((k, d))
        if worst <= HOLD_TOLERANCE:
            break
    return x, moves


def hold(physical, x, v):
    """(x, v) with every hard binding held (attachments.hold_attachments), and a Held."""
    rows, u = hard_shares(physical)
    if not len(rows):
        return x, v, Held(rows, u, [], [])
    x, x_moves = project(physical, x, rows, u)
    v, v_moves = project(physical, v, rows, u)
    return x, v, Held(rows, u, x_moves, v_moves)


def hold_vjp(physical, held, x_bar, v_bar, bar):
    """The cotangents before ``hold`` from those after it (and the masses' share in bar)."""
    rows, u = held.rows, held.u
    u_bar = np.zeros_like(u)
    x_bar = project_vjp(physical, rows, u, held.x_moves, x_bar, u_bar)
    v_bar = project_vjp(physical, rows, u, held.v_moves, v_bar, u_bar)
    if len(rows):
        mass_share_vjp(physical, rows, u_bar, bar)
    return x_bar, v_bar


def project_vjp(physical, rows, u, moves, g, u_bar):
    """The transposes of the moves, last first: x' = x - u d, d = c . x."""
    g = g.copy()
    nodes, c = stencils(physical, rows)
    for k, d in reversed(moves):
        after = g[nodes[k]]
        u_bar[k] -= after @ d
        g[nodes[k]] -= c[k][:, None] * (u[k] @ after)
    return g


def mass_share_vjp(physical, rows, u_bar, bar):
    """u_j = c_j w_j / S, S = sum_i c_i^2 w_i, w = 1/m: the masses' share of u's cotangent."""
    nodes, c = stencils(physical, rows)
    w = physical.inv_mass[nodes]
    share = np.einsum("kj,kj->k", c * c, w)
    # du_j/dw_i = c_j delta_ij / S - c_j w_j c_i^2 / S^2
    w_bar = (u_bar * c / share[:, None]
             - (c * c) * (np.einsum("kj,kj,kj->k", u_bar, c, w) / share ** 2)[:, None])
    mass_bar = np.zeros_like(bar.mass)
    np.add.at(mass_bar, nodes, -w_bar * w * w)
    bar.mass += np.where(physical.free, mass_bar, 0.0)


class SoftAttachmentsAdjoint(AdjointTerm):
    """The soft bindings' derivative (terms/soft_attachments.py): they couple the four
    particles of each binding, so the matrix parts are their own."""

    @classmethod
    def acts(cls, physical) -> bool:
        return bool(soft(physical).any())

    # the functions above, whose arguments are the protocol's (terms/adjoint.py)
    forces, forces_vjp = staticmethod(attachment_forces), staticmethod(attachment_forces_vjp)
    first_iteration_rhs = staticmethod(first_iteration_rhs)
    first_iteration_rhs_vjp = staticmethod(first_iteration_rhs_vjp)

    @classmethod
    def diagonal_blocks(cls, physical, x, v, h):
        return attachment_diagonal(physical, len(x), h)

    @classmethod
    def diagonal_blocks_vjp(cls, physical, x, v, h, weights, x_bar, v_bar, bar) -> None:
        attachment_diagonal_vjp(physical, h, weights, bar)

    @classmethod
    def matrix_entries(cls, physical, x, v, h):
        return matrix_entries(physical, h)

    @classmethod
    def product_vjp(cls, physical, x, v, h, u, g, x_bar, v_bar, bar) -> None:
        attachment_product_vjp(physical, u, g, h, bar)

    @classmethod
    def add_forward_blocks(cls, solver, physical, x, v, h) -> None:
        """The forward's own kernel: the coupled blocks' slots are the solve layout's."""
        from ..attachments import add_attachment_jacobian

        if cls.acts(physical):
            add_attachment_jacobian(solver.arrays, solver.layout.attachment_slots, h, False, v,
                                    solver.blocks, solver.unused_rhs)
