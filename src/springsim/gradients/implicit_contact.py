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

``replay`` takes the same branches (which particles are contacts, released, capped, slide or
hold, how many passes) and solves each linear system exactly; ``adjoint`` goes back through it:
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
from scipy import sparse

from ..errors import SceneError
from ..implicit.constraints import (CONTACT, FREE, FRICTION_SETTLED, PINNED, SLIP_SPEED)
from ..integrators.implicit_euler import MAX_CONTACT_UPDATES
from .contact import add_curvature, along, impacts, impacts_vjp
from .physics import geometry, stiffness_coefficients, system_product_vjp
from .solve import newton_rhs, rhs_vjp, solve_reduced, system_matrix
from .attachments import hold, hold_vjp, holds
from .body_contact import respond, respond_vjp
from .implicit_bodies import (contact_bars, friction_vjp, linearization_vjp, penalty_end,
                              penalty_matrix, penalty_vjp)
from .pins import place, release
from .clock import STEP_START
from .implicit_lookup import look_up, refuse_turning, swept, swept_vjp, unseen
from ..terrains.plane import Flat
from . import terms

# how each contact's floor came about (constraints.lowest_normal_velocity)
FLOOR_GAP, FLOOR_VELOCITY, FLOOR_ZERO, FLOOR_INSIDE = 0, 1, 2, 3   # inside: -max(phi, 0) / h = 0
# how a friction damper came about
KEPT, CAPPED, SLIDING, HOLDING, RELEASED = 0, 1, 2, 3, 4


class Constraints(NamedTuple):
    kind: np.ndarray       # (P,) FREE, CONTACT, PINNED
    terrain: np.ndarray    # (P,) the contact's terrain or -1
    normal: np.ndarray     # (P, 3)
    floor: np.ndarray      # (P,) m/s
    floor_case: np.ndarray
    surface: np.ndarray    # (P, 3) m/s, the terrain's surface velocity (0 on a still one)
    at: np.ndarray         # (P, 3) m, where the contact was looked up (implicit_lookup.Lookup)
    ahead: np.ndarray      # (P,) s, how far along the particle's path: 0 where not swept


def floor_of(phi, v_n, s_n, h, epsilon):
    """lowest_normal_velocity for arrays: (floor, case); s_n the surface's normal velocity
    (FLOOR_ZERO: the particle slows to it)."""
    outside = phi >= epsilon
    gap = -np.maximum(phi, 0.0) / h
    low = s_n + np.minimum(v_n - s_n, 0.0)
    case = np.where(outside, FLOOR_GAP, np.where(
        low >= gap, np.where(v_n - s_n < 0.0, FLOOR_VELOCITY, FLOOR_ZERO),
        np.where(phi > 0.0, FLOOR_GAP, FLOOR_INSIDE)))
    floor = np.where(outside, -phi / h, np.maximum(low, gap))
    return floor, case


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


def find_constraints(physical, x, v, h, previous_kind, previous_terrain, lookups):
    """constraints.find_constraints: (Constraints, whether each contact continues the last
    step's, with the same terrain)."""
    epsilons = physical.planes.epsilon
    count = x.shape[0]
    kind = np.where(physical.free, FREE, PINNED).astype(np.int64)
    terrain = np.full(count, -1)
    normal = np.zeros((count, 3))
    surface = np.zeros((count, 3))
    at, ahead = x.copy(), np.zeros(count)
    phi_best, v_n_best = np.zeros(count), np.zeros(count)
    earliest = np.full(count, np.inf)
    for lookup in lookups:
        t, phi, n = lookup.terrain, lookup.phi, lookup.normal
        v_n = along(v, n)
        reached = phi + h * v_n
        touching = ((phi < epsilons[t]) | (reached < epsilons[t])) & physical.free
        better = touching & (reached < earliest)
        terrain[better], earliest[better] = t, reached[better]
        phi_best[better], v_n_best[better] = phi[better], v_n[better]
        normal[better] = n[better]
        at[better], ahead[better] = lookup.at[better], lookup.ahead[better]
        if lookup.surface is not None:
            surface[better] = lookup.surface[better]
    epsilon = epsilons[np.maximum(terrain, 0)]
    s_n = rowdot(surface, normal)
    joins = (phi_best < epsilon) | (phi_best + h * v_n_best < 0.0)
    released = (previous_kind == FREE) & (previous_terrain >= 0)
    terrain[released & ~joins] = -1   # constraints.joins_afresh
    contact = terrain >= 0
    kind[contact] = CONTACT
    floor, case = floor_of(phi_best, v_n_best, s_n, h, epsilon)
    floor[~contact] = 0.0
    continues = contact & (previous_kind == CONTACT) & (previous_terrain == terrain)
    return Constraints(kind, terrain, normal, floor, case, surface, at, ahead), continues


