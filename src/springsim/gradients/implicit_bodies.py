"""Backward Euler's body-body contact in the adjoint: the solve's penalty springs
(collision/response/penalty.py) and their friction after the solve
(collision/response/solve_friction.py), then the post-step pass (body_contact.py).

The forward, for surfaces of two bodies (integrators/implicit_euler.py):

    contacts        every pair the step can bring together (contact_sets/solve.py)
    per Newton iteration k, at the estimate e_k = x + h (v + dv_k):
      linearize     each pair's stencil c and normal n at e_k, its gap g = n . sum_i c_i e_i - R,
                    its coefficient h^2 k = STIFFNESS / sum_i c_i^2 / m_i; active if g < 0
      solve         (A_k + sum_active h^2 k J^T J) ddv = r_k - sum_active c_i (h^2 k) g / h n,
                    J = n^T sum_i c_i e_i; the active set updated from phi = g + h J ddv and
                    solved again (at most MAX_CONTACT_UPDATES times)
    end             friction against each active contact's push h k (-phi), phi at the step's
                    end x + h v_K, in the impulses' Jacobi passes; x' = x + h v
    post-step pass  impulses and overlap correction (body_contact.respond)

``replay`` runs it again with the forward's own kernels for the contact set, the linearization
and the solves (so the active sets are the forward's), and keeps what the adjoint needs;
``adjoint`` goes back through it. Each solve's adjoint is one solve with the same matrix,
contacts included: lambda = A^-1 dv_bar; the cotangent of the contacts' matrix is
-lambda ddv^T and of their right-hand side lambda, which reach the coefficients, gaps, stencils
and normals, and through the stencils' closest points (complex step, as body_contact.py) the
estimate's and the start's positions. The active set, the closest-point regions and the
sides are the branches the run took.

Covered: point-triangle and edge-edge contacts of two bodies' surfaces and of a self-colliding
body's own (collision/pair_lists/own_pairs.py: those in contact at the step's start, and those
an iteration's solve brings into contact, after which the forward solves that iteration again
with them, as ``PenaltyStep.regrow`` does), and a ball's contacts with a particle, a sheet
triangle (at its closest point, or at its centre and corners where the ball is larger than it)
or another ball, with the ball's friction after the solve (none between two balls). In a step
in which particles also touch a terrain, the terrain replay (implicit_replay.py) takes the
contacts beside its constraints through ``PenaltyStep``, and takes an iteration again for grown
own pairs as this replay does (implicit_contact.Iteration.again).
"""
from typing import NamedTuple

import numpy as np

from ..collision.contact_sets import (BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE, PASSES,
                                      SolveContacts)
from ..collision.contact_sets.solve import find_solve_contacts
from ..collision.pair_lists.keeping import start_surface_pairs
from ..collision.pair_lists.own_pairs import (MOST_OWN_REDOS, OwnPairs, grown_own_pairs,
                                              own_pairs_touching)
from ..collision.pair_lists.solve_pairs import kept_surface_pairs
from ..collision.response.penalty import (STIFFNESS, linearize_contacts,
                                          newton_iterations_needed, update_active_contacts)
from ..integrators.implicit_euler import MAX_CONTACT_UPDATES
from .body_contact import (Contacts, check_replayed, far_from_bodies, gather, impulse_passes,
                           mobilities, respond, surface_params)
from .stencil_geometry import STEP, dot, solve_stencil, stencil_branches
from .body_contact_adjoint import Bars, dot4, impulse_passes_vjp, mobility_vjp, respond_vjp
from .attachments import hold, hold_vjp, holds
from .pins import place, release
from .solve import estimate, iteration_vjp, newton_rhs


class Linearized(NamedTuple):
    """One Newton iteration: where it started and the contacts as its last solve had them."""

    dv: np.ndarray          # (P, 3) the estimate's velocity change
    first: bool
    contacts: SolveContacts   # copies: weights, normal, gap, coefficient, active at its end
    ddv: np.ndarray         # (P, 3) its solution


