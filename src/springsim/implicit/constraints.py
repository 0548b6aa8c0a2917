"""Pinned particles and terrain contact as constraints on the velocity change of a step.

Baraff and Witkin (1998, section 5) enforce constraints inside the linear solve: a filter
S_i = I (free), I - n n^T (normal fixed) or 0 (all fixed) removes the constrained components from
every conjugate-gradient direction, so the solve keeps them at the values it starts from.

Contact, as collision/response/terrain.py does it but for a whole implicit step:
- A particle is in contact with a terrain when it is in the contact band (phi < epsilon) or will
  be by the end of the step at its current velocity (phi + h v_n < epsilon). The second case is
  what keeps large steps honest: a particle falling 0.4 m per step would otherwise be driven deep
  into the terrain by the solve and then lifted out alone, crushing the lattice above it.
  A particle that a solve released (its terrain would have had to pull) is not looked ahead
  for again while it stays free and within a terrain's reach: outside the band it joins at a
  step's start only if it would end the step inside (phi + h v_n < 0), and otherwise joins if
  the solve carries it inside (the update below). Its memory marks it with a terrain (the one
  that released it, then the one its look-ahead finds first), cleared once no terrain is in
  reach (``joins_afresh``).
  Without that, cloth lying on a figure that walks away under it had hundreds of its
  particles just outside the band taken as contacts at every step only for the first update
  to release them again, each release costing a solve. A particle never released keeps the
  look-ahead: a layer of cloth pressed down fast onto another is stopped on the floor's
  surface, not first carried into it. The band itself is as before (for the terrain reached
  first): a rule there (say, free while moving away) would flip resting particles in and out
  at every step, and make the run jump with the smallest change of a parameter.
- A contact's normal velocity at the end of the step is held at a floor v'_n = bound:
  outside the band, bound = -phi/h: it may end the step on the surface, not beyond; in the band,
  bound = max(min(v_n, 0), -phi/h): the terrain cancels the forces that would push the particle in
  (as collision/response/terrain.py does), stops it at the surface, and lets a leaving particle
  slow down but not turn back into the terrain. The solve therefore never moves a particle into a
  terrain.
- Coulomb friction is part of the solve, so that the springs feel it in the same step (applied
  afterwards, it would hold a contact still while the springs carry the rest of the body on, and
  fold the lattice at the first impact of a large step). It enters as a tangential damper: c
  (N s/m) times the tangential velocity, against it, which adds c (I - n n^T) to the matrix and
  keeps it symmetric positive definite. c is chosen after each solve (``coulomb_damping``) so
  that the impulse is friction * lambda_n (lambda_n the normal impulse) on a contact that
  slides, and so that a contact friction can hold creeps at most at SLIP_SPEED (regularized
  Coulomb friction: a slip speed that no one will see, and no sticking state to flip in and
  out of).
- After each solve the contacts are updated from their reaction impulses R = A dv - b, and the
  system solved again (an active set with a fixed-point update of c, a few passes at most): a
  contact whose normal impulse lambda_n = R . n is negative is released (the terrain can push,
  not pull), c is recomputed, and a free particle that the solved velocities carry into a
  terrain becomes a contact. Contacts and their c carry over to the next step as its first
  guess, so a body at rest or sliding steadily needs one solve a step; a carried c that would
  give the step's starting velocity more than the Coulomb impulse (a held body set sliding) is
  lowered to it first (``remembered_friction_in_cone``).
- Restitution is left to the impact pass every integrator runs after its step
  (``_steps.collide``), which reflects whatever normal velocity still approaches a terrain.
  A contact that the floor slowed down (an impact: it came in faster than the floor allows) ends
  the step on the surface, and gets its approach speed back for that pass to reflect: the
  bounce is e times the speed of the impact, not of the slowed arrival
  (``restore_impact_speeds``).
One terrain per particle: the one it reaches first. A particle touching two terrains at once has
the second handled by the impact pass alone.
"""
import math
from typing import NamedTuple