def tangential(u, n):
    """(I - n n^T) u per particle."""
    return u - np.einsum("ij,ij->i", u, n)[:, None] * n


def rowdot(u, w):
    return np.einsum("ij,ij->i", u, w)


class Solve(NamedTuple):
    """One filtered solve of a Newton iteration, as ``adjoint`` needs it."""

    kind: np.ndarray      # the constraints it had
    c: np.ndarray         # (P,) the friction dampers in its matrix
    ddv: np.ndarray       # (P, 3) its solution
    push: np.ndarray      # (P,) n . (A ddv - b) on contacts, the terrain's push (N s), else 0
    active: object = None   # (K,) bool: the penalty contacts active in it (none: no bodies)


class Update(NamedTuple):
    """One active-set pass: the dampers it chose, from the solve before it."""

    index: np.ndarray     # contacts whose damper it chose (SLIDING or HOLDING)
    case: np.ndarray
    c_before: np.ndarray  # (P,)
    slip: np.ndarray      # (len(index),) |u_t|
    impulse: np.ndarray   # R . n
    stiffness: np.ndarray
    sliding: np.ndarray
    released: np.ndarray  # contacts it released (c -> 0)
    grown: np.ndarray     # free particles it made contacts (c = 0)
    reaction: np.ndarray  # (len(index), 3) A_sp ddv - b_sp, whose normal part is the impulse
    active: object = None   # the penalty contacts active in the solve before it


class Iteration(NamedTuple):
    dv: np.ndarray        # the estimate it starts from
    first: bool
    cap: tuple            # (index, c_in, slip, impulse, gap, b) of the carried dampers it
                          # capped, b their rows of the right-hand side
    c_start: np.ndarray   # (P,) the dampers the matrix starts with (after any cap)
    steps: list           # [Solve, Update, Solve, ..., (Update)] in order
    c_end: np.ndarray     # the dampers it leaves
    cap_active: object = None   # the penalty contacts active when the cap was taken
    again: bool = False   # solved again (a fold closed within it): only its dampers carry on


class Bodies(NamedTuple):
    """The body-body contacts of a step with terrain contact too (implicit_bodies.py)."""

    penalty: object       # implicit_bodies.PenaltyStep
    friction: object      # implicit_bodies.Friction after the solve
    x_before: np.ndarray  # x + h v_K, before that friction
    response: object      # body_contact.Response of the post-step pass, or None


class Replay(NamedTuple):
    constraints: Constraints
    continues: np.ndarray
    iterations: list
    restored: np.ndarray  # particles whose approach speed the end restored
    impacts: list         # contact.impacts' record
    end: tuple            # (x, v) before the impact pass, and v before the restoring
    bodies: object = None   # Bodies: the penalty contacts' part, when bodies touched too
    lookups: list = ()    # [Lookup] of the terrains at the step's start
    held: object = None   # attachments.Held: the hard attachments held before the impacts


def diagonal_blocks(physical, x_k, v_k, h):
    """Each particle's diagonal block of the springs' matrix A (P, 3, 3): the masses and drag,
    the terms' diagonal blocks and every spring's C = p l l^T + q I
    (physics.system_product)."""
    springs = geometry(physical, x_k)
    along_, across, _, _, _ = stiffness_coefficients(physical, springs)
    real = springs.length > 0.0
    p = (h * physical.kd + h * h * along_) * real
    q = h * h * across * real
    l = springs.unit
    blocks = p[:, None, None] * l[:, :, None] * l[:, None, :] + q[:, None, None] * np.eye(3)
    out = np.zeros((x_k.shape[0], 3, 3))
    np.add.at(out, physical.a, blocks)
    np.add.at(out, physical.b, blocks)
    out += (physical.solve_mass + h * physical.drag)[:, None, None] * np.eye(3)
    return out + terms.diagonal_blocks(physical, x_k, v_k, h)


