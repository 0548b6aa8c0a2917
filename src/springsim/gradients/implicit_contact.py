"""Backward Euler's step with terrain contact (planes, spheres, bowls and meshes, still, moving
rigidly or deforming), replayed in NumPy, and its adjoint.

The forward (integrators/implicit_euler.py with implicit/constraints.py) holds each contact's
normal velocity at a floor and lets it slide along the surface against a friction damper c (N s/m)
that it chooses from the solve's own reaction impulses, a few passes a Newton iteration:

    find_constraints          kind, normal, floor of every particle; c carried from the last step
    per Newton iteration k:
      assemble                A_k = (the springs' matrix at x_k) + c_i (I - n n^T) on contacts
                              b_k = newton_rhs - c_i (I - n n^T) (v + dv - s)
                              (first iteration: a carried c capped to the friction cone)
      solve                   S (A ddv - b) = 0 with the contacts' normal components at their
                              floors (z) and the pinned particles' at zero
      update, solve again     R = A ddv - b: a contact with R . n < 0 is released, a free
                              particle that the solve carries into a terrain becomes a contact,
                              every other contact's c is chosen anew (coulomb_damping); solved
                              again while anything moved (at most MAX_CONTACT_UPDATES passes)
      dv += ddv
    end                       x' = x + h (v + dv); an impact's approach speed restored; the
                              impact pass of every integrator (contact.impacts)

The replay (implicit_replay.py) takes the branches the forward's step record says it took
(which particles are contacts, released, capped, slide or hold, how many passes: implicit
/step_record.py) and solves each linear system exactly; ``adjoint`` goes back through it:
each solve's adjoint is one solve with the same filtered matrix, and every friction damper c is
differentiated as the function of the last solve's impulses and velocities it is. The damper the
step leaves (``c_out``) is carried into the next step's matrix, so the backward pass carries its
cotangent from step to step (adjoints.ImplicitEulerAdjoint).

Where bodies touch each other in the same step, their penalty contacts (implicit_bodies
.PenaltyStep) are in every solve's matrix and right-hand side, with the active set each solve
had, their friction comes after the Newton iterations and the post-step pass after the impacts;
the adjoint gives each solve's and each update's cotangents their share. A Newton iteration in
which a self-colliding body's fold closes is taken again from its dv with the grown own pairs,
keeping the terrain contacts and dampers its first try left (as the forward does); the
adjoint goes back through both tries, the first giving only its dampers' cotangent.

Each contact's normal, distance and surface velocity s are its terrain's at the step's start
positions, with a moving or deforming terrain where it is at the step's end
(implicit_lookup.py); friction and the floor act on the velocity relative to s. On a curved
terrain the normal turns with the position, and on a turning or deforming one s changes with
it, so the adjoint also gathers the cotangents
of the normal (from the held components, the projection the solve keeps, the dampers, the
impulses and slips the updates read, the restored approach speed) and of s, and carries them to
the start through the terrain's curvature and s's derivative (``held_vjp``); where every
terrain is a still plane neither is gathered.

The gradient is of the exactly solved step: the forward's CG stops at its tolerance, and the
difference is of that order (docs/guide/gradients.md).
"""
from typing import NamedTuple

import numpy as np

from ..implicit.constraints import (CONTACT, FLOOR_GAP, FLOOR_VELOCITY, FLOOR_ZERO, HOLDING,
                                    SLIP_SPEED)
from .contact import add_curvature, impacts_vjp
from .physics import geometry, stiffness_coefficients, system_product_vjp
from .solve import rhs_vjp, solve_reduced, system_matrix
from .attachments import hold_vjp
from .body_contact_adjoint import respond_vjp
from .implicit_bodies import (contact_bars, friction_vjp, linearization_vjp, penalty_matrix,
                              penalty_vjp)
from .implicit_replay import Replay, Solve
from .implicit_system import (basis, diagonal_blocks, friction_terms, rowdot, tangential)
from .pins import release
from .implicit_lookup import swept_vjp
from ..terrains.plane import Flat
from . import terms


