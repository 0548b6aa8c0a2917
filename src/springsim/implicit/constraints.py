"""Pinned particles and terrain contact as constraints on the velocity change of a step.

Baraff and Witkin (1998, section 5) enforce constraints inside the linear solve: a filter
S_i = I (free), I - n n^T (contact, normal n) or 0 (pinned) removes the constrained components
from every conjugate-gradient direction, so the solve keeps them at the value they start with.

Contact, as in contact.py but at the level of a whole implicit step:
- A particle is in contact with a terrain when it is in the contact band (phi < epsilon) or will
  be by the end of the step at its current velocity (phi + h v_n < epsilon). The second case is
  what keeps large steps honest: a particle falling 0.4 m per step would otherwise be driven deep
  into the terrain by the solve and then lifted out alone, crushing the lattice above it.
- Its normal velocity change is fixed at dv_n = max(0, -phi/h - v_n): zero when the particle
  would stay out of the terrain anyway (the terrain only cancels forces that push into it, as in
  contact.py), and otherwise just enough for it to end the step on the surface. The solve
  therefore never moves a particle into a terrain.
- The terrain can push, not pull, and nothing may go through it: after each solve, contacts
  whose normal reaction impulse lambda_n = ((A dv - b) . n) is negative (the springs pull the
  particle away harder than the constraint allows) are released, free particles that the solved
  velocities would carry into a terrain become contacts, and the system is solved again (an
  active set; a few passes at most).
- Coulomb friction then takes at most ``friction * lambda_n`` of tangential momentum: a particle
  whose sliding that can stop sticks (static friction), any other slides on with kinetic friction.
- Restitution is left to the impact pass every integrator runs after its step
  (``_steps.finish_step``), which reflects whatever normal velocity still approaches a terrain.
One terrain per particle: the one it reaches first. A particle touching two terrains at once has
the second handled by the impact pass alone.
"""
import math

import numpy as np

from .._jit import kernel
from ..contact import terrain_distance

FREE, CONTACT, PINNED = 0, 1, 2


@kernel
def find_constraints(model, x, v, h, kind, normal, terrain, normal_change):
    """Classify every particle (FREE, CONTACT, PINNED); for contacts set the terrain, its normal
    and the normal velocity change the step must make (see module doc)."""
    kinds, points, normals = model.terrain_kind, model.terrain_point, model.terrain_normal
    radii, epsilon = model.terrain_radius, model.terrain_epsilon
    for i in range(x.shape[0]):
        kind[i] = FREE
        terrain[i] = -1
        normal_change[i] = 0.0
        if model.inv_mass[i] == 0.0:
            kind[i] = PINNED
            continue
        earliest = np.inf
        for t in range(kinds.shape[0]):
            phi, nx, ny, nz = terrain_distance(kinds[t], points[t], normals[t], radii[t],
                                               x[i, 0], x[i, 1], x[i, 2], model.radius[i])
            v_n = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
            reached = phi + h * v_n   # distance at the end of the step, at the current velocity
            if phi >= epsilon[t] and reached >= epsilon[t]:
                continue
            if reached < earliest:
                earliest = reached
                kind[i] = CONTACT
                terrain[i] = t
                normal[i, 0], normal[i, 1], normal[i, 2] = nx, ny, nz
                normal_change[i] = max(0.0, -max(phi, 0.0) / h - v_n)


@kernel
def add_penetrating_contacts(model, x, v, dv, ddv, h, kind, normal, terrain, normal_change):
    """Make a contact of every free particle that the velocity change dv + ddv just solved for
    would carry into a terrain (phi + h v'_n < 0), with the normal velocity change it needs
    (the same rule as find_constraints), and correct ddv to make it. Returns how many."""
    kinds, points, normals = model.terrain_kind, model.terrain_point, model.terrain_normal
    radii = model.terrain_radius
    added = 0
    for i in range(x.shape[0]):
        if kind[i] != FREE:
            continue
        for t in range(kinds.shape[0]):
            phi, nx, ny, nz = terrain_distance(kinds[t], points[t], normals[t], radii[t],
                                               x[i, 0], x[i, 1], x[i, 2], model.radius[i])
            v_n = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
            dv_n = ((dv[i, 0] + ddv[i, 0]) * nx + (dv[i, 1] + ddv[i, 1]) * ny
                    + (dv[i, 2] + ddv[i, 2]) * nz)
            if phi + h * (v_n + dv_n) >= 0.0:
                continue
            kind[i] = CONTACT
            terrain[i] = t
            normal[i, 0], normal[i, 1], normal[i, 2] = nx, ny, nz
            normal_change[i] = max(0.0, -max(phi, 0.0) / h - v_n)
            correction = normal_change[i] - dv_n
            ddv[i, 0] += correction * nx
            ddv[i, 1] += correction * ny
            ddv[i, 2] += correction * nz
            added += 1
            break
    return added


@kernel
def filter_constrained(kind, normal, u):
    """u = S u: remove the normal component at contacts and everything at pinned particles."""
    for i in range(u.shape[0]):
        if kind[i] == FREE:
            continue
        if kind[i] == PINNED:
            u[i, 0] = u[i, 1] = u[i, 2] = 0.0
            continue
        u_n = u[i, 0] * normal[i, 0] + u[i, 1] * normal[i, 1] + u[i, 2] * normal[i, 2]
        for c in range(3):
            u[i, c] -= u_n * normal[i, c]


@kernel
def normal_reactions(kind, normal, product, rhs, reaction):
    """reaction_i = ((A dv - b)_i . n_i): the terrain's normal impulse (N s) on every contact,
    given ``product`` = A dv; zero for the rest."""
    for i in range(rhs.shape[0]):
        reaction[i] = 0.0
        if kind[i] == CONTACT:
            reaction[i] = ((product[i, 0] - rhs[i, 0]) * normal[i, 0]
                           + (product[i, 1] - rhs[i, 1]) * normal[i, 1]
                           + (product[i, 2] - rhs[i, 2]) * normal[i, 2])


@kernel
def release_pulling_contacts(kind, reaction):
    """Free the contacts whose terrain would have to pull; return how many there were."""
    released = 0
    for i in range(kind.shape[0]):
        if kind[i] == CONTACT and reaction[i] < 0.0:
            kind[i] = FREE
            released += 1
    return released


@kernel
def apply_friction(model, kind, normal, terrain, reaction, v):
    """Coulomb friction on the new velocities: remove at most friction * lambda_n / m of each
    contact's tangential velocity (all of it when that suffices: the particle sticks)."""
    for i in range(v.shape[0]):
        if kind[i] != CONTACT or not reaction[i] > 0.0:
            continue
        nx, ny, nz = normal[i, 0], normal[i, 1], normal[i, 2]
        v_n = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
        tx, ty, tz = v[i, 0] - v_n * nx, v[i, 1] - v_n * ny, v[i, 2] - v_n * nz
        sliding = math.sqrt(tx * tx + ty * ty + tz * tz)
        stoppable = model.terrain_friction[terrain[i]] * reaction[i] * model.inv_mass[i]
        keep = 0.0 if sliding <= stoppable else 1.0 - stoppable / sliding
        v[i, 0] = v_n * nx + keep * tx
        v[i, 1] = v_n * ny + keep * ty
        v[i, 2] = v_n * nz + keep * tz