def held(constraints, kind, u0):
    """z: the constrained components of ddv (hold_constrained): (floor - n . u0) n on contacts."""
    z = np.zeros_like(u0)
    contact = kind == CONTACT
    gap = constraints.floor[contact] - rowdot(u0[contact], constraints.normal[contact])
    z[contact] = gap[:, None] * constraints.normal[contact]
    return z


def friction_terms(kind, normal, c, u0):
    """(the dampers' blocks as a sparse matrix, their share of b: -c (I - n n^T) u0, u0 the
    velocity relative to the terrain's surface)."""
    on = (kind == CONTACT) & (c != 0.0)
    blocks = np.zeros((len(c), 3, 3))
    n = normal[on]
    blocks[on] = c[on, None, None] * (np.eye(3) - n[:, :, None] * n[:, None, :])
    count = len(c)
    matrix = sparse.bsr_matrix((blocks, np.arange(count), np.arange(count + 1)),
                               shape=(3 * count, 3 * count)).tocsr()
    share = np.zeros_like(u0)
    share[on] = -c[on, None] * tangential(u0[on], n)
    return matrix, share


def replay(physical, h, x, v, c_memory, previous_kind, previous_terrain, iterations,
           penalty=None):
    """The step as the forward took it (module doc), each solve exact; with ``penalty`` (an
    implicit_bodies.PenaltyStep) the bodies' penalty contacts in every solve, their friction
    after it and the post-step pass. Returns (x', v', the dampers it leaves, Replay)."""
    lookups = look_up(physical, x, v, h)
    constraints, continues = find_constraints(physical, x, v, h, previous_kind, previous_terrain,
                                              lookups)
    kind = constraints.kind.copy()
    normal = constraints.normal.copy()
    terrain = constraints.terrain.copy()
    floor, floor_case = constraints.floor.copy(), constraints.floor_case.copy()
    constraints = constraints._replace(   # grows in place
        kind=kind, terrain=terrain, normal=normal, floor=floor, floor_case=floor_case,
        surface=constraints.surface.copy(), at=constraints.at.copy(),
        ahead=constraints.ahead.copy())
    c = np.where(continues, c_memory, 0.0)
    dv = np.zeros_like(x)
    record = []
    if penalty is not None:
        iterations = penalty.needed

    def active():
        return None if penalty is None else penalty.contacts.active.copy()

    k = 0
    while k < iterations:
        first = k == 0
        x_k, v_k = (x, v) if first else (x + h * (v + dv), v + dv)
        matrix = system_matrix(physical, x_k, v_k, h)
        b_sp = newton_rhs(physical, h, x, v, dv, first)
        if penalty is not None:
            penalty.linearize(dv)

        def full():
            """The matrix and right-hand side with the penalty contacts active now."""
            if penalty is None:
                return matrix, b_sp
            return matrix + penalty.matrix(), b_sp + penalty.rhs

        u0 = v + dv
        blocks = diagonal_blocks(physical, x_k, v_k, h)
        cap = (np.empty(0, np.int64), np.empty(0), np.empty(0), np.empty(0), np.empty(0),
               np.empty((0, 3)))
        cap_active = active()
        if first:   # remembered_friction_in_cone
            *cap, lowered = capped_dampers(physical, constraints, kind, blocks, full()[1], u0, c)
            c = c.copy()
            c[cap[0]] = lowered
        c_start = c.copy()
        steps = []
        # the penalty contacts' active set changes only in penalty.update
        ddv, reaction = solve_step(physical, constraints, kind, *full(), u0, c)
        steps.append(Solve(kind.copy(), c.copy(), ddv, pushes(kind, normal, reaction), active()))
        for _ in range(MAX_CONTACT_UPDATES):
            solved_with = active()
            update, c_new, grew = update_contacts(physical, h, x, v, constraints, kind, blocks,
                                                  reaction, u0, c, ddv, lookups)
            steps.append(update._replace(active=solved_with))
            bodies_changed = penalty is not None and penalty.update(
                held_grown(constraints, update.grown, u0, ddv))
            moved = np.sum(np.abs(c_new[update.index] - c[update.index])
                           * np.maximum(update.slip, SLIP_SPEED))
            total = np.sum(physical.friction[terrain[update.index]] * update.impulse)
            changed = grew or len(update.released) > 0 or bodies_changed
            c = c_new
            if not (changed or moved > FRICTION_SETTLED * total):
                break
            ddv, reaction = solve_step(physical, constraints, kind, *full(), u0, c)
            steps.append(Solve(kind.copy(), c.copy(), ddv, pushes(kind, normal, reaction),
                               active()))
        if penalty is not None:
            penalty.keep(dv, first, ddv)
        # a fold closing within the solve: the iteration again, from its dv, with the own
        # pairs it brought into contact; the terrain contacts and dampers as it left them
        again = penalty is not None and penalty.regrow(dv, ddv)
        record.append(Iteration(dv, first, cap, c_start, steps, c.copy(), cap_active, again))
        if again:
            continue
        dv = dv + ddv
        k += 1
    v_k = v + dv
    bodies = None
    if penalty is not None:   # the penalty contacts' friction, then x from v again
        v_k, friction, x_before = penalty_end(physical, penalty, h, x, v_k)
        bodies = Bodies(penalty, friction, x_before, None)
    x_end = x + h * v_k
    # restore_impact_speeds
    contact = np.nonzero(kind == CONTACT)[0]
    n = normal[contact]
    approach, end_n = rowdot(v[contact], n), rowdot(v_k[contact], n)
    fl = floor[contact]
    restore = (approach < fl) & ~(end_n > fl + 1e-12 * np.abs(fl) + 1e-12)
    restored = contact[restore]
    v_end = v_k.copy()
    v_end[restored] += (approach[restore] - end_n[restore])[:, None] * n[restore]
    x_out, v_out, held = x_end, v_end, None
    if holds(physical):   # the pins on paths placed, the hard attachments held (_steps.collide)
        x_out, v_out, held = hold(physical, *place(physical, x_end, v_end))
    x_out, v_out, found = impacts(physical, x_out, v_out)
    if bodies is not None:   # the pins on paths placed, then the post-step pass
        x_out, v_out, response = respond(physical, *place(physical, x_out, v_out), x)
        bodies = bodies._replace(response=response)
    return x_out, v_out, c, Replay(constraints, continues, record, restored, found,
                                   (x_end, v_end, v_k), bodies, lookups, held)