import numpy as np

from .._jit import inline_kernel, kernel
from ..terrains import still_terrain_distance
from ..world import surface_velocity, terrain_at, terrain_view
from .terrain_lookups import beyond_reach, closest_terrain, swept_lookups

FREE, CONTACT, PINNED = 0, 1, 2
# how a contact's floor came about (lowest_normal_velocity): -phi / h, the normal velocity
# itself, the surface's normal velocity (slowed to it), or zero (inside: -max(phi, 0) / h)
FLOOR_GAP, FLOOR_VELOCITY, FLOOR_ZERO, FLOOR_INSIDE = 0, 1, 2, 3
# what a pass decided for each particle (ContactSlots.case; implicit/step_record.py keeps them
# for the gradient): nothing, a carried damper capped to the friction cone, a damper chosen for
# a contact that slides or one friction holds, a contact released, a contact made (GROWN plus
# its terrain's index)
UNCHANGED, CAPPED, SLIDING, HOLDING, RELEASED, GROWN = 0, 1, 2, 3, 4, 8
SLIP_SPEED = 1e-6        # m/s, the creep speed below which friction acts as a plain damper
FRICTION_SETTLED = 0.02  # relative change of the friction impulses that needs no new solve


class ContactSlots(NamedTuple):
    """Where the constraints of a step are written, per particle: the state's contact memory
    and the step's work arrays (integrators/implicit_euler.py)."""

    kind: np.ndarray              # (P,) int8: FREE, CONTACT or PINNED
    terrain: np.ndarray           # (P,) int64: the contact's terrain; free: a release's mark
    normal: np.ndarray            # (P, 3): the contact's terrain normal
    surface: np.ndarray           # (P, 3) m/s: the terrain surface's velocity there
    normal_floor: np.ndarray      # (P,) m/s: the lowest normal velocity the contact allows
    friction_damping: np.ndarray  # (P,) N s/m: the friction damper in the system
    floor_case: np.ndarray        # (P,) int8: how the floor came about (FLOOR_GAP, ...)
    case: np.ndarray              # (P,) int16: what the last pass decided (UNCHANGED, ...)


@kernel
def lowest_normal_velocity(phi, v_n, s_n, h, epsilon):
    """(the floor a contact's normal velocity is held at by the end of the step (module doc),
    which of its expressions it is: FLOOR_GAP, ...); s_n is the terrain surface's normal
    velocity (zero for a still terrain): in the band a particle may slow down to it but not
    fall behind it."""
    if phi >= epsilon:
        return -phi / h, FLOOR_GAP
    low, gap = s_n + min(v_n - s_n, 0.0), -max(phi, 0.0) / h
    if low >= gap:
        return low, FLOOR_VELOCITY if v_n - s_n < 0.0 else FLOOR_ZERO
    return gap, FLOOR_GAP if phi > 0.0 else FLOOR_INSIDE


@inline_kernel
def make_contact(terrains, epsilon, x, i, t, found, h, slots):
    """Particle i becomes a contact with terrain t, ``found`` = (phi, nx, ny, nz, v_n) there."""
    phi, nx, ny, nz, v_n = found
    slots.kind[i] = CONTACT
    slots.terrain[i] = t
    slots.normal[i, 0], slots.normal[i, 1], slots.normal[i, 2] = nx, ny, nz
    s0, s1, s2 = surface_velocity(terrains, t, x[i, 0], x[i, 1], x[i, 2])
    slots.surface[i, 0], slots.surface[i, 1], slots.surface[i, 2] = s0, s1, s2
    slots.normal_floor[i], slots.floor_case[i] = lowest_normal_velocity(
        phi, v_n, s0 * nx + s1 * ny + s2 * nz, h, epsilon[t])


