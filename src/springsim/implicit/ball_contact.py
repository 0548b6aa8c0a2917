"""Ball-particle contact inside the backward-Euler solve: stiff one-sided penalty springs.

Why: collisions.py resolves ball-particle contact after the step (an impulse with restitution
and a position correction of 0.15 of the penetration). The solve alone knows nothing of the ball,
so at large steps it pulls the cloth particles into the ball faster than the correction pushes
them out, and a dropped or thrown ball ends up under the cloth. Here the contacts are forces of
the backward-Euler system, so the springs of the cloth and the ball feel them in the same step.

Each step, every (ball a, point b) pair that the step could bring into contact is a candidate:
the broad phase (``broadphase.find_contacts``) run on the predicted positions x + h (v + dv),
with each ball's radius grown by the distance the step can close, h (|v_a| + the fastest point's
speed), plus REACH_SLACK of its radius. Ball-ball pairs are left to collisions.py (they bounce).

For a candidate, with d = x_a - x_b at the positions the solve linearizes about (the Newton
estimate x + h (v + dv), the prediction x + h v in the first iteration), n = d / |d| (the normal
at the start of the step instead if the prediction has the point past the ball's centre), and
R = r_a + r_b, the end-of-step gap is, to first order in the solve's velocity change ddv,
    phi = g + h n . (ddv_a - ddv_b),     g = n . d - R,
and the contact force on a is the one-sided spring -k min(0, phi) n (b gets the opposite). Its
stiffness k = STIFFNESS m_eff / h^2, m_eff = 1 / (w_a + w_b) the pair's reduced mass, so that a
pair alone ends the step with phi = g / (1 + STIFFNESS): backward Euler stays stable for any k,
and this scaling keeps the contact as stiff, relative to the masses, at every h. A pair whose
contact is active adds
    to the matrix    h^2 k n n^T = STIFFNESS m_eff n n^T   on (a, a) and (b, b), minus on (a, b)
                     and (b, a),
    to the right side  -h k g n  on a, +h k g n on b.
The geometric part of the spring's stiffness (across n) is dropped, as for compressed springs
(jacobian.py): it would make the matrix indefinite. Since the block pattern is fixed when the
model is built, none of this is assembled: ``add_contact_product`` adds it to every matrix-vector
product of the solve (cg.py) and ``add_contact_blocks`` to the block-Jacobi preconditioner.

Which contacts are active is an active set, updated between solves together with the terrain
contacts (implicit_euler.solve_with_contacts): a pair starts active if g < 0; after a solve an
active pair with phi > 0 (the spring would pull) is released and an inactive one with phi < 0
becomes active, and the system is solved again (a few passes at most).

Every term acts on both particles of its pair with opposite signs, so the contacts conserve
momentum like the springs do: the ball feels the reaction of every point it pushes. The impulse
pass of collisions.py still runs after the step, unchanged: it removes what approach speed the
penalty leaves and 0.15 of the small penetration, and applies restitution and friction to it
(the penalty itself is inelastic and frictionless, so restitution only reflects what is left:
see collisions.py).

Measured on cloth-balls with one ball dropped from 2.5 m or thrown down at 20 m/s (the
no-tunnelling test): the deepest cloth particle is 0.08 % / 0.16 % of the radius inside the ball at
h = 5 ms, 0.3 % / 0.6 % at 10 ms and 0.8 % / 1.5 % at 1/60 s, and the ball stays 0.43 m above the
cloth beneath it; without these contacts it ended below the cloth at every one of these steps.
"""
import math

import numpy as np

from .._jit import kernel
from ..broadphase import find_contacts

STIFFNESS = 100.0    # h^2 k / m_eff: a pair alone keeps 1/101 of its predicted penetration
REACH_SLACK = 0.1    # share of the ball's radius added to the candidates' search reach


@kernel
def no_ball_contacts():
    """An empty contact set."""
    return candidate_contacts(np.empty((0, 2), np.int64))


@kernel
def candidate_contacts(pairs):
    """A contact set (pairs, normal, gap g, coefficient h^2 k, active) for the given pairs, all
    inactive."""
    count = pairs.shape[0]
    return (pairs, np.zeros((count, 3)), np.zeros(count), np.zeros(count),
            np.zeros(count, np.bool_))


@kernel
def find_ball_contacts(model, x, v, h):
    """The contact set of a step: every (ball, point) pair the step can bring into contact
    (module doc), all inactive until ``linearize_ball_contacts``."""
    balls = model.balls
    if balls.shape[0] == 0:
        return candidate_contacts(np.empty((0, 2), np.int64))
    count = x.shape[0]
    fastest = 0.0
    for i in range(count):
        if model.ball_slot[i] < 0 and model.inv_mass[i] > 0.0:
            fastest = max(fastest, math.sqrt(v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2))
    predicted = np.empty_like(x)
    for i in range(count):
        for c in range(3):
            predicted[i, c] = x[i, c] + h * v[i, c]
    reach = model.radius.copy()
    for a in balls:
        speed = math.sqrt(v[a, 0] ** 2 + v[a, 1] ** 2 + v[a, 2] ** 2)
        reach[a] += h * (speed + fastest) + REACH_SLACK * model.radius[a]
    found = find_contacts(predicted, reach, balls, model.ball_slot)
    kept = 0
    for k in range(found.shape[0]):
        if model.ball_slot[found[k, 1]] < 0:   # ball-ball pairs are collisions.py's
            kept += 1
    pairs = np.empty((kept, 2), np.int64)
    kept = 0
    for k in range(found.shape[0]):
        if model.ball_slot[found[k, 1]] < 0:
            pairs[kept, 0], pairs[kept, 1] = found[k, 0], found[k, 1]
            kept += 1
    return candidate_contacts(pairs)