def refuse_another_contact(physical, constraints, i, terrain, normal, floor):
    """Refuse the step where particle i, a contact earlier in it and let go, is found again
    with another terrain, normal or floor (a swept lookup along another velocity, or another
    terrain first): the adjoint reads one contact per particle and step (its Constraints)."""
    if constraints.terrain[i] < 0:
        return
    rounding = 1e-12 * max(1.0, abs(floor))   # the floor's v . n is summed in another order
    if (constraints.terrain[i] != terrain or abs(constraints.floor[i] - floor) > rounding
            or np.any(np.abs(constraints.normal[i] - normal) > 1e-12)):
        now = float(physical.clock[STEP_START])
        raise SceneError(f"terrains.{terrain}", "contact", f"takes particle {i} again within "
                         f"the step at {now:.6g} s, where it was let go, with another normal "
                         "or floor, which gradients do not follow under implicit_euler: try a "
                         "smaller dt")


def held_grown(constraints, grown, u0, ddv):
    """ddv with the contacts an update made held at their floors, as the forward's update
    leaves it for the penalty contacts' active-set pass that follows (a choice, not a value:
    nothing to differentiate)."""
    if not len(grown):
        return ddv
    n = constraints.normal[grown]
    held = ddv.copy()
    held[grown] += (constraints.floor[grown] - rowdot(u0[grown] + ddv[grown], n))[:, None] * n
    return held