@kernel
def find_constraints(model, x, v, h, slots, lookups):
    """Classify every particle at the start of a step (PINNED, FREE or CONTACT); set each
    contact's terrain, normal and floor. A contact that continues one of the last step keeps
    its friction damper as the first guess; a new one starts without. ``kind`` and ``terrain``
    come in as the last step left them: a free particle with a terrain is one a solve released
    (update_contacts), which must also pass ``joins_afresh``, and stays marked (with the
    terrain found now) if it does not. Fills ``lookups`` for the step's
    update_contacts."""
    terrains, epsilon = terrain_view(model), model.terrain_epsilon
    kind, terrain, friction_damping = slots.kind, slots.terrain, slots.friction_damping
    swept = np.empty((1, lookups.shape[1], 4))   # a particle's lookups along its path
    for i in range(x.shape[0]):
        previous = terrain[i] if kind[i] == CONTACT else -1
        released = kind[i] == FREE and terrain[i] >= 0
        kind[i] = FREE
        terrain[i] = -1
        if model.inv_mass[i] == 0.0:
            kind[i] = PINNED
        else:
            radius = model.terrain_offset[i]
            # each terrain's (phi, normal) at the step's start, where the step's end has it, for
            # every closest_terrain of the step: a still terrain looked up directly, as
            # collision/response/terrain.py's STILL_LOOKUP does (through the view, in an inline
            # kernel per particle, the cube's search was 1.4 to 1.5 times slower:
            # benchmarks/contact_search.py)
            for t in range(lookups.shape[1]):
                if model.terrain_motion[t] < 0 and model.terrain_deforming[t] < 0:
                    phi, mx, my, mz = still_terrain_distance(
                        model.terrain_kind[t], model.terrain_parameters[t], model.terrain_data,
                        x[i, 0], x[i, 1], x[i, 2], radius)
                else:
                    phi, mx, my, mz = terrain_at(terrains, t, x[i, 0], x[i, 1], x[i, 2], radius)
                lookups[i, t, 0], lookups[i, t, 1] = phi, mx
                lookups[i, t, 2], lookups[i, t, 3] = my, mz
            # two calls, so that the usual one, reading the lookups, is inlined alone
            if beyond_reach(lookups, i):
                swept_lookups(terrains, epsilon, radius, lookups, x, i, v[i, 0], v[i, 1],
                              v[i, 2], h, swept)
                t, phi, nx, ny, nz, v_n = closest_terrain(epsilon, swept, 0, v[i, 0], v[i, 1],
                                                          v[i, 2], h, True)
            else:
                t, phi, nx, ny, nz, v_n = closest_terrain(epsilon, lookups, i, v[i, 0], v[i, 1],
                                                          v[i, 2], h, True)
            if t >= 0 and released and not joins_afresh(phi, v_n, h, epsilon[t]):
                terrain[i] = t   # still free, still marked as released
            elif t >= 0:
                make_contact(terrains, epsilon, x, i, t, (phi, nx, ny, nz, v_n), h, slots)
        if kind[i] != CONTACT or terrain[i] != previous:
            friction_damping[i] = 0.0


@kernel
def joins_afresh(phi, v_n, h, epsilon):
    """Whether a particle that a solve released, free since, is a contact at this step's start
    (module doc): it is in the band, or would end the step inside at its velocity."""
    return phi < epsilon or phi + h * v_n < 0.0


@kernel
def hold_constrained(i, kind, normal, normal_floor, v, dv, ddv):
    """Set the components of ddv that particle i's constraint fixes, so that v + dv + ddv meets
    it: at rest for PINNED (v = 0), on the floor for CONTACT. Free components stay as they are."""
    if kind[i] == PINNED:
        ddv[i, 0] = ddv[i, 1] = ddv[i, 2] = 0.0
    elif kind[i] == CONTACT:
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        gap = (normal_floor[i] - (v[i, 0] + dv[i, 0] + ddv[i, 0]) * nx
               - (v[i, 1] + dv[i, 1] + ddv[i, 1]) * ny - (v[i, 2] + dv[i, 2] + ddv[i, 2]) * nz)
        ddv[i, 0] += gap * nx
        ddv[i, 1] += gap * ny
        ddv[i, 2] += gap * nz