class HeldBars(NamedTuple):
    """The cotangents of the contacts' floors, normals and surface velocities, summed over the
    step's solves."""

    floor: np.ndarray     # (P,)
    normal: object        # (P, 3), or None where every terrain is flat (no curvature)
    surface: object       # (P, 3), or None where every terrain stands still


def held_vjp(constraints, lookups, x, v, bars: HeldBars, h, x_bar, v_bar):
    """Each contact's floor (-phi / h (FLOOR_GAP), v . n (FLOOR_VELOCITY) or s . n), normal
    and surface velocity s are its terrain's at the step's start positions (where the terrain
    is at the step's end): their cotangents go to x through grad phi, the normal's derivative
    (a curved terrain's; a plane has none) and the surface velocity's (a turning terrain's),
    and to v."""
    index = np.nonzero(bars.floor)[0]
    case = constraints.floor_case[index]
    g = bars.floor[index]
    phi_bar = np.where(case == FLOOR_GAP, -g / h, 0.0)
    vel = np.where(case == FLOOR_VELOCITY, g, 0.0)
    slowed = np.where(case == FLOOR_ZERO, g, 0.0)   # to the surface's s . n
    n_bar = np.zeros_like(x) if bars.normal is None else bars.normal.copy()
    s_bar = np.zeros_like(x) if bars.surface is None else bars.surface.copy()
    n_bar[index] += vel[:, None] * v[index] + slowed[:, None] * constraints.surface[index]
    s_bar[index] += slowed[:, None] * constraints.normal[index]
    v_bar[index] += vel[:, None] * constraints.normal[index]
    phi_bar_all = np.zeros(len(x))
    phi_bar_all[index] = phi_bar
    swept = constraints.ahead > 0.0
    for lookup in lookups:
        ours = constraints.terrain == lookup.terrain
        plain = ours & ~swept
        rows = np.nonzero(plain & s_bar.any(axis=1))[0]
        if lookup.surface is not None and len(rows):
            x_bar[rows] += lookup.shape.velocity_vjp(x[rows], s_bar[rows])
        rows = np.nonzero(plain & (phi_bar_all != 0.0))[0]
        x_bar[rows] += phi_bar_all[rows, None] * lookup.shape.gradient(x[rows])
        rows = np.nonzero(plain & n_bar.any(axis=1))[0]
        if len(rows):
            add_curvature(rows, lookup.shape.curvature(x[rows]), n_bar[rows], x_bar)
        rows = np.nonzero(ours & swept)[0]
        if len(rows):   # along v: a solve's contacts are on faces, where u plays no part
            at_bar, u_bar = swept_vjp(lookup.shape, constraints.at[rows],
                                      constraints.ahead[rows], constraints.normal[rows],
                                      v[rows], phi_bar_all[rows], n_bar[rows])
            x_bar[rows] += at_bar
            v_bar[rows] += u_bar


# --- the adjoint --------------------------------------------------------------------------------


