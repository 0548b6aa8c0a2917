"""Backward Euler's step with terrain contact replayed in NumPy, each solve exact, each choice
the one the forward made: the forward's step record (implicit/step_record.py) says which
particles were contacts at the start and on which terrain, how each floor came about, which
carried dampers the first iteration capped, what each update pass decided (a contact slid,
held, was let go; a free particle was carried into a terrain), how many passes and solves each
Newton iteration took and which contacts got their approach speed back. The replay computes
the values those choices lead to (normals, floors, dampers, each solve's ddv and reactions),
which the adjoint (implicit_contact.py) differentiates; it decides nothing again.

Two things the record does not hold yet are still found here: a self-colliding body's own
pairs that close within a solve (implicit_bodies.PenaltyStep.regrow; a replay that finds
otherwise than the record is refused) and the penalty contacts' active sets.
"""
from typing import NamedTuple

import numpy as np

from ..errors import SceneError
from ..implicit.constraints import (CAPPED, CONTACT, FLOOR_INSIDE, FLOOR_VELOCITY, FLOOR_ZERO,
                                    FREE, GROWN, HOLDING, RELEASED, SLIDING, SLIP_SPEED)
from .attachments import hold, holds
from .body_contact import respond
from .clock import STEP_START
from .contact import along, impacts
from .implicit_bodies import penalty_end
from .implicit_lookup import look_up, refuse_turning, swept, unseen
from .implicit_system import diagonal_blocks, pushes, rowdot, solve_step, tangential
from .pins import place
from .solve import newton_rhs, system_matrix


class Constraints(NamedTuple):
    kind: np.ndarray       # (P,) FREE, CONTACT, PINNED
    terrain: np.ndarray    # (P,) the contact's terrain or -1
    normal: np.ndarray     # (P, 3)
    floor: np.ndarray      # (P,) m/s
    floor_case: np.ndarray
    surface: np.ndarray    # (P, 3) m/s, the terrain's surface velocity (0 on a still one)
    at: np.ndarray         # (P, 3) m, where the contact was looked up (implicit_lookup.Lookup)
    ahead: np.ndarray      # (P,) s, how far along the particle's path: 0 where not swept


def floor_value(case, phi, v_n, s_n, h):
    """Each contact's floor as the forward made it (constraints.lowest_normal_velocity), by the
    expression its ``case`` names (the step's record); s_n the surface's normal velocity."""
    return np.select([case == FLOOR_VELOCITY, case == FLOOR_ZERO, case == FLOOR_INSIDE],
                     [s_n + (v_n - s_n), s_n + 0.0, -np.maximum(phi, 0.0) / h], -phi / h)


def touched_terrains(physical, record) -> bool:
    """Whether the step had terrain contacts, as its record says: some contact at its start or
    made within it. A step the forward cut into parts is refused: its record is the last
    part's."""
    if record.counts[2] > 0:
        now = float(physical.clock[STEP_START])
        raise SceneError("dt", "implicit_euler", f"took the step at {now:.6g} s in parts (a "
                         "surface carried through another), which gradients do not follow: "
                         "try a smaller dt")
    return bool(np.any(record.kind == CONTACT) or np.any(record.rows >= GROWN))


def recorded_constraints(record, x, v, h, previous_kind, previous_terrain, lookups):
    """The constraints the forward's step started with (its record: each particle's kind,
    terrain and floor's case), with their values at x: (Constraints, whether each contact
    continues the last step's, with the same terrain, and so keeps its damper)."""
    count = x.shape[0]
    kind = record.kind.astype(np.int64)
    terrain = record.terrain.copy()
    constraints = Constraints(kind, terrain, np.zeros((count, 3)), np.zeros(count),
                              record.floor_case.astype(np.int64), np.zeros((count, 3)),
                              x.copy(), np.zeros(count))
    for lookup in lookups:
        rows = np.nonzero(terrain == lookup.terrain)[0]
        take_contacts(constraints, lookup, rows, v, h)
    continues = (kind == CONTACT) & (previous_kind == CONTACT) & (previous_terrain == terrain)
    return constraints, continues