@kernel
def hold_all_constrained(kind, normal, normal_floor, v, dv, ddv):
    """hold_constrained for every particle: after a solve, whose filtered steps leave rounding
    in the components it must not change, so that no contact ends off its floor."""
    for i in range(ddv.shape[0]):
        hold_constrained(i, kind, normal, normal_floor, v, dv, ddv)


@kernel
def filter_constrained(kind, normal, u):
    """u = S u: remove the normal component of contacts and everything of pinned particles."""
    for i in range(u.shape[0]):
        u[i, 0], u[i, 1], u[i, 2] = filtered(kind[i], normal[i, 0], normal[i, 1], normal[i, 2],
                                             u[i, 0], u[i, 1], u[i, 2])


@kernel
def filtered(kind, n0, n1, n2, u0, u1, u2):
    """S_i u_i for one particle of the given kind and normal. Scalars in and out: a kernel
    called per particle with arrays as arguments costs a reference count up and down per array
    (about a hundred times the work of filtering a free particle)."""
    if kind == FREE:
        return u0, u1, u2
    if kind == PINNED:
        return 0.0, 0.0, 0.0
    u_n = u0 * n0 + u1 * n1 + u2 * n2
    return u0 - u_n * n0, u1 - u_n * n1, u2 - u_n * n2


@kernel
def set_friction_damping(i, value, pattern, blocks, rhs, normal, surface, v, dv,
                         friction_damping):
    """Make particle i's friction damper c = value in the system: its diagonal block holds
    c (I - n n^T), and the right-hand side -c (I - n n^T)(v + dv - s), so that the impulse on the
    solved velocity change ddv is -c (I - n n^T)(v + dv + ddv - s): against the sliding
    relative to the terrain's surface velocity s."""
    change = value - friction_damping[i]
    if change == 0.0:
        return
    friction_damping[i] = value
    slot = pattern.diagonal_slot[i]
    nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
    n = (nx, ny, nz)
    u0, u1, u2 = (v[i, 0] + dv[i, 0] - surface[i, 0], v[i, 1] + dv[i, 1] - surface[i, 1],
                  v[i, 2] + dv[i, 2] - surface[i, 2])
    u_n = u0 * nx + u1 * ny + u2 * nz
    rhs[i, 0] -= change * (u0 - u_n * nx)
    rhs[i, 1] -= change * (u1 - u_n * ny)
    rhs[i, 2] -= change * (u2 - u_n * nz)
    for r in range(3):
        for c in range(3):
            blocks[slot, r, c] += change * ((1.0 if r == c else 0.0) - n[r] * n[c])


