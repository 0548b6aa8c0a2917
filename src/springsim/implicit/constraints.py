"""Pinned particles and terrain contact as constraints on the velocity change of a step.

Baraff and Witkin (1998, section 5) enforce constraints inside the linear solve: a filter
S_i = I (free), I - n n^T (normal fixed) or 0 (all fixed) removes the constrained components from
every conjugate-gradient direction, so the solve keeps them at the values it starts from.

Contact, as contact.py does it but for a whole implicit step:
- A particle is in contact with a terrain when it is in the contact band (phi < epsilon) or will
  be by the end of the step at its current velocity (phi + h v_n < epsilon). The second case is
  what keeps large steps honest: a particle falling 0.4 m per step would otherwise be driven deep
  into the terrain by the solve and then lifted out alone, crushing the lattice above it.
- A contact's normal velocity at the end of the step is held at a floor v'_n = bound:
  outside the band, bound = -phi/h: it may end the step on the surface, not beyond;
  in the band, bound = max(min(v_n, 0), -phi/h): the terrain cancels the forces that would push
  the particle in (as contact.py does), stops it at the surface, and lets a leaving particle slow
  down but not turn back into the terrain. The solve therefore never moves a particle into a
  terrain.
- Coulomb friction is part of the solve, so that the springs feel it in the same step (applied
  afterwards, it would hold a contact still while the springs carry the rest of the body on, and
  fold the lattice at the first impact of a large step). A contact is STUCK (tangential velocity
  held at zero as well) or SLIDING (a kinetic friction impulse friction * lambda_n against its
  tangential velocity enters the right-hand side).
- After each solve the contacts are updated from their reaction impulses R = A dv - b, and the
  system solved again (an active set, a few passes at most): a contact whose normal impulse
  lambda_n = R . n is negative is released (the terrain can push, not pull); a stuck contact whose
  tangential impulse leaves the cone |R_T| <= friction * lambda_n starts to slide; a sliding one
  whose friction has reversed its motion sticks; a free particle that the solved velocities carry
  into a terrain becomes a contact.
- Restitution is left to the impact pass every integrator runs after its step
  (``_steps.finish_step``), which reflects whatever normal velocity still approaches a terrain.
One terrain per particle: the one it reaches first. A particle touching two terrains at once has
the second handled by the impact pass alone.
"""
import math

import numpy as np

from .._jit import kernel
from ..contact import terrain_distance

FREE, SLIDING, STUCK, PINNED = 0, 1, 2, 3
STICKING_TOLERANCE = 1e-9  # relative slack of the friction cone, against round-off flip-flops


@kernel
def lowest_normal_velocity(phi, v_n, h, epsilon):
    """The floor a contact's normal velocity is held at by the end of the step (module doc)."""
    if phi >= epsilon:
        return -phi / h
    return max(min(v_n, 0.0), -max(phi, 0.0) / h)


@kernel
def closest_terrain(model, x, i, u0, u1, u2, h, in_reach):
    """The terrain that particle i, moving at (u0, u1, u2), reaches first this step, with phi, the
    normal and the normal velocity; terrain -1 if it reaches none.

    With ``in_reach``, reaching means phi < epsilon or phi + h u_n < epsilon (contacts at the
    start of a step); without, it means ending the step inside (phi + h u_n < 0).
    """
    kinds, points, normals = model.terrain_kind, model.terrain_point, model.terrain_normal
    radii, epsilon = model.terrain_radius, model.terrain_epsilon
    best, best_phi, best_u_n, earliest = -1, 0.0, 0.0, np.inf
    nx = ny = nz = 0.0
    for t in range(kinds.shape[0]):
        phi, mx, my, mz = terrain_distance(kinds[t], points[t], normals[t], radii[t],
                                           x[i, 0], x[i, 1], x[i, 2], model.radius[i])
        u_n = u0 * mx + u1 * my + u2 * mz
        reached = phi + h * u_n   # distance at the end of the step
        if in_reach:
            touching = phi < epsilon[t] or reached < epsilon[t]
        else:
            touching = reached < 0.0
        if touching and reached < earliest:
            best, best_phi, best_u_n, earliest = t, phi, u_n, reached
            nx, ny, nz = mx, my, mz
    return best, best_phi, nx, ny, nz, best_u_n


@kernel
def find_constraints(model, x, v, h, kind, normal, terrain, normal_floor, friction):
    """Classify every particle at the start of a step: PINNED, FREE, or a STUCK contact (the
    first solve tells which contacts slide). Sets each contact's terrain, normal and floor."""
    for i in range(x.shape[0]):
        kind[i] = FREE
        terrain[i] = -1
        friction[i, 0] = friction[i, 1] = friction[i, 2] = 0.0
        if model.inv_mass[i] == 0.0:
            kind[i] = PINNED
            continue
        t, phi, nx, ny, nz, v_n = closest_terrain(model, x, i, v[i, 0], v[i, 1], v[i, 2], h,
                                                  True)
        if t >= 0:
            kind[i] = STUCK
            terrain[i] = t
            normal[i, 0], normal[i, 1], normal[i, 2] = nx, ny, nz
            normal_floor[i] = lowest_normal_velocity(phi, v_n, h, model.terrain_epsilon[t])