def adjoint(physical, h, x, v, record: Replay, x_bar, v_bar, c_bar, bar):
    """The cotangents of (x, v, the carried dampers) at the step's start, given those of
    (x', v', the dampers the step leaves); the parameters' share is added to ``bar``."""
    constraints = record.constraints
    normal = constraints.normal
    out_x, out_v = np.zeros_like(x), np.zeros_like(x)
    bodies = record.bodies
    if bodies is not None and bodies.response is not None:
        x_bar, v_bar, start_bar = respond_vjp(physical, bodies.response, x_bar, v_bar, bar)
        release(physical, x_bar, v_bar)
        out_x += start_bar
    x_end_bar, v_end_bar = impacts_vjp(physical, record.impacts, x_bar.copy(), v_bar.copy(), bar)
    if record.held is not None:
        x_end_bar, v_end_bar = hold_vjp(physical, record.held, x_end_bar, v_end_bar, bar)
        release(physical, x_end_bar, v_end_bar)
    curved = any(not isinstance(lookup.shape, Flat) for lookup in record.lookups)
    moving = any(lookup.surface is not None for lookup in record.lookups)
    held_bar = HeldBars(np.zeros(len(x)), np.zeros_like(x) if curved or moving else None,
                        np.zeros_like(x) if moving else None)
    # restore_impact_speeds: v_k + (v . n - v_k . n) n
    vk_bar = v_end_bar.copy()
    rows = record.restored
    if len(rows):
        gn = rowdot(vk_bar[rows], normal[rows])
        if held_bar.normal is not None:
            moved = v[rows] - record.end[2][rows]
            held_bar.normal[rows] += (rowdot(moved, normal[rows])[:, None] * vk_bar[rows]
                                      + gn[:, None] * moved)
        vk_bar[rows] -= gn[:, None] * normal[rows]
        out_v[rows] += gn[:, None] * normal[rows]
    # x' = x + h v_k, v_k = v + dv (with the penalty contacts' friction between)
    out_x += x_end_bar
    vk_bar += h * x_end_bar
    penalty, last = None, None
    if bodies is not None:
        penalty = bodies.penalty
        last = contact_bars(penalty.iterations[-1].contacts)
        vk_bar = friction_vjp(physical, bodies.friction, penalty.iterations[-1].contacts,
                              bodies.x_before, vk_bar, last, out_x, h, bar)
    out_v += vk_bar
    dv_bar = vk_bar
    c_bar = c_bar.copy()
    for k in reversed(range(len(record.iterations))):
        it = record.iterations[k]
        bodies_k = None
        if penalty is not None:
            bars = last if k == len(record.iterations) - 1 else contact_bars(
                penalty.iterations[k].contacts)
            bodies_k = (penalty, k, bars)
        # an iteration solved again left its dampers to the next, its ddv to none
        ddv_bar = np.zeros_like(x) if it.again else dv_bar
        start_bar, c_bar = iteration_adjoint(physical, h, (x, v), constraints, it, ddv_bar,
                                             c_bar, held_bar, (out_x, out_v), bar, bodies_k)
        dv_bar = dv_bar + start_bar if it.again else start_bar
        if bodies_k is not None:   # the contacts linearized about x + h (v + dv_k)
            estimate_bar = linearization_vjp(physical, penalty.iterations[k].contacts, x, v,
                                             it.dv, h, bodies_k[2], out_x, bar)
            out_x += estimate_bar
            out_v += h * estimate_bar
            dv_bar = dv_bar + h * estimate_bar
    c_memory_bar = np.where(record.continues, c_bar, 0.0)
    # every particle that was a contact at some solve (made or released within the step too)
    held_vjp(constraints, record.lookups, x, v, held_bar, h, out_x, out_v)
    return out_x, out_v, c_memory_bar


class IterationBars(NamedTuple):
    """The cotangents a Newton iteration's adjoint gathers, each added to in place."""

    b: np.ndarray          # (P, 3) of its right-hand side b_sp
    u0: np.ndarray         # (P, 3) of u0 = v + dv, the velocity it starts from
    c: np.ndarray          # (P,) of the friction dampers
    held: HeldBars         # of the contacts' floors, normals and surface velocities
    weights: np.ndarray    # (P, 3, 3) of each particle's diagonal block (stiffness, cap)
    estimate: tuple        # (x_k_bar, v_k_bar) of the estimate it is linearized about
    parameters: object     # physics.Cotangents: the parameters' share