@kernel
def remembered_friction_in_cone(model, pattern, blocks, rhs, i, slots, v, dv, ddv, damping):
    """(the friction damper c that contact i carries over from the last step, whether it was
    lowered): lowered where it would leave the friction cone, c |u_t| <= friction * lambda_n,
    u_t the tangential velocity the step starts from; ``slots`` the step's ContactSlots. Without this a contact that friction held at rest (c = Coulomb /
    SLIP_SPEED) and is then set sliding (a push, a kick, a velocity given between steps) starts
    the solve with a friction impulse c |u_t| millions of times Coulomb's: the first solve stops
    the body, tips it over its leading edge, and leaves a right-hand side so large that the
    re-solves after the friction update meet their tolerance without an iteration (the cube
    given 3 m/s on the plane lost 10 times Coulomb's impulse in that step).

    lambda_n is estimated as ``coulomb_damping`` estimates slip, as if the rest of the system
    stayed put: the reaction n . (A_ii ddv_i - b_i) of the particle's own block, with ddv_i the
    velocity change that holds it on its floor (``hold_constrained``) and no friction in A_ii
    or b_i yet. For a resting or steadily sliding contact it is the load it carries (the
    springs and gravity in b), and the cap leaves c as it was.

    The impulse that c can take is that of c in series with the particle's own tangential
    stiffness d (``tangential_stiffness``): c d / (c + d) |u_t|, at most the momentum d |u_t|
    it would take to stop the slip. A contact that friction holds on a turning support starts
    each step slipping by the support's acceleration times h (it moved on along a straight
    line while the surface turned under it); c |u_t| alone would read that as a kick, lower c
    at every step and need a second solve to restore it."""
    kind, terrain, normal, surface = slots.kind, slots.terrain, slots.normal, slots.surface
    if kind[i] != CONTACT or damping == 0.0:
        return damping, False
    nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
    u0, u1, u2 = (v[i, 0] + dv[i, 0] - surface[i, 0], v[i, 1] + dv[i, 1] - surface[i, 1],
                  v[i, 2] + dv[i, 2] - surface[i, 2])   # relative to the surface
    u_n = u0 * nx + u1 * ny + u2 * nz
    slip = math.sqrt((u0 - u_n * nx) ** 2 + (u1 - u_n * ny) ** 2 + (u2 - u_n * nz) ** 2)
    slot = pattern.diagonal_slot[i]
    impulse_n = -(rhs[i, 0] * nx + rhs[i, 1] * ny + rhs[i, 2] * nz)
    for r in range(3):
        for c in range(3):
            impulse_n += normal[i, r] * blocks[slot, r, c] * ddv[i, c]
    coulomb = model.terrain_friction[terrain[i]] * max(impulse_n, 0.0)
    d = tangential_stiffness(pattern, blocks, normal, i)
    taken = damping * d / (damping + d) if d > 0.0 else damping
    if taken * slip > coulomb:
        return coulomb / slip, True
    return damping, False


@kernel
def tangential_stiffness(pattern, blocks, normal, i):
    """Half the trace of particle i's diagonal block across its normal: (trace - n^T A_ii n)
    / 2, how much momentum a unit tangential velocity change of it takes."""
    slot = pattern.diagonal_slot[i]
    along_normal = 0.0
    for r in range(3):
        for c in range(3):
            along_normal += normal[i, r] * blocks[slot, r, c] * normal[i, c]
    trace = blocks[slot, 0, 0] + blocks[slot, 1, 1] + blocks[slot, 2, 2]
    return 0.5 * (trace - along_normal)


@kernel
def coulomb_damping(pattern, blocks, normal, i, damping, slip, coulomb):
    """The friction damper that gives contact i the Coulomb impulse, estimated from the last
    solve as if the rest of the system stayed put. With the particle's own tangential stiffness
    d (its diagonal block across the normal, without friction) and damper c, the solve left it
    the tangential momentum p = (d + c) slip. Coulomb friction removes min(p, coulomb) of it:
    it slides on at (p - coulomb) / d > SLIP_SPEED with c = coulomb / slip, or it holds, with
    c = coulomb / SLIP_SPEED. Returns (c, SLIDING or HOLDING)."""
    stiffness = tangential_stiffness(pattern, blocks, normal, i) - damping
    momentum = (stiffness + damping) * slip
    sliding = (momentum - coulomb) / stiffness
    if sliding > SLIP_SPEED:
        return coulomb / sliding, SLIDING
    return coulomb / SLIP_SPEED, HOLDING