class Friction(NamedTuple):
    """The friction after the solve: its stencils (rows of the last iteration's contacts)."""

    rows: np.ndarray        # the active contacts
    phi: np.ndarray         # (R,) their gaps at the step's end before it
    pushed: np.ndarray      # (R,) N s: their pushes
    contacts: Contacts      # as the impulse passes take them
    count: np.ndarray       # (P,) contacts per particle
    mobility: np.ndarray
    passes: list


class Replay(NamedTuple):
    iterations: list        # [Linearized]
    x_before: np.ndarray    # (P, 3) x + h v_K, before the friction
    v_end: np.ndarray       # (P, 3) v_K
    friction: Friction
    x_end: np.ndarray       # (P, 3) x + h v after the friction: the post-step pass's input
    v_after: np.ndarray
    response: object        # body_contact.Response or None
    held: object = None     # attachments.Held: the hard attachments held before the pass


def touches_bodies(physical, h, start, end) -> bool:
    """Whether the step from ``start`` to ``end`` may have had body-body contact: some pair
    within reach at its end, or at the start's prediction x + h v (body_contact.far_from_bodies
    for both)."""
    if not physical.bodies.collide:
        return False
    predicted = (start[0] + h * start[1], start[1])
    return not (far_from_bodies(physical, h, start, end)
                and far_from_bodies(physical, h, start, predicted))


def copy_contacts(contacts):
    return SolveContacts(*(np.array(part) for part in contacts))


def replay(physical, integrator, solver, h, x, v):
    """The step as the forward took it (module doc): (x', v', Replay)."""
    penalty = PenaltyStep(physical, h, x, v, integrator.newton_iterations)
    dv = np.zeros_like(x)
    k = 0
    while k < penalty.needed:
        first = k == 0
        x_k, v_k = estimate(x, v, dv, h, first)
        rhs = newton_rhs(physical, h, x, v, dv, first)
        solver.assemble(physical, x_k, v_k, h)
        penalty.linearize(dv)
        ddv = solver.solve(np.ascontiguousarray(rhs + penalty.rhs), penalty.contacts)
        for _ in range(MAX_CONTACT_UPDATES):
            if not penalty.update(ddv):
                break
            ddv = solver.solve(np.ascontiguousarray(rhs + penalty.rhs), penalty.contacts)
        if penalty.regrow(dv, ddv):
            continue   # the iteration again, from where it started, with the grown set
        penalty.keep(dv, first, ddv)
        dv = dv + ddv
        k += 1
    v_end = v + dv
    v_after, friction, x_before = penalty_end(physical, penalty, h, x, v_end)
    x_end, v_after = place(physical, x + h * v_after, v_after)   # the post-step pass's start
    x_held, v_held, held = x_end, v_after, None
    if holds(physical):   # the hard attachments, before the pass (_steps.collide)
        x_held, v_held, held = hold(physical, x_end, v_after)
    x_out, v_out, response = respond(physical, x_held, v_held, x)
    return x_out, v_out, Replay(penalty.iterations, x_before, v_end, friction, x_end, v_after,
                                response, held)


def is_ball(shape):
    return (shape == BALL_POINT) | (shape == BALL_TRIANGLE) | (shape == BALL_SAMPLE)


def end_friction(physical, contacts, x_end, h):
    """solve_friction.apply_contact_friction's contacts: the active ones but two balls', their
    gaps at x_end, their pushes and parameters (surfaces: the means of the two bodies' keys; a
    ball against a particle or a sheet: the ball's particle friction)."""
    bodies = physical.bodies
    two_balls = (contacts.shape == BALL_POINT) & (bodies.ball_slot[contacts.nodes[:, 1]] >= 0)
    rows = np.flatnonzero(contacts.active & ~two_balls)
    nodes, c, n = contacts.nodes[rows], contacts.weights[rows], contacts.normal[rows]
    phi = dot(gather(c, nodes, x_end), n) - contacts.rest[rows]
    pushed = contacts.coefficient[rows] * np.maximum(-phi, 0.0) / h
    params = surface_params(bodies, bodies.body[nodes[:, 0]], bodies.body[nodes[:, 3]])
    ball = is_ball(contacts.shape[rows])
    friction = bodies.particle_friction[bodies.ball_slot[nodes[ball, 0]]]
    params[ball] = np.column_stack([np.zeros_like(friction), friction, friction,
                                    np.zeros_like(friction), np.ones_like(friction),
                                    np.full_like(friction, PASSES)])
    count, mobility = mobilities(physical.inv_mass, nodes, c)
    return Friction(rows, phi, pushed, Contacts(nodes, c, n, np.zeros(len(rows)), params, None),
                    count, mobility, [])