def iteration_adjoint(physical, h, start, constraints, it, dv_bar, c_bar, held_bar, out, bar,
                      bodies=None):
    """One Newton iteration backwards (module doc) from the step's ``start`` (x, v), adding to
    ``out`` (x_bar, v_bar); returns the cotangents of its starting dv and dampers.
    ``bodies``: (implicit_bodies.PenaltyStep, this iteration's number, its contacts'
    SolveBars) when penalty contacts took part: each solve's and update's matrix and
    right-hand side had those active then."""
    (x, v), (out_x, out_v) = start, out
    first, dv = it.first, it.dv
    x_k, v_k = (x, v) if first else (x + h * (v + dv), v + dv)
    u0 = v + dv
    matrix = system_matrix(physical, x_k, v_k, h)
    xk_bar, vk_bar = np.zeros_like(x), np.zeros_like(x)
    b_bar, u0_bar = np.zeros_like(x), np.zeros_like(x)
    weights = np.zeros((len(x), 3, 3))
    bars = IterationBars(b_bar, u0_bar, c_bar, held_bar, weights, (xk_bar, vk_bar), bar)
    ddv_bar = dv_bar.copy()              # dv_next = dv + the last solve's ddv
    steps = it.steps
    # the diagonal blocks the updates read (n^T B n), where the normals have a cotangent
    blocks = None if held_bar.normal is None else diagonal_blocks(physical, x_k, v_k, h)

    def with_penalty(active):
        """(the matrix with the penalty contacts ``active``, those contacts) or (matrix, None)."""
        if bodies is None:
            return matrix, None
        contacts = bodies[0].with_active(bodies[1], active)
        return matrix + penalty_matrix(contacts, active, len(x)), contacts

    for j in reversed(range(len(steps))):
        step = steps[j]
        full, contacts = with_penalty(step.active)
        if isinstance(step, Solve):
            lam = solve_adjoint(physical, h, (x_k, v_k), full, constraints, step, u0, ddv_bar,
                                bars)
            if contacts is not None:   # its matrix's cotangent -lam ddv^T, its rhs's lam
                penalty_vjp(contacts, lam, step.ddv, h, bodies[2])
            ddv_bar = np.zeros_like(x)
        else:
            ddv_before = steps[j - 1].ddv
            g_r = update_adjoint(physical, h, (x_k, v_k), full, constraints, step, u0,
                                 ddv_before, ddv_bar, bars, blocks)
            if contacts is not None and g_r is not None:   # R = A ddv - b: g_r ddv^T, -g_r
                penalty_vjp(contacts, -g_r, ddv_before, h, bodies[2])
    if first and len(it.cap.index):
        cap_bar = np.zeros_like(x)   # the cap read the right-hand side with the contacts
        cap_adjoint(physical, h, (x_k, v_k), constraints, it.cap, u0, bars._replace(b=cap_bar))
        b_bar += cap_bar
        _, contacts = with_penalty(it.cap_active)
        if contacts is not None:
            penalty_vjp(contacts, cap_bar, np.zeros_like(x), h, bodies[2])
    diagonal_blocks_vjp(physical, x_k, h, weights, xk_bar, bar)
    terms.diagonal_blocks_vjp(physical, x_k, v_k, h, weights, xk_bar, vk_bar, bar)
    dv_start_bar = dv_bar + u0_bar - physical.solve_mass[:, None] * b_bar
    rhs_vjp(physical, h, start, (x_k, v_k), dv, first, b_bar, out, (xk_bar, vk_bar), bar)
    out_v += u0_bar
    if first:
        out_x += xk_bar
        out_v += vk_bar
    else:
        out_x += xk_bar
        out_v += h * xk_bar + vk_bar
        dv_start_bar += h * xk_bar + vk_bar
    return dv_start_bar, c_bar