@kernel
def hold_constrained(i, kind, normal, normal_floor, v, dv, ddv):
    """Set the components of ddv that particle i's constraint fixes, so that v + dv + ddv
    meets it: all three at rest for PINNED (v = 0), on the floor with no tangential velocity
    for STUCK, on the floor for SLIDING. Free components are left as they are."""
    if kind[i] == FREE:
        return
    if kind[i] == PINNED:
        ddv[i, 0] = ddv[i, 1] = ddv[i, 2] = 0.0
        return
    nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
    u0, u1, u2 = v[i, 0] + dv[i, 0], v[i, 1] + dv[i, 1], v[i, 2] + dv[i, 2]
    if kind[i] == STUCK:
        ddv[i, 0] = normal_floor[i] * nx - u0
        ddv[i, 1] = normal_floor[i] * ny - u1
        ddv[i, 2] = normal_floor[i] * nz - u2
        return
    gap = normal_floor[i] - (u0 + ddv[i, 0]) * nx - (u1 + ddv[i, 1]) * ny - (u2 + ddv[i, 2]) * nz
    ddv[i, 0] += gap * nx
    ddv[i, 1] += gap * ny
    ddv[i, 2] += gap * nz


@kernel
def filter_constrained(kind, normal, u):
    """u = S u: remove the normal component of sliding contacts, everything of stuck or pinned
    particles."""
    for i in range(u.shape[0]):
        if kind[i] == FREE:
            continue
        if kind[i] != SLIDING:
            u[i, 0] = u[i, 1] = u[i, 2] = 0.0
            continue
        u_n = u[i, 0] * normal[i, 0] + u[i, 1] * normal[i, 1] + u[i, 2] * normal[i, 2]
        for c in range(3):
            u[i, c] -= u_n * normal[i, c]


@kernel
def update_contacts(model, x, v, dv, ddv, h, kind, normal, terrain, normal_floor, friction,
                    reaction):
    """One active-set pass (module doc), given the reaction impulses R = A ddv - b of the last
    solve. Adjusts ddv to every changed constraint; returns how many changed."""
    changed = 0
    for i in range(x.shape[0]):
        if kind[i] == PINNED:
            continue
        if kind[i] == FREE:
            t, phi, nx, ny, nz, _ = closest_terrain(model, x, i, v[i, 0] + dv[i, 0] + ddv[i, 0],
                                                    v[i, 1] + dv[i, 1] + ddv[i, 1],
                                                    v[i, 2] + dv[i, 2] + ddv[i, 2], h, False)
            if t >= 0:
                kind[i] = STUCK
                terrain[i] = t
                normal[i, 0], normal[i, 1], normal[i, 2] = nx, ny, nz
                v_n = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
                normal_floor[i] = lowest_normal_velocity(phi, v_n, h,
                                                         model.terrain_epsilon[t])
                hold_constrained(i, kind, normal, normal_floor, v, dv, ddv)
                changed += 1
            continue
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        r_n = reaction[i, 0] * nx + reaction[i, 1] * ny + reaction[i, 2] * nz
        if r_n < 0.0:
            kind[i] = FREE   # the terrain would have to pull
            friction[i, 0] = friction[i, 1] = friction[i, 2] = 0.0
            changed += 1
            continue
        limit = model.terrain_friction[terrain[i]] * r_n
        if kind[i] == STUCK:
            tx, ty, tz = reaction[i, 0] - r_n * nx, reaction[i, 1] - r_n * ny, reaction[i, 2] - r_n * nz
            holding = math.sqrt(tx * tx + ty * ty + tz * tz)
            if holding > limit * (1.0 + STICKING_TOLERANCE):
                kind[i] = SLIDING   # friction at the edge of the cone, the way it pulled
                scale = limit / holding
                friction[i, 0], friction[i, 1], friction[i, 2] = scale * tx, scale * ty, scale * tz
                changed += 1
            continue
        # sliding: kinetic friction against the tangential velocity just solved for
        u0, u1, u2 = v[i, 0] + dv[i, 0] + ddv[i, 0], v[i, 1] + dv[i, 1] + ddv[i, 1], \
            v[i, 2] + dv[i, 2] + ddv[i, 2]
        u_n = u0 * nx + u1 * ny + u2 * nz
        tx, ty, tz = u0 - u_n * nx, u1 - u_n * ny, u2 - u_n * nz
        if tx * friction[i, 0] + ty * friction[i, 1] + tz * friction[i, 2] > 0.0:
            kind[i] = STUCK   # friction turned the motion around: it would have stopped
            friction[i, 0] = friction[i, 1] = friction[i, 2] = 0.0
            hold_constrained(i, kind, normal, normal_floor, v, dv, ddv)
            changed += 1
            continue
        speed = math.sqrt(tx * tx + ty * ty + tz * tz)
        if speed == 0.0:
            continue
        fx, fy, fz = -limit * tx / speed, -limit * ty / speed, -limit * tz / speed
        shift = math.sqrt((fx - friction[i, 0]) ** 2 + (fy - friction[i, 1]) ** 2
                          + (fz - friction[i, 2]) ** 2)
        if shift > 1e-3 * limit:
            changed += 1
        friction[i, 0], friction[i, 1], friction[i, 2] = fx, fy, fz
    return changed