def capped_dampers(physical, constraints, kind, blocks, b_sp, u0, c):
    """remembered_friction_in_cone: (index, c_in, slip, impulse, gap, c_capped) of the carried
    dampers that would leave the friction cone, each lowered to Coulomb's impulse / slip."""
    index = np.nonzero((kind == CONTACT) & (c != 0.0))[0]
    n = constraints.normal[index]
    gap = constraints.floor[index] - rowdot(u0[index], n)
    slip = np.linalg.norm(tangential(u0[index] - constraints.surface[index], n), axis=1)
    along_normal = np.einsum("ki,kij,kj->k", n, blocks[index], n)
    impulse = -rowdot(b_sp[index], n) + gap * along_normal
    coulomb = physical.friction[constraints.terrain[index]] * np.maximum(impulse, 0.0)
    d = 0.5 * (np.trace(blocks[index], axis1=1, axis2=2) - along_normal)   # in series with c
    taken = np.where(d > 0.0, c[index] * d / (c[index] + np.where(d > 0.0, d, 1.0)), c[index])
    over = taken * slip > coulomb
    index, slip, impulse, gap = index[over], slip[over], impulse[over], gap[over]
    return index, c[index].copy(), slip, impulse, gap, b_sp[index], np.where(
        slip > 0.0, coulomb[over] / np.where(slip > 0.0, slip, 1.0), 0.0)


def pushes(kind, normal, reaction):
    """n . R of each contact after a solve (0 elsewhere), R = A_sp ddv - b_sp: the friction's
    share of A ddv - b has no part along n."""
    return np.where(kind == CONTACT, rowdot(reaction, normal), 0.0)


def solve_step(physical, constraints, kind, matrix, b_sp, u0, c):
    """(ddv with S (A ddv - b) = 0 and its constrained components held (z), the reaction
    R = A_sp ddv - b_sp without the dampers, which the push and the update read)."""
    friction, share = friction_terms(kind, constraints.normal, c, u0 - constraints.surface)
    z = held(constraints, kind, u0)
    a = matrix + friction
    ddv = solve_reduced(a, b_sp + share, z, basis(kind, constraints.normal))
    return ddv, (matrix @ ddv.ravel()).reshape(ddv.shape) - b_sp


def basis(kind, normal):
    """Q: orthonormal columns spanning the components no constraint fixes (3P, r): a free
    particle's three axes, a contact's two tangents, none of a pinned one's, in particle
    order."""
    free, contact = np.nonzero(kind == FREE)[0], np.nonzero(kind == CONTACT)[0]
    width = np.zeros(len(kind), np.int64)
    width[free], width[contact] = 3, 2
    first = np.cumsum(width) - width   # each particle's first column
    axes, shape = np.arange(3), (len(contact), 2, 3)   # a contact's tangent k, component c
    rows = [(3 * free[:, None] + axes).ravel(),
            np.broadcast_to(3 * contact[:, None, None] + axes, shape).ravel()]
    cols = [(first[free][:, None] + axes).ravel(),
            np.broadcast_to(first[contact][:, None, None] + np.arange(2)[:, None], shape).ravel()]
    values = [np.ones(3 * len(free)), np.stack(tangents(normal[contact]), axis=1).ravel()]
    return sparse.csr_matrix((np.concatenate(values), (np.concatenate(rows),
                                                       np.concatenate(cols))),
                             shape=(3 * len(kind), int(width.sum())))


def tangents(n):
    """Two unit tangents of each normal (K, 3): across the axis the normal leans on least."""
    e = np.zeros_like(n)
    e[np.arange(len(n)), np.argmin(np.abs(n), axis=1)] = 1.0
    t1 = np.cross(n, e)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(n, t1)