def take_contacts(constraints, lookup, rows, v, h):
    """Fill the contacts ``rows`` with ``lookup``'s terrain there: normal, surface velocity,
    where it was looked up and the floor of the case the record gives (in place)."""
    n = lookup.normal[rows]
    surface = np.zeros((len(rows), 3)) if lookup.surface is None else lookup.surface[rows]
    constraints.terrain[rows] = lookup.terrain
    constraints.normal[rows], constraints.surface[rows] = n, surface
    constraints.at[rows], constraints.ahead[rows] = lookup.at[rows], lookup.ahead[rows]
    constraints.floor[rows] = floor_value(constraints.floor_case[rows], lookup.phi[rows],
                                          along(v[rows], n), rowdot(surface, n), h)


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
    cap: "Cap"            # the carried dampers it capped
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


def replay(physical, h, x, v, memory, record, penalty=None):
    """The step as the forward took it (module doc), each solve exact, each choice the one the
    forward's ``record`` (implicit/step_record.py) says it made; ``memory``: the contact memory
    the step started from, (kind, terrain, friction dampers). With ``penalty`` (an
    implicit_bodies.PenaltyStep) the bodies' penalty contacts in every solve, their friction
    after it and the post-step pass. Returns (x', v', the dampers it leaves, Replay)."""
    previous_kind, previous_terrain, c_memory = memory
    lookups = look_up(physical, x, v, h)
    constraints, continues = recorded_constraints(record, x, v, h, previous_kind,
                                                  previous_terrain, lookups)
    c = np.where(continues, c_memory, 0.0)
    dv = np.zeros_like(x)
    passes = iter(record.rows)
    iterations = []
    for updates, solves, again in record.tries:
        first = not any(not it.again for it in iterations)
        it, c, ddv = replay_iteration(physical, h, (x, v), constraints, lookups, dv, c,
                                      (first, updates, solves, bool(again)), passes, penalty)
        iterations.append(it)
        if not it.again:
            dv = dv + ddv
    x_out, v_out, end, bodies, held = replay_end(physical, h, x, v, dv, record, constraints,
                                                 penalty)
    return x_out, v_out, c, Replay(constraints, continues, iterations,
                                   np.nonzero(record.restored)[0], end.found, end.states,
                                   bodies, lookups, held)


class End(NamedTuple):
    found: list    # contact.impacts' record
    states: tuple  # (x, v) before the impact pass, and v before the restoring


def replay_end(physical, h, x, v, dv, record, constraints, penalty):
    """The step's end after its Newton iterations: the penalty contacts' friction, x from v,
    the approach speeds the forward restored (its record), the held pins and attachments, the
    impact pass and the bodies' post-step pass. Returns (x', v', End, Bodies or None, held)."""
    v_k = v + dv
    bodies = None
    if penalty is not None:   # the penalty contacts' friction, then x from v again
        v_k, friction, x_before = penalty_end(physical, penalty, h, x, v_k)
        bodies = Bodies(penalty, friction, x_before, None)
    x_end = x + h * v_k
    restored = np.nonzero(record.restored)[0]   # restore_impact_speeds
    n = constraints.normal[restored]
    v_end = v_k.copy()
    v_end[restored] += (rowdot(v[restored], n) - rowdot(v_k[restored], n))[:, None] * n
    x_out, v_out, held = x_end, v_end, None
    if holds(physical):   # the pins on paths placed, the hard attachments held (_steps.collide)
        x_out, v_out, held = hold(physical, *place(physical, x_end, v_end))
    x_out, v_out, found = impacts(physical, x_out, v_out)
    if bodies is not None:   # the pins on paths placed, then the post-step pass
        x_out, v_out, response = respond(physical, *place(physical, x_out, v_out), x)
        bodies = bodies._replace(response=response)
    return x_out, v_out, End(found, (x_end, v_end, v_k)), bodies, held