def rub(physical, friction, v):
    """response/impulses.apply_friction: the friction passes against the pushes."""
    v, passes, _ = impulse_passes(physical.inv_mass, v, friction.contacts, friction.mobility,
                                  friction.pushed, push=False)
    return v, friction._replace(passes=passes)


def check_solved(replayed, end, h, tolerance):
    """Refuse a step whose replay does not end where the forward did (body_contact
    .check_replayed): one the forward took in halves (a surface carried through another), or
    whose active set came out otherwise. The replay's solves start from zero, the forward's
    from the last step's change, so the two agree to about the CG ``tolerance``: allowed a
    thousand times that, relative to the fastest speed."""
    allowed = max(1e-9, 1e3 * tolerance) * max(1.0, float(np.abs(end[1]).max()))
    check_replayed(replayed, end, h, allowed, "took a step under implicit_euler with body-body "
                   "contact that the gradient cannot follow (taken in halves, or its contacts "
                   "changed within the solve's tolerance): try a smaller dt or a tighter "
                   "cg_tolerance")


# ---- the adjoint ------------------------------------------------------------------------------

def adjoint(physical, h, x, v, replayed, x_bar, v_bar, bar, solver):
    """The cotangents of (x, v) at the step's start from those after it (module doc)."""
    x_bar, v_bar = x_bar.copy(), v_bar.copy()
    start_bar = np.zeros_like(x)
    if replayed.response is not None:
        x_bar, v_bar, start_bar = respond_vjp(physical, replayed.response, x_bar, v_bar, bar)
    if replayed.held is not None:
        x_bar, v_bar = hold_vjp(physical, replayed.held, x_bar, v_bar, bar)
    release(physical, x_bar, v_bar)      # the pins on paths were placed before the pass
    out_x = start_bar + x_bar            # x' = x + h v_after
    v_after_bar = v_bar + h * x_bar
    last = replayed.iterations[-1]
    geometry_bars = contact_bars(last.contacts)
    v_end_bar = friction_vjp(physical, replayed.friction, last.contacts, replayed.x_before,
                             v_after_bar, geometry_bars, out_x, h, bar)
    out_v = v_end_bar.copy()             # v_K = v + dv_K
    dv_bar = v_end_bar
    for k in reversed(range(len(replayed.iterations))):
        one = replayed.iterations[k]
        bars = geometry_bars if k == len(replayed.iterations) - 1 else contact_bars(one.contacts)
        x_k, v_k = estimate(x, v, one.dv, h, one.first)
        solver.assemble(physical, x_k, v_k, h)
        lam = solver.solve(np.ascontiguousarray(dv_bar), one.contacts)
        penalty_vjp(one.contacts, lam, one.ddv, h, bars)
        dv_bar = iteration_vjp(physical, h, x, v, one.dv, one.ddv, one.first, lam, dv_bar,
                               out_x, out_v, bar)
        estimate_bar = linearization_vjp(physical, one.contacts, x, v, one.dv, h, bars, out_x,
                                         bar)
        out_x += estimate_bar   # e_k = x + h (v + dv_k)
        out_v += h * estimate_bar
        dv_bar = dv_bar + h * estimate_bar
    return out_x, out_v


