"""The solve's contacts as stiff one-sided penalty springs of backward Euler's system.

Why: the post-step pass (collision/pipeline.py) resolves contact after the step. The solve
alone knows nothing of it, so at large steps it pulls cloth particles into a ball faster than
the correction pushes them out, and a cube dropped onto another at 1/30 s sinks into it. Here
the contacts are forces of the backward-Euler system, so the springs on both sides feel them in
the same step.

With R the contact's rest distance (r_a + r_b for a ball, the mean of the two bodies' thickness
for surfaces), the end-of-step gap is, to first order in the solve's velocity change ddv,
    phi = g + h n . sum_i c_i ddv_i,     g = n . d - R,
and the contact force on particle i is the one-sided spring -c_i k min(0, phi) n. Its stiffness
k = STIFFNESS m_eff / h^2, m_eff = 1 / sum_i c_i^2 w_i the contact's reduced mass along n (w_i
the inverse masses), so that a contact alone ends the step with phi = g / (1 + STIFFNESS):
backward Euler stays stable for any k, and this scaling keeps the contact as stiff, relative to
the masses, at every h. An active contact adds J^T (h^2 k) J, J = n^T sum_i c_i e_i:
    to the matrix      c_i c_j h^2 k n n^T = c_i c_j STIFFNESS m_eff n n^T  on (i, j),
    to the right side  -c_i h k g n  on i.
The geometric part of the spring's stiffness (across n) is dropped, as for compressed springs
(implicit/jacobian.py): it would make the matrix indefinite. Since the block pattern is fixed
when the model is built, none of this is assembled: ``add_contact_product`` adds it to every
matrix-vector product of the solve (implicit/cg.py) and ``add_contact_blocks`` to the
block-Jacobi preconditioner.

Which contacts are active is an active set, updated between solves together with the terrain
contacts: a contact starts active if g < 0; after a solve an active one with phi > 0 (the spring
would pull) is released and an inactive one with phi < 0 becomes active, and the system is
solved again (a few passes at most).

Every term acts with weights c_i that sum to zero, so the contacts conserve momentum like the
springs do. The post-step pass still runs after the step: it removes what approach speed the
penalty leaves and part of the small penetration, and applies restitution and friction to it
(the penalty itself is inelastic and frictionless). A contact the penalty already holds at rest
gets next to no normal impulse there, so next to no friction: the surface contacts' friction is
applied when the solve is done, against the penalty's own push (solve_friction.py).
"""
import math

import numpy as np

from ..._jit import inline_kernel, kernel
from ..contact_sets import BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE
from ..narrow_phase.solve import stencil


STIFFNESS = 100.0    # h^2 k / m_eff: a pair alone keeps 1/101 of its predicted penetration


@kernel
def linearize_contacts(model, contacts, x, v, dv, h, rhs):
    """Weights, normals, gaps and coefficients about the estimate x + h (v + dv); activate the
    contacts with g < 0 and add their right-hand side (module doc)."""
    nodes, weights, normal, gap = contacts.nodes, contacts.weights, contacts.normal, contacts.gap
    coefficient, active, shape, rest = (contacts.coefficient, contacts.active, contacts.shape,
                                        contacts.rest)
    estimate, start = np.empty((4, 3)), np.empty((4, 3))
    for p in range(nodes.shape[0]):
        for i in range(4):
            j = nodes[p, i]
            for c in range(3):
                estimate[i, c] = x[j, c] + h * (v[j, c] + dv[j, c])
                start[i, c] = x[j, c]
        touching = stencil(shape[p], estimate, start, weights[p], normal[p])
        inverse_mass = 0.0
        for i in range(4):
            inverse_mass += weights[p, i] ** 2 * model.inv_mass[nodes[p, i]]
        active[p] = False
        if not (touching and inverse_mass > 0.0):
            gap[p], coefficient[p] = np.inf, 0.0   # never active
            continue
        gap[p] = along_normal(weights[p], normal[p], estimate) - rest[p]
        coefficient[p] = STIFFNESS / inverse_mass
        if gap[p] < 0.0:
            set_active(contacts, p, True, h, rhs)


@inline_kernel
def along_normal(c, n, positions):
    """n . sum_i c_i positions[i]."""
    total = 0.0
    for i in range(4):
        total += c[i] * (n[0] * positions[i, 0] + n[1] * positions[i, 1]
                         + n[2] * positions[i, 2])
    return total


@kernel
def set_active(contacts, p, value, h, rhs):
    """Make contact p active or not, adding or removing its right-hand side, -h k g n shared
    as c_i of it by its nodes."""
    nodes, weights, normal = contacts.nodes, contacts.weights, contacts.normal
    gap, coefficient, active = contacts.gap, contacts.coefficient, contacts.active
    if active[p] == value:
        return
    active[p] = value
    impulse = -coefficient[p] * gap[p] / h   # h k (-g), with h^2 k = coefficient
    if not value:
        impulse = -impulse
    for i in range(4):
        for c in range(3):
            rhs[nodes[p, i], c] += weights[p, i] * impulse * normal[p, c]