def update_contacts(physical, h, x, v, constraints, kind, blocks, reaction, u0, c, ddv,
                    lookups):
    """constraints.update_contacts: (Update, the dampers after it, whether a contact was
    added). ``kind`` and ``constraints`` grow in place as the forward's do."""
    epsilons = physical.planes.epsilon
    u = u0 + ddv
    # a free particle the start's lookup does not see is asked along its path at u
    lookups = [swept(physical, lookup, x, u, h, np.nonzero((kind == FREE) & unseen(lookup))[0])
               for lookup in lookups]
    c_new = c.copy()
    index, cases, slips, impulses, stiffs, slides, released = [], [], [], [], [], [], []
    grown = []
    for i in range(len(kind)):
        if kind[i] == PINNED:
            continue
        if kind[i] == FREE:
            best, earliest = None, np.inf
            for lookup in lookups:
                phi, n = lookup.phi[i], lookup.normal[i]
                reached = phi + h * (u[i, 0] * n[0] + u[i, 1] * n[1] + u[i, 2] * n[2])
                if reached < 0.0 and reached < earliest:
                    best, earliest = lookup, reached
            if best is not None:
                n = best.normal[i]
                s = np.zeros(3) if best.surface is None else best.surface[i]
                floor, case = floor_of(np.array([best.phi[i]]), np.array([v[i] @ n]),
                                       np.array([s @ n]), h, epsilons[best.terrain])
                refuse_another_contact(physical, constraints, i, best.terrain, n, floor[0])
                kind[i] = CONTACT
                constraints.terrain[i] = best.terrain
                constraints.normal[i] = n
                constraints.surface[i] = s
                constraints.at[i], constraints.ahead[i] = best.at[i], best.ahead[i]
                if best.ahead[i] > 0.0:
                    refuse_turning(physical, best, i)
                constraints.floor[i], constraints.floor_case[i] = floor[0], case[0]
                c_new[i] = 0.0
                grown.append(i)
            continue
        n = constraints.normal[i]
        impulse = reaction[i] @ n
        if impulse < 0.0:
            kind[i] = FREE
            c_new[i] = 0.0
            released.append(i)
            continue
        relative = u[i] - constraints.surface[i]
        t_u = relative - (relative @ n) * n
        slip = np.sqrt(t_u @ t_u)
        coulomb = physical.friction[constraints.terrain[i]] * impulse
        block = blocks[i]
        stiffness = 0.5 * (np.trace(block) - n @ block @ n)   # without friction (module doc)
        sliding = ((stiffness + c[i]) * slip - coulomb) / stiffness
        if sliding > SLIP_SPEED:
            c_new[i], case = coulomb / sliding, SLIDING
        else:
            c_new[i], case = coulomb / SLIP_SPEED, HOLDING
        index.append(i)
        cases.append(case)
        slips.append(slip)
        impulses.append(impulse)
        stiffs.append(stiffness)
        slides.append(sliding)
    index = np.array(index, np.int64)
    update = Update(index, np.array(cases, np.int64), c.copy(), np.array(slips),
                    np.array(impulses), np.array(stiffs), np.array(slides),
                    np.array(released, np.int64), np.array(grown, np.int64),
                    reaction[index])
    return update, c_new, len(grown) > 0


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
        start_bar, c_bar = iteration_adjoint(physical, h, x, v, constraints, it, ddv_bar, c_bar,
                                             held_bar, out_x, out_v, bar, bodies_k)
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