def replay_iteration(physical, h, start, constraints, lookups, dv, c, shape, passes, penalty):
    """One Newton iteration (or a try of one) from dv, as the record's ``shape`` (first,
    update passes, solves, solved again) and its ``passes`` say: the cap of the carried
    dampers (first only), then solve, update, solve ... Returns (Iteration, the dampers it
    leaves, its last solve's ddv)."""
    x, v = start
    first, updates, solves, again = shape
    kind = constraints.kind
    x_k, v_k = (x, v) if first else (x + h * (v + dv), v + dv)
    matrix = system_matrix(physical, x_k, v_k, h)
    b_sp = newton_rhs(physical, h, x, v, dv, first)
    if penalty is not None:
        penalty.linearize(dv)

    def active():
        return None if penalty is None else penalty.contacts.active.copy()

    def full():
        """The matrix and right-hand side with the penalty contacts active now."""
        if penalty is None:
            return matrix, b_sp
        return matrix + penalty.matrix(), b_sp + penalty.rhs

    u0 = v + dv
    blocks = diagonal_blocks(physical, x_k, v_k, h)
    cap = Cap.none()
    cap_active = active()
    if first:   # remembered_friction_in_cone
        cap = capped_dampers(physical, constraints, np.nonzero(next(passes) == CAPPED)[0],
                             blocks, full()[1], u0, c)
        c = c.copy()
        c[cap.index] = cap.lowered
    c_start = c.copy()
    ddv, reaction = solve_step(physical, constraints, kind, *full(), u0, c)
    steps = [Solve(kind.copy(), c.copy(), ddv, pushes(kind, constraints.normal, reaction),
                   active())]
    for update_number in range(updates):
        solved_with = active()
        update, c = update_contacts(physical, h, (x, v), constraints, lookups, next(passes),
                                    (blocks, reaction, u0, c, ddv))
        steps.append(update._replace(active=solved_with))
        if penalty is not None:
            penalty.update(held_grown(constraints, update.grown, u0, ddv))
        if update_number + 1 < solves:
            ddv, reaction = solve_step(physical, constraints, kind, *full(), u0, c)
            steps.append(Solve(kind.copy(), c.copy(), ddv,
                               pushes(kind, constraints.normal, reaction), active()))
    if penalty is not None:
        penalty.keep(dv, first, ddv)
        # a fold closing within the solve: the iteration again, from its dv, with the own
        # pairs it brought into contact; the terrain contacts and dampers as it left them
        if penalty.regrow(dv, ddv) != again:
            refuse_own_pairs(physical)
    return Iteration(dv, first, cap, c_start, steps, c.copy(), cap_active, again), c, ddv


def refuse_own_pairs(physical):
    """Refuse a step whose self-colliding body's own pairs the replay finds grown otherwise than
    the forward did (they are not in the step's record yet)."""
    now = float(physical.clock[STEP_START])
    raise SceneError("bodies", "self_collision", f"closes a fold within the step at {now:.6g} "
                     "s that the gradient's replay finds otherwise than the run did, which "
                     "gradients do not follow under implicit_euler: try a smaller dt")


def refuse_another_contact(physical, constraints, i, terrain):
    """Refuse the step where particle i, a contact earlier in it and let go, is taken again on
    another terrain: the adjoint holds one contact per particle and step (its Constraints)."""
    if constraints.terrain[i] < 0 or constraints.terrain[i] == terrain:
        return
    now = float(physical.clock[STEP_START])
    raise SceneError(f"terrains.{terrain}", "contact", f"takes particle {i} again within the "
                     f"step at {now:.6g} s, where it was let go, on another terrain, which "
                     "gradients do not follow under implicit_euler: try a smaller dt")


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


class Cap(NamedTuple):
    """The carried dampers that the first iteration capped to the friction cone
    (remembered_friction_in_cone), with what the cap read."""

    index: np.ndarray     # the contacts capped
    c_in: np.ndarray      # their carried dampers
    slip: np.ndarray      # |u_t| at the iteration's start
    impulse: np.ndarray   # the normal impulse estimated from the particle's own block
    gap: np.ndarray       # floor - n . u0
    b_rows: np.ndarray    # (K, 3) their rows of the right-hand side
    lowered: np.ndarray   # the dampers they were lowered to: Coulomb's impulse / slip

    @classmethod
    def none(cls) -> "Cap":
        empty = np.empty(0)
        return cls(np.empty(0, np.int64), empty, empty, empty, empty, np.empty((0, 3)), empty)