def solve_adjoint(physical, h, estimate, matrix, constraints, step, u0, ddv_bar, bars):
    """ddv = solve(A_sp + C(c), b_sp - c T u0, z(floor, u0)): lambda = (Q^T A Q)^-1 Q^T ddv_bar
    (A symmetric), then b's cotangent is lambda, A's -lambda ddv^T, z's (I - S)(ddv_bar -
    A lambda). ``estimate``: (x_k, v_k), with their cotangents ``bars.estimate``. Returns
    lambda (the penalty contacts in A and b take their share from it: iteration_adjoint)."""
    kind, c, ddv = step.kind, step.c, step.ddv
    contact = np.nonzero(kind == CONTACT)[0]
    normal = constraints.normal
    friction, _ = friction_terms(kind, normal, c, u0)
    a = matrix + friction
    q = basis(kind, normal)
    lam = solve_reduced(a, ddv_bar, np.zeros_like(ddv_bar), q)
    bars.b[...] += lam
    matrix_vjp(physical, h, estimate, ddv, -lam, bars.estimate, bars.parameters)
    n = normal[contact]
    lam_t = tangential(lam[contact], n)
    surface = constraints.surface[contact]
    bars.c[contact] -= rowdot(lam_t, ddv[contact]) + rowdot(lam_t, u0[contact] - surface)
    bars.u0[contact] -= c[contact, None] * lam_t
    if bars.held.surface is not None:   # the dampers act on the velocity relative to s
        bars.held.surface[contact] += c[contact, None] * lam_t
    rest = ddv_bar - (matrix @ lam.ravel()).reshape(lam.shape)
    gap_bar = rowdot(rest[contact], n)
    bars.held.floor[contact] += gap_bar
    bars.u0[contact] -= gap_bar[:, None] * n
    # the normal: in z = gap n, in the projections S = I - n n^T that the solve holds (with
    # A ddv - b = push n on a contact) and in the dampers' c (I - n n^T)
    if bars.held.normal is not None:
        u = u0[contact] + ddv[contact]
        lam_c = lam[contact]
        bars.held.normal[contact] += (-gap_bar[:, None] * u + step.push[contact, None] * lam_c
                                     + (c[contact] * rowdot(u - surface, n))[:, None] * lam_c)
    return lam


def update_adjoint(physical, h, estimate, matrix, constraints, update, u0, ddv, ddv_bar, bars,
                   blocks):
    """The dampers chosen from the solve before (constraints.coulomb_damping), backwards.
    Returns the cotangent g_r of the reaction R = A ddv - b they read (None if none)."""
    bars.c[update.released] = 0.0
    bars.c[update.grown] = 0.0
    index = update.index
    if not len(index):
        return None
    g = bars.c[index]
    c_before = update.c_before[index]
    slip, impulse, stiff, sliding = update.slip, update.impulse, update.stiffness, update.sliding
    mu = physical.friction[constraints.terrain[index]]
    coulomb = mu * impulse
    holding = update.case == HOLDING
    safe = np.where(holding, 1.0, sliding)
    coulomb_bar = np.where(holding, g / SLIP_SPEED, g / safe)
    sliding_bar = np.where(holding, 0.0, -g * coulomb / safe ** 2)
    stiff_bar = sliding_bar * (coulomb - c_before * slip) / stiff ** 2
    coulomb_bar -= sliding_bar / stiff
    bars.c[index] = sliding_bar * slip / stiff
    slip_bar = sliding_bar * (stiff + c_before) / stiff
    np.add.at(bars.parameters.friction, constraints.terrain[index], coulomb_bar * impulse)
    impulse_bar = coulomb_bar * mu
    n = constraints.normal[index]
    relative = u0[index] + ddv[index] - constraints.surface[index]
    direction = tangential(relative, n) / np.where(slip > 0.0, slip, 1.0)[:, None]
    bars.u0[index] += slip_bar[:, None] * direction
    ddv_bar[index] += slip_bar[:, None] * direction
    if bars.held.surface is not None:
        bars.held.surface[index] -= slip_bar[:, None] * direction
    # impulse = n . (A_sp ddv - b_sp)_i
    g_r = np.zeros_like(u0)
    g_r[index] = impulse_bar[:, None] * n
    ddv_bar += (matrix @ g_r.ravel()).reshape(g_r.shape)
    matrix_vjp(physical, h, estimate, ddv, g_r, bars.estimate, bars.parameters)
    bars.b[...] -= g_r
    # stiffness = (tr B - n^T B n) / 2
    bars.weights[index] += (0.5 * stiff_bar[:, None, None]
                            * (np.eye(3) - n[:, :, None] * n[:, None, :]))
    if bars.held.normal is not None:   # impulse = n . R, u_t = (I - n n^T) u, n^T B n
        bars.held.normal[index] += (
            impulse_bar[:, None] * update.reaction
            - (slip_bar * rowdot(relative, n))[:, None] * direction
            - stiff_bar[:, None] * np.einsum("kij,kj->ki", blocks[index], n))
    return g_r