class SolveBars(NamedTuple):
    """The cotangents of a solve's contact set, gathered on the way back before they go to the
    positions and masses (linearization_vjp)."""

    weights: np.ndarray       # (K, 4)
    normal: np.ndarray        # (K, 3)
    gap: np.ndarray           # (K,)
    coefficient: np.ndarray   # (K,) of h^2 k


def contact_bars(contacts):
    """Zeroed SolveBars of a contact set."""
    count = len(contacts.nodes)
    return SolveBars(np.zeros((count, 4)), np.zeros((count, 3)), np.zeros(count),
                     np.zeros(count))


def friction_vjp(physical, friction, linearized, x_before, v_bar, bars, x_bar, h, bar):
    """Back through the friction passes and the pushes they took (end_friction: the last
    iteration's contacts ``linearized``, their gaps at ``x_before``); returns the cotangent of
    v_K; the gaps' share goes to x_bar and the contacts' SolveBars ``bars``."""
    if not len(friction.rows):
        return v_bar
    rows, contacts = friction.rows, friction.contacts
    count = len(rows)
    rub_bars = Bars(np.zeros((count, 4)), np.zeros((count, 3)), np.zeros(count),
                    np.zeros(count), np.zeros(len(v_bar)), np.zeros(count), np.zeros(count))
    v_bar = v_bar.copy()
    pushed_bar = impulse_passes_vjp(physical, contacts, friction.mobility, friction.passes,
                                    v_bar, rub_bars)
    mobility_vjp(physical, contacts, friction.count, rub_bars)
    bar.mass += np.where(physical.free, -rub_bars.inv_mass * physical.inv_mass ** 2, 0.0)
    bodies, ball = physical.bodies, is_ball(linearized.shape[rows])
    for side in (0, 3):   # a surface contact's friction is the mean of its two bodies'
        np.add.at(bar.body_friction, bodies.body[contacts.nodes[~ball, side]],
                  0.5 * rub_bars.kinetic[~ball])
    np.add.at(bar.particle_friction, bodies.ball_slot[contacts.nodes[ball, 0]],
              rub_bars.kinetic[ball])
    pressing = friction.phi < 0.0
    coefficient = linearized.coefficient[rows]
    bars.coefficient[rows] += np.where(pressing, -friction.phi / h * pushed_bar, 0.0)
    phi_bar = np.where(pressing, -coefficient / h * pushed_bar, 0.0)
    # phi = n . sum_i c_i x_end[n_i] - R, x_end = x + h v_K
    along = gather(contacts.weights, contacts.nodes, x_before)
    bars.normal[rows] += phi_bar[:, None] * along
    bars.weights[rows] += rub_bars.weights + phi_bar[:, None] * np.einsum(
        "kjc,kc->kj", x_before[contacts.nodes], contacts.normal)
    bars.normal[rows] += rub_bars.normal
    end_bar = np.zeros_like(v_bar)
    np.add.at(end_bar, contacts.nodes.ravel(), (contacts.weights[:, :, None] * (
        phi_bar[:, None] * contacts.normal)[:, None, :]).reshape(-1, 3))
    x_bar += end_bar
    return v_bar + h * end_bar


def penalty_vjp(contacts, lam, ddv, h, bars):
    """The active contacts' share of the solve's adjoint: matrix sum h^2k J^T J (cotangent
    -lambda ddv^T), right-hand side -c_i h^2k g / h n (cotangent lambda)."""
    rows = np.flatnonzero(contacts.active)
    nodes, c, n = contacts.nodes[rows], contacts.weights[rows], contacts.normal[rows]
    k, g = contacts.coefficient[rows], contacts.gap[rows]
    lam_c, ddv_c = gather(c, nodes, lam), gather(c, nodes, ddv)   # sum_i c_i u_i
    j_lam, j_ddv = dot(n, lam_c), dot(n, ddv_c)
    push = -k * g / h
    bars.coefficient[rows] += -g / h * j_lam - j_lam * j_ddv
    bars.gap[rows] += -k / h * j_lam
    bars.normal[rows] += (push[:, None] * lam_c - k[:, None] * (j_ddv[:, None] * lam_c
                                                                 + j_lam[:, None] * ddv_c))
    n_lam = np.einsum("kjc,kc->kj", lam[nodes], n)
    n_ddv = np.einsum("kjc,kc->kj", ddv[nodes], n)
    bars.weights[rows] += (push[:, None] * n_lam
                           - k[:, None] * (j_ddv[:, None] * n_lam + j_lam[:, None] * n_ddv))