def iteration_adjoint(physical, h, x, v, constraints, it, dv_bar, c_bar, held_bar, out_x,
                      out_v, bar, bodies=None):
    """One Newton iteration backwards (module doc); returns the cotangents of its starting dv
    and dampers. ``bodies``: (implicit_bodies.PenaltyStep, this iteration's number, its
    contacts' SolveBars) when penalty contacts took part: each solve's and update's matrix and
    right-hand side had those active then."""
    first, dv = it.first, it.dv
    x_k, v_k = (x, v) if first else (x + h * (v + dv), v + dv)
    u0 = v + dv
    matrix = system_matrix(physical, x_k, v_k, h)
    xk_bar, vk_bar = np.zeros_like(x), np.zeros_like(x)
    b_bar, u0_bar = np.zeros_like(x), np.zeros_like(x)
    weights = np.zeros((len(x), 3, 3))   # cotangent of each diagonal block (stiffness, cap)
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
                                b_bar, u0_bar, c_bar, held_bar, (xk_bar, vk_bar), bar)
            if contacts is not None:   # its matrix's cotangent -lam ddv^T, its rhs's lam
                penalty_vjp(contacts, lam, step.ddv, h, bodies[2])
            ddv_bar = np.zeros_like(x)
        else:
            ddv_before = steps[j - 1].ddv
            g_r = update_adjoint(physical, h, (x_k, v_k), full, constraints, step, u0,
                                 ddv_before, c_bar, ddv_bar, b_bar, u0_bar, weights,
                                 (xk_bar, vk_bar), bar, held_bar, blocks)
            if contacts is not None and g_r is not None:   # R = A ddv - b: g_r ddv^T, -g_r
                penalty_vjp(contacts, -g_r, ddv_before, h, bodies[2])
    if first and len(it.cap[0]):
        cap_bar = np.zeros_like(x)   # the cap read the right-hand side with the contacts
        cap_adjoint(physical, h, (x_k, v_k), constraints, it.cap, c_bar, cap_bar, u0_bar,
                    held_bar, weights, u0, bar)
        b_bar += cap_bar
        _, contacts = with_penalty(it.cap_active)
        if contacts is not None:
            penalty_vjp(contacts, cap_bar, np.zeros_like(x), h, bodies[2])
    diagonal_blocks_vjp(physical, x_k, h, weights, xk_bar, bar)
    terms.diagonal_blocks_vjp(physical, x_k, v_k, h, weights, xk_bar, vk_bar, bar)
    dv_start_bar = dv_bar + u0_bar - physical.solve_mass[:, None] * b_bar
    rhs_vjp(physical, h, x, v, x_k, v_k, dv, first, b_bar, out_x, out_v, xk_bar, vk_bar, bar)
    out_v += u0_bar
    if first:
        out_x += xk_bar
        out_v += vk_bar
    else:
        out_x += xk_bar
        out_v += h * xk_bar + vk_bar
        dv_start_bar += h * xk_bar + vk_bar
    return dv_start_bar, c_bar


def solve_adjoint(physical, h, estimate, matrix, constraints, step, u0, ddv_bar, b_bar, u0_bar,
                  c_bar, held_bar, estimate_bar, bar):
    """ddv = solve(A_sp + C(c), b_sp - c T u0, z(floor, u0)): lambda = (Q^T A Q)^-1 Q^T ddv_bar
    (A symmetric), then b's cotangent is lambda, A's -lambda ddv^T, z's (I - S)(ddv_bar -
    A lambda). ``estimate``: (x_k, v_k), with their cotangents ``estimate_bar``. Returns
    lambda (the penalty contacts in A and b take their share from it: iteration_adjoint)."""
    kind, c, ddv = step.kind, step.c, step.ddv
    contact = np.nonzero(kind == CONTACT)[0]
    normal = constraints.normal
    friction, _ = friction_terms(kind, normal, c, u0)
    a = matrix + friction
    q = basis(kind, normal)
    lam = solve_reduced(a, ddv_bar, np.zeros_like(ddv_bar), q)
    b_bar += lam
    matrix_vjp(physical, h, estimate, ddv, -lam, estimate_bar, bar)
    n = normal[contact]
    lam_t = tangential(lam[contact], n)
    surface = constraints.surface[contact]
    c_bar[contact] -= rowdot(lam_t, ddv[contact]) + rowdot(lam_t, u0[contact] - surface)
    u0_bar[contact] -= c[contact, None] * lam_t
    if held_bar.surface is not None:   # the dampers act on the velocity relative to s
        held_bar.surface[contact] += c[contact, None] * lam_t
    rest = ddv_bar - (matrix @ lam.ravel()).reshape(lam.shape)
    gap_bar = rowdot(rest[contact], n)
    held_bar.floor[contact] += gap_bar
    u0_bar[contact] -= gap_bar[:, None] * n
    # the normal: in z = gap n, in the projections S = I - n n^T that the solve holds (with
    # A ddv - b = push n on a contact) and in the dampers' c (I - n n^T)
    if held_bar.normal is not None:
        u = u0[contact] + ddv[contact]
        lam_c = lam[contact]
        held_bar.normal[contact] += (-gap_bar[:, None] * u + step.push[contact, None] * lam_c
                                     + (c[contact] * rowdot(u - surface, n))[:, None] * lam_c)
    return lam