@kernel
def relative_normal(contacts, p, u):
    """n . sum_i c_i u_i: the contact's normal component of u (ball against point, point
    against triangle, edge against edge)."""
    nodes, weights, normal = contacts.nodes, contacts.weights, contacts.normal
    total = 0.0
    for c in range(3):
        along = 0.0
        for i in range(4):
            along += weights[p, i] * u[nodes[p, i], c]
        total += normal[p, c] * along
    return total


@kernel
def end_gap(contacts, p, h, ddv):
    """phi = g + h n . sum_i c_i ddv_i: the contact's gap at the end of the step, to first
    order."""
    return contacts.gap[p] + h * relative_normal(contacts, p, ddv)


@kernel
def update_active_contacts(contacts, h, ddv, rhs):
    """One active-set pass after a solve (module doc); returns how many contacts changed."""
    active = contacts.active
    changed = 0
    for p in range(active.shape[0]):
        phi = end_gap(contacts, p, h, ddv)
        if active[p] and phi > 0.0:
            set_active(contacts, p, False, h, rhs)
            changed += 1
        elif not active[p] and phi < 0.0:
            set_active(contacts, p, True, h, rhs)
            changed += 1
    return changed


@kernel
def add_contact_product(contacts, u, out):
    """out += A_c u: each active contact adds c_i h^2 k n n^T sum_j c_j u_j to node i."""
    nodes, weights, normal = contacts.nodes, contacts.weights, contacts.normal
    coefficient, active = contacts.coefficient, contacts.active
    for p in range(nodes.shape[0]):
        if not active[p]:
            continue
        along = coefficient[p] * relative_normal(contacts, p, u)
        for i in range(4):
            for c in range(3):
                out[nodes[p, i], c] += weights[p, i] * along * normal[p, c]


@kernel
def add_contact_blocks(contacts, diagonal):
    """diagonal[i] += the diagonal blocks of A_c: c_i^2 h^2 k n n^T on each node."""
    nodes, weights, normal = contacts.nodes, contacts.weights, contacts.normal
    coefficient, active = contacts.coefficient, contacts.active
    for p in range(nodes.shape[0]):
        if not active[p]:
            continue
        for r in range(3):
            for c in range(3):
                value = coefficient[p] * normal[p, r] * normal[p, c]
                for i in range(4):
                    diagonal[nodes[p, i], r, c] += weights[p, i] ** 2 * value


# How many linearized solves a step takes per radius a ball moves against a point it may touch:
# the fewest that hold a fast ball on the cloth at 1/30 and 1/20 s
# (tests/test_balls_on_cloth_surface.py)
SOLVES_PER_RADIUS = 4.0
SLOW_CONTACT = 0.5   # below half a radius per step one solve holds the ball (tests up to 1/60 s)


@kernel
def newton_iterations_needed(model, contacts, v, h, requested):
    """``requested``, or more when a ball moves more than half its radius against a point it may
    touch within this step: the contact normal then turns during the step, and the one-sided
    springs, linearized once, let the ball through; and at least IMPACT_SOLVES when a body
    closes fast on another's surface (``impact_solves``)."""
    nodes, shape, rest = contacts.nodes, contacts.shape, contacts.rest
    most = 0.0
    needed = requested
    for k in range(nodes.shape[0]):
        if shape[k] != BALL_POINT and shape[k] != BALL_TRIANGLE and shape[k] != BALL_SAMPLE:
            needed = max(needed, impact_solves(model, nodes, k, v, h, rest[k]))
            continue
        a = nodes[k, 0]
        for j in range(1, 4):   # every corner of a triangle: its weights are not known yet
            b = nodes[k, j]
            relative = math.sqrt((v[a, 0] - v[b, 0]) ** 2 + (v[a, 1] - v[b, 1]) ** 2
                                 + (v[a, 2] - v[b, 2]) ** 2)
            most = max(most, h * relative / model.radius[a])
    if most <= SLOW_CONTACT:
        return needed
    return max(needed, int(math.ceil(SOLVES_PER_RADIUS * most)))


# A body closing on another's surface by more than IMPACT_STRIDE rest distances in one step is
# linearized once per stride: linearized once, at x + h v, a cube thrown onto another farther
# than the particle spacing in one step is held with its points linearized against triangles
# they had already passed (tests/test_implicit_surface_contact.py throws it at 10 and 20 m/s).
IMPACT_STRIDE = 2.0
MOST_IMPACT_SOLVES = 10


@kernel
def impact_solves(model, nodes, k, v, h, rest):
    """The solves surface contact k asks for: 1, or one per IMPACT_STRIDE rest distances its
    two bodies close in the step (the first node against the last: the point and a corner, or
    the two edges; a body's own fold moves together and asks for 1)."""
    a, b = nodes[k, 0], nodes[k, 3]
    if model.particle_body[a] == model.particle_body[b]:
        return 1
    relative = math.sqrt((v[a, 0] - v[b, 0]) ** 2 + (v[a, 1] - v[b, 1]) ** 2
                         + (v[a, 2] - v[b, 2]) ** 2)
    strides = h * relative / (IMPACT_STRIDE * rest)
    if not strides > 1.0:
        return 1
    return min(MOST_IMPACT_SOLVES, int(math.ceil(strides)))