def linearization_vjp(physical, contacts, x, v, dv, h, bars, x_bar, bar):
    """Back through linearize_contacts for the contacts whose cotangents ``bars`` (SolveBars)
    holds: the coefficient's masses and stencil, the gap's
    estimate and stencil, the stencil's and normal's closest points. Returns the estimate's
    cotangent; the start's is added to x_bar."""
    rows = np.flatnonzero((bars.coefficient != 0.0) | (bars.gap != 0.0)
                          | np.any(bars.weights != 0.0, axis=1) | np.any(bars.normal != 0.0,
                                                                            axis=1))
    estimate_bar = np.zeros_like(x)
    if not len(rows):
        return estimate_bar
    nodes, c, n = contacts.nodes[rows], contacts.weights[rows], contacts.normal[rows]
    inv = physical.inv_mass[nodes]
    k = contacts.coefficient[rows]
    e = x + h * (v + dv)
    # k = STIFFNESS / sum_i c_i^2 w_i
    k_bar = bars.coefficient[rows]
    shared = -k * k / STIFFNESS * k_bar
    c_bar = bars.weights[rows] + 2.0 * shared[:, None] * c * inv
    inv_bar = np.zeros(len(x))
    np.add.at(inv_bar, nodes.ravel(), (shared[:, None] * c * c).ravel())
    bar.mass += np.where(physical.free, -inv_bar * physical.inv_mass ** 2, 0.0)
    # g = n . sum_i c_i e_i - R
    g_bar = bars.gap[rows]
    n_bar = bars.normal[rows] + g_bar[:, None] * gather(c, nodes, e)
    c_bar += g_bar[:, None] * np.einsum("kjc,kc->kj", e[nodes], n)
    np.add.at(estimate_bar, nodes.ravel(), (c[:, :, None] * (g_bar[:, None] * n)[:, None, :])
              .reshape(-1, 3))
    e4, s4 = e[nodes], x[nodes]
    flipped, face, region, sign = stencil_branches(contacts.shape[rows], c, n, e4, s4)
    e4_bar, s4_bar = np.zeros(e4.shape), np.zeros(s4.shape)
    for which, positions, out in ((0, e4, e4_bar), (1, s4, s4_bar)):
        z = positions.astype(complex)
        other = s4 if which == 0 else e4
        for corner in range(4):
            for axis in range(3):
                z[:, corner, axis] += 1j * STEP
                pair = (z, other) if which == 0 else (other, z)
                weights, normal = solve_stencil(contacts.shape[rows], flipped, face, region,
                                                sign, *pair)
                z[:, corner, axis] -= 1j * STEP
                out[:, corner, axis] = (dot4(c_bar, weights.imag)
                                        + dot(n_bar, normal.imag)) / STEP
    np.add.at(estimate_bar, nodes.ravel(), e4_bar.reshape(-1, 3))
    np.add.at(x_bar, nodes.ravel(), s4_bar.reshape(-1, 3))
    return estimate_bar


# ---- with terrain contact in the same step (implicit_replay.py takes these) --------------------

def own_pairs_at(bodies, x):
    """(a self-colliding body's own pairs in contact at x, the post-step pair list they came
    from; any list gives the same set), or none without such a body (no search)."""
    if not bodies.own:
        none = np.empty((0, 2), np.int64)
        return OwnPairs(none, none), None
    x = np.ascontiguousarray(x)
    return own_pairs_touching(bodies.arrays, x, start_surface_pairs(bodies.arrays, x))