def capped_dampers(physical, constraints, index, blocks, b_sp, u0, c) -> Cap:
    """The carried dampers of the contacts ``index`` that the forward capped (its record),
    each lowered to Coulomb's impulse / slip."""
    n = constraints.normal[index]
    gap = constraints.floor[index] - rowdot(u0[index], n)
    slip = np.linalg.norm(tangential(u0[index] - constraints.surface[index], n), axis=1)
    along_normal = np.einsum("ki,kij,kj->k", n, blocks[index], n)
    impulse = -rowdot(b_sp[index], n) + gap * along_normal
    coulomb = physical.friction[constraints.terrain[index]] * np.maximum(impulse, 0.0)
    lowered = np.where(slip > 0.0, coulomb / np.where(slip > 0.0, slip, 1.0), 0.0)
    return Cap(index, c[index].copy(), slip, impulse, gap, b_sp[index], lowered)


def update_contacts(physical, h, start, constraints, lookups, decided, solved):
    """constraints.update_contacts as the forward's record says it went: ``decided`` (P,) is
    what the pass decided for each particle (UNCHANGED, SLIDING, HOLDING, RELEASED, GROWN plus
    the terrain); ``solved`` = (the diagonal blocks, the reaction R = A_sp ddv - b_sp, u0, the
    dampers, ddv) of the solve before it. Returns (Update, the dampers after it); the
    constraints grow and shrink in place as the forward's do."""
    blocks, reaction, u0, c, ddv = solved
    x, v = start
    kind = constraints.kind
    released = np.nonzero(decided == RELEASED)[0]
    grown = np.nonzero(decided >= GROWN)[0]
    kind[released] = FREE
    c_new = c.copy()
    c_new[released] = 0.0
    c_new[grown] = 0.0
    grow(physical, h, (x, v, u0 + ddv), constraints, lookups, grown, decided[grown] - GROWN)
    index = np.nonzero((decided == SLIDING) | (decided == HOLDING))[0]
    case = decided[index].astype(np.int64)
    n = constraints.normal[index]
    impulse = rowdot(reaction[index], n)
    relative = u0[index] + ddv[index] - constraints.surface[index]
    slip = np.sqrt(np.einsum("ij,ij->i", *(2 * (tangential(relative, n),))))
    coulomb = physical.friction[constraints.terrain[index]] * impulse
    block = blocks[index]
    stiffness = 0.5 * (np.einsum("kii->k", block) - np.einsum("ki,kij,kj->k", n, block, n))
    # a contact the forward saw slide slides here too, on at least SLIP_SPEED
    sliding = np.maximum(((stiffness + c[index]) * slip - coulomb) / stiffness, SLIP_SPEED)
    c_new[index] = np.where(case == SLIDING, coulomb / sliding, coulomb / SLIP_SPEED)
    update = Update(index, case, c.copy(), slip, impulse, stiffness, sliding, released, grown,
                    reaction[index])
    return update, c_new


def grow(physical, h, motion, constraints, lookups, rows, terrains):
    """Make the free particles ``rows`` contacts on the ``terrains`` the forward's update found
    them reaching (in place), looked up as it did: a particle the start's lookup does not see
    asked along its path at the solve's end velocity u."""
    x, v, u = motion
    for lookup in lookups:
        ours = rows[terrains == lookup.terrain]
        if not len(ours):
            continue
        for i in ours:
            refuse_another_contact(physical, constraints, i, lookup.terrain)
        hidden = ours[unseen(lookup)[ours]]
        if len(hidden):
            lookup = swept(physical, lookup, x, u, h, hidden)
            for i in hidden[lookup.ahead[hidden] > 0.0]:
                refuse_turning(physical, lookup, i)
        constraints.kind[ours] = CONTACT
        take_contacts(constraints, lookup, ours, v, h)