@kernel
def update_contacts(model, pattern, blocks, rhs, x, v, dv, ddv, h, slots, reaction, lookups):
    """One active-set pass (module doc), given the reaction impulses R = A ddv - b of the last
    solve and the step's ``lookups`` (find_constraints). Adjusts ddv, the matrix and the
    right-hand side to every change, and writes what it decided for each particle into
    ``slots.case``. Returns whether another solve is needed: some contact came or went, or the
    friction impulses (summed over all contacts) moved by more than FRICTION_SETTLED of their
    total."""
    changed = 0
    friction_total = friction_moved = 0.0
    terrains, epsilon = terrain_view(model), model.terrain_epsilon
    # the particle loop reads its arrays as locals (a named tuple's field read inside it counts
    # a reference at every particle)
    kind, terrain, normal, surface, normal_floor, friction_damping, case = (
        slots.kind, slots.terrain, slots.normal, slots.surface, slots.normal_floor,
        slots.friction_damping, slots.case)
    swept = np.empty((1, lookups.shape[1], 4))   # a particle's lookups along its path
    for i in range(x.shape[0]):
        case[i] = UNCHANGED
        if kind[i] == PINNED:
            continue
        u0, u1, u2 = (v[i, 0] + dv[i, 0] + ddv[i, 0], v[i, 1] + dv[i, 1] + ddv[i, 1],
                      v[i, 2] + dv[i, 2] + ddv[i, 2])   # the velocity at the end of the step
        if kind[i] == FREE:
            # two calls, so that the usual one, reading the lookups, is inlined alone
            if beyond_reach(lookups, i):
                swept_lookups(terrains, epsilon, model.terrain_offset[i], lookups, x, i, u0, u1,
                              u2, h, swept)
                t, phi, nx, ny, nz, _ = closest_terrain(epsilon, swept, 0, u0, u1, u2, h, False)
            else:
                t, phi, nx, ny, nz, _ = closest_terrain(epsilon, lookups, i, u0, u1, u2, h, False)
            if t >= 0:
                v_n = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
                make_contact(terrains, epsilon, x, i, t, (phi, nx, ny, nz, v_n), h, slots)
                hold_constrained(i, kind, normal, normal_floor, v, dv, ddv)
                case[i] = GROWN + t
                changed += 1
            continue
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        impulse_n = reaction[i, 0] * nx + reaction[i, 1] * ny + reaction[i, 2] * nz
        if impulse_n < 0.0:
            kind[i] = FREE   # the terrain would have to pull
            set_friction_damping(i, 0.0, pattern, blocks, rhs, normal, surface, v, dv,
                                 friction_damping)
            case[i] = RELEASED
            changed += 1
            continue
        u0, u1, u2 = u0 - surface[i, 0], u1 - surface[i, 1], u2 - surface[i, 2]   # relative
        u_n = u0 * nx + u1 * ny + u2 * nz
        slip = math.sqrt((u0 - u_n * nx) ** 2 + (u1 - u_n * ny) ** 2 + (u2 - u_n * nz) ** 2)
        coulomb = model.terrain_friction[terrain[i]] * impulse_n
        damping, case[i] = coulomb_damping(pattern, blocks, normal, i, friction_damping[i], slip,
                                           coulomb)
        friction_total += coulomb
        friction_moved += abs(damping - friction_damping[i]) * max(slip, SLIP_SPEED)
        set_friction_damping(i, damping, pattern, blocks, rhs, normal, surface, v, dv,
                             friction_damping)
    return changed > 0 or friction_moved > FRICTION_SETTLED * friction_total


@kernel
def restore_impact_speeds(kind, normal, normal_floor, v_start, v_end, restored):
    """Give every contact that hit its terrain this step (it started faster into it than its
    floor) its normal velocity from the start of the step back, for the impact pass to reflect;
    its position already ends on the surface (module doc). ``restored`` says which were."""
    for i in range(v_end.shape[0]):
        restored[i] = False
        if kind[i] != CONTACT:
            continue
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        approach = v_start[i, 0] * nx + v_start[i, 1] * ny + v_start[i, 2] * nz
        if approach >= normal_floor[i]:
            continue
        end = v_end[i, 0] * nx + v_end[i, 1] * ny + v_end[i, 2] * nz
        if end > normal_floor[i] + 1e-12 * abs(normal_floor[i]) + 1e-12:
            continue   # the springs carried it off the surface: no impact to restore
        change = approach - end
        restored[i] = True
        v_end[i, 0] += change * nx
        v_end[i, 1] += change * ny
        v_end[i, 2] += change * nz