class PenaltyStep:
    """A step's penalty contacts as the terrain replay (implicit_replay.replay) takes them,
    beside its constraints: the contact set, linearized each Newton iteration, its matrix and
    right-hand side for the active set of each solve, and its friction after the solve."""

    def __init__(self, physical, h, x, v, requested):
        self.physical, self.h, self.x, self.v = physical, h, x, v
        arrays = physical.bodies.arrays
        self.own, self.pairs = own_pairs_at(physical.bodies, x)
        self.redone = 0
        self.contacts = self.found()
        self.needed = newton_iterations_needed(arrays, self.contacts, np.ascontiguousarray(v),
                                               h, requested)
        self.rhs = np.zeros_like(x)
        self.iterations = []   # [Linearized], the active set of the iteration's last solve

    def found(self):
        """The contact set: find_solve_contacts with the own pairs found so far."""
        return find_solve_contacts(self.physical.bodies.arrays, np.ascontiguousarray(self.x),
                                   np.ascontiguousarray(self.v), self.h,
                                   kept_surface_pairs(self.x), self.own)

    def regrow(self, dv, ddv):
        """After an iteration's solves (implicit_euler.own_pairs_met): whether the own pairs in
        contact at x + h (v + dv + ddv) grew, and then the contact set with them, for the
        iteration to be solved again (MOST_OWN_REDOS times a step at most)."""
        if self.redone >= MOST_OWN_REDOS or not self.physical.bodies.own:
            return False
        v_k = (self.v + dv) + ddv
        own, grew, self.pairs = grown_own_pairs(self.physical.bodies.arrays,
                                                np.ascontiguousarray(self.x + self.h * v_k),
                                                self.pairs, self.own)
        if not grew:
            return False
        self.own, self.redone = own, self.redone + 1
        self.contacts = self.found()
        return True

    def linearize(self, dv):
        """Linearize the contacts about x + h (v + dv); returns their right-hand side."""
        self.rhs = np.zeros_like(self.x)
        linearize_contacts(self.physical.bodies.arrays, self.contacts, self.x, self.v,
                           np.ascontiguousarray(dv), self.h, self.rhs)
        return self.rhs

    def matrix(self, active=None):
        """sum_active h^2 k J^T J as a sparse (3P, 3P) matrix (the active set ``active``, or
        the present one)."""
        return penalty_matrix(self.contacts, self.contacts.active if active is None else active,
                              len(self.x))

    def update(self, ddv):
        """update_active_contacts after a solve: whether the active set changed (the
        right-hand side follows it)."""
        return update_active_contacts(self.contacts, self.h, np.ascontiguousarray(ddv),
                                      self.rhs) > 0

    def keep(self, dv, first, ddv):
        self.iterations.append(Linearized(dv, first, copy_contacts(self.contacts), ddv))

    def with_active(self, k, active):
        """Iteration k's contacts with the active set ``active``."""
        return self.iterations[k].contacts._replace(active=active)


def penalty_matrix(contacts, active, count):
    from scipy import sparse

    rows = np.flatnonzero(active)
    nodes, c, n = contacts.nodes[rows], contacts.weights[rows], contacts.normal[rows]
    columns = (3 * nodes[:, :, None] + np.arange(3)[None, None, :]).reshape(len(rows), 12)
    values = (c[:, :, None] * n[:, None, :]).reshape(len(rows), 12)
    jacobian = sparse.csr_matrix((values.ravel(), columns.ravel(),
                                  np.arange(0, 12 * len(rows) + 1, 12)),
                                 shape=(len(rows), 3 * count))
    return (jacobian.T @ sparse.diags(contacts.coefficient[rows]) @ jacobian).tocsr()


def penalty_end(physical, penalty, h, x, v_end):
    """The friction after the solve (end_friction, rub) on v_K: (v after it, Friction)."""
    x_before = x + h * v_end
    friction = end_friction(physical, penalty.iterations[-1].contacts, x_before, h)
    if len(friction.rows):
        v_end, friction = rub(physical, friction, v_end)
    return v_end, friction, x_before