@kernel
def linearize_ball_contacts(model, contacts, x, v, dv, h, rhs):
    """Normals, gaps and coefficients about the estimate x + h (v + dv); activate the pairs with
    g < 0 and add their right-hand side (module doc)."""
    pairs, normal, gap, coefficient, active = contacts
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        d = np.empty(3)
        start = np.empty(3)
        for c in range(3):
            start[c] = x[a, c] - x[b, c]
            d[c] = start[c] + h * (v[a, c] + dv[a, c] - v[b, c] - dv[b, c])
        direction = d
        if d[0] * start[0] + d[1] * start[1] + d[2] * start[2] <= 0.0:
            direction = start   # the prediction passed the centre (or one of them is zero)
        length = math.sqrt(direction[0] ** 2 + direction[1] ** 2 + direction[2] ** 2)
        if length > 0.0:
            n0, n1, n2 = direction[0] / length, direction[1] / length, direction[2] / length
        else:
            n0, n1, n2 = 0.0, 1.0, 0.0   # concentric: choose up, as collisions.py does
        normal[p, 0], normal[p, 1], normal[p, 2] = n0, n1, n2
        gap[p] = n0 * d[0] + n1 * d[1] + n2 * d[2] - model.radius[a] - model.radius[b]
        coefficient[p] = STIFFNESS / (model.inv_mass[a] + model.inv_mass[b])
        active[p] = False
        if gap[p] < 0.0:
            set_active(contacts, p, True, h, rhs)


@kernel
def set_active(contacts, p, value, h, rhs):
    """Make pair p active or not, adding or removing its right-hand side -h k g n on a (+ on b)."""
    pairs, normal, gap, coefficient, active = contacts
    if active[p] == value:
        return
    active[p] = value
    impulse = -coefficient[p] * gap[p] / h   # h k (-g), with h^2 k = coefficient
    if not value:
        impulse = -impulse
    a, b = pairs[p, 0], pairs[p, 1]
    for c in range(3):
        rhs[a, c] += impulse * normal[p, c]
        rhs[b, c] -= impulse * normal[p, c]


@kernel
def end_gap(contacts, p, h, ddv):
    """phi = g + h n . (ddv_a - ddv_b): the pair's gap at the end of the step, to first order."""
    pairs, normal, gap, coefficient, active = contacts
    a, b = pairs[p, 0], pairs[p, 1]
    closing = 0.0
    for c in range(3):
        closing += normal[p, c] * (ddv[a, c] - ddv[b, c])
    return gap[p] + h * closing


@kernel
def update_ball_contacts(contacts, h, ddv, rhs):
    """One active-set pass after a solve (module doc); returns how many pairs changed."""
    active = contacts[4]
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
    """out += A_c u: each active pair adds h^2 k n n^T (u_a - u_b) to a and subtracts it from b."""
    pairs, normal, gap, coefficient, active = contacts
    for p in range(pairs.shape[0]):
        if not active[p]:
            continue
        a, b = pairs[p, 0], pairs[p, 1]
        along = coefficient[p] * (normal[p, 0] * (u[a, 0] - u[b, 0])
                                  + normal[p, 1] * (u[a, 1] - u[b, 1])
                                  + normal[p, 2] * (u[a, 2] - u[b, 2]))
        for c in range(3):
            out[a, c] += along * normal[p, c]
            out[b, c] -= along * normal[p, c]


@kernel
def add_contact_blocks(contacts, diagonal):
    """diagonal[i] += the diagonal blocks of A_c: h^2 k n n^T on both particles of active
    pairs."""
    pairs, normal, gap, coefficient, active = contacts
    for p in range(pairs.shape[0]):
        if not active[p]:
            continue
        a, b = pairs[p, 0], pairs[p, 1]
        for r in range(3):
            for c in range(3):
                value = coefficient[p] * normal[p, r] * normal[p, c]
                diagonal[a, r, c] += value
                diagonal[b, r, c] += value


# How many linearized solves a step takes per radius a ball moves against a point it may touch.
# Measured on cloth-balls with a 20 m/s ball: at 1/30 s (1.3 radii per step) 3 solves hold it and 1
# does not; at 0.05 s (2 radii) 8 do and 5 do not.
SOLVES_PER_RADIUS = 4.0
SLOW_CONTACT = 0.5   # below half a radius per step one solve holds the ball (tests up to 1/60 s)


@kernel
def newton_iterations_needed(model, contacts, v, h, requested):
    """``requested``, or more when a ball moves more than half its radius against a point it may
    touch within this step: the contact normal then turns during the step, and the one-sided
    springs, linearized once, let the ball through."""
    pairs = contacts[0]
    most = 0.0
    for k in range(pairs.shape[0]):
        a, b = pairs[k, 0], pairs[k, 1]
        relative = math.sqrt((v[a, 0] - v[b, 0]) ** 2 + (v[a, 1] - v[b, 1]) ** 2
                             + (v[a, 2] - v[b, 2]) ** 2)
        most = max(most, h * relative / model.radius[a])
    if most <= SLOW_CONTACT:
        return requested
    return max(requested, int(math.ceil(SOLVES_PER_RADIUS * most)))