def update_adjoint(physical, h, estimate, matrix, constraints, update, u0, ddv, c_bar, ddv_bar,
                   b_bar, u0_bar, weights, estimate_bar, bar, held_bar, blocks):
    """The dampers chosen from the solve before (constraints.coulomb_damping), backwards.
    Returns the cotangent g_r of the reaction R = A ddv - b they read (None if none)."""
    c_bar[update.released] = 0.0
    c_bar[update.grown] = 0.0
    index = update.index
    if not len(index):
        return None
    g = c_bar[index]
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
    c_bar[index] = sliding_bar * slip / stiff
    slip_bar = sliding_bar * (stiff + c_before) / stiff
    np.add.at(bar.friction, constraints.terrain[index], coulomb_bar * impulse)
    impulse_bar = coulomb_bar * mu
    n = constraints.normal[index]
    relative = u0[index] + ddv[index] - constraints.surface[index]
    direction = tangential(relative, n) / np.where(slip > 0.0, slip, 1.0)[:, None]
    u0_bar[index] += slip_bar[:, None] * direction
    ddv_bar[index] += slip_bar[:, None] * direction
    if held_bar.surface is not None:
        held_bar.surface[index] -= slip_bar[:, None] * direction
    # impulse = n . (A_sp ddv - b_sp)_i
    g_r = np.zeros_like(u0)
    g_r[index] = impulse_bar[:, None] * n
    ddv_bar += (matrix @ g_r.ravel()).reshape(g_r.shape)
    matrix_vjp(physical, h, estimate, ddv, g_r, estimate_bar, bar)
    b_bar -= g_r
    # stiffness = (tr B - n^T B n) / 2
    weights[index] += 0.5 * stiff_bar[:, None, None] * (np.eye(3) - n[:, :, None] * n[:, None, :])
    if held_bar.normal is not None:   # impulse = n . R, u_t = (I - n n^T) u, n^T B n
        held_bar.normal[index] += (
            impulse_bar[:, None] * update.reaction
            - (slip_bar * rowdot(relative, n))[:, None] * direction
            - stiff_bar[:, None] * np.einsum("kij,kj->ki", blocks[index], n))
    return g_r


def cap_adjoint(physical, h, estimate, constraints, cap, c_bar, b_bar, u0_bar, held_bar, weights,
                u0, bar):
    """c = friction max(impulse, 0) / slip for the carried dampers the cone capped, with
    impulse = -b_sp . n + gap n^T B n and gap = floor - n . u0."""
    index, _, slip, impulse, gap, b_rows = cap
    g = c_bar[index]
    c_bar[index] = 0.0   # the carried value is replaced
    mu = physical.friction[constraints.terrain[index]]
    safe = np.where(slip > 0.0, slip, 1.0)
    pushing = (impulse > 0.0) & (slip > 0.0)
    coulomb = mu * np.maximum(impulse, 0.0)
    coulomb_bar = np.where(pushing, g / safe, 0.0)
    slip_bar = np.where(slip > 0.0, -g * coulomb / safe ** 2, 0.0)
    np.add.at(bar.friction, constraints.terrain[index], coulomb_bar * np.maximum(impulse, 0.0))
    impulse_bar = coulomb_bar * mu
    n = constraints.normal[index]
    relative = u0[index] - constraints.surface[index]
    slipping = (slip_bar / safe)[:, None] * tangential(relative, n)
    u0_bar[index] += slipping
    if held_bar.surface is not None:
        held_bar.surface[index] -= slipping
    b_bar[index] -= impulse_bar[:, None] * n
    blocks = diagonal_blocks(physical, *estimate, h)[index]
    block_n = np.einsum("kij,kj->ki", blocks, n)
    gap_bar = impulse_bar * rowdot(block_n, n)
    held_bar.floor[index] += gap_bar
    u0_bar[index] -= gap_bar[:, None] * n
    if held_bar.normal is not None:   # in the impulse, the gap and the slip
        held_bar.normal[index] += (
            impulse_bar[:, None] * (2.0 * gap[:, None] * block_n - b_rows)
            - gap_bar[:, None] * u0[index]
            - ((slip_bar / safe) * rowdot(relative, n))[:, None] * tangential(relative, n))
    weights[index] += (impulse_bar * gap)[:, None, None] * n[:, :, None] * n[:, None, :]


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