def cap_adjoint(physical, h, estimate, constraints, cap, u0, bars):
    """c = friction max(impulse, 0) / slip for the carried dampers the cone capped, with
    impulse = -b_sp . n + gap n^T B n and gap = floor - n . u0."""
    index, slip, impulse, gap, b_rows = cap.index, cap.slip, cap.impulse, cap.gap, cap.b_rows
    g = bars.c[index]
    bars.c[index] = 0.0   # the carried value is replaced
    mu = physical.friction[constraints.terrain[index]]
    safe = np.where(slip > 0.0, slip, 1.0)
    pushing = (impulse > 0.0) & (slip > 0.0)
    coulomb = mu * np.maximum(impulse, 0.0)
    coulomb_bar = np.where(pushing, g / safe, 0.0)
    slip_bar = np.where(slip > 0.0, -g * coulomb / safe ** 2, 0.0)
    np.add.at(bars.parameters.friction, constraints.terrain[index],
              coulomb_bar * np.maximum(impulse, 0.0))
    impulse_bar = coulomb_bar * mu
    n = constraints.normal[index]
    relative = u0[index] - constraints.surface[index]
    slipping = (slip_bar / safe)[:, None] * tangential(relative, n)
    bars.u0[index] += slipping
    if bars.held.surface is not None:
        bars.held.surface[index] -= slipping
    bars.b[index] -= impulse_bar[:, None] * n
    blocks = diagonal_blocks(physical, *estimate, h)[index]
    block_n = np.einsum("kij,kj->ki", blocks, n)
    gap_bar = impulse_bar * rowdot(block_n, n)
    bars.held.floor[index] += gap_bar
    bars.u0[index] -= gap_bar[:, None] * n
    if bars.held.normal is not None:   # in the impulse, the gap and the slip
        bars.held.normal[index] += (
            impulse_bar[:, None] * (2.0 * gap[:, None] * block_n - b_rows)
            - gap_bar[:, None] * u0[index]
            - ((slip_bar / safe) * rowdot(relative, n))[:, None] * tangential(relative, n))
    bars.weights[index] += (impulse_bar * gap)[:, None, None] * n[:, :, None] * n[:, None, :]


def matrix_vjp(physical, h, estimate, u, g, estimate_bar, bar):
    """Add g . d(A u)/d(x_k, v_k, parameters), u held fixed: the springs' and the terms'."""
    system_product_vjp(physical, estimate[0], u, g, h, estimate_bar[0], bar)
    terms.product_vjp(physical, *estimate, h, u, g, *estimate_bar, bar)


def diagonal_blocks_vjp(physical, x_k, h, weights, xk_bar, bar):
    """Add sum_i weights_i : B_i (diagonal_blocks) differentiated into xk_bar and bar."""
    if not weights.any():
        return
    trace = np.einsum("kii->k", weights)
    bar.mass += np.where(physical.free, trace, 0.0)
    bar.drag += h * trace
    springs = geometry(physical, x_k)
    along_, across, across_dl, across_dr, ratio = stiffness_coefficients(physical, springs)
    real = springs.length > 0.0
    p = (h * physical.kd + h * h * along_) * real
    l = springs.unit
    w = weights[physical.a] + weights[physical.b]
    g_p = np.einsum("ki,kij,kj->k", l, w, l) * real
    g_q = np.einsum("kii->k", w) * real
    bar.kd += h * g_p
    along_bar = h * h * g_p
    across_bar = h * h * g_q - along_bar
    bar.ks += along_bar + across_bar * ratio
    bar.rest += across_bar * across_dr
    l_bar = p[:, None] * np.einsum("kij,kj->ki", w + np.transpose(w, (0, 2, 1)), l)
    d_bar = (l_bar - rowdot(l_bar, l)[:, None] * l) * springs.inverse[:, None]
    d_bar += (across_bar * across_dl)[:, None] * l
    np.add.at(xk_bar, physical.a, d_bar)
    np.add.at(xk_bar, physical.b, -d_bar)
