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

A particle of a sheet (a cloth: model.sheet_triangles) is touched through its triangles, not as
a point: every triangle with a corner within that reach (grown by the longest triangle edge) is
a candidate, and its contact point b is the point of the triangle closest to the ball's centre,
x_b = sum_k w_k x_k (barycentric weights w_k, found at the linearization's positions). Why: a
ball about the size of the cloth's spacing that lands between four particles touches them at
their sides; point contacts then push them apart instead of holding the ball up, and it went
through the cloth at every step from 1/60 to 1/20 s (68 of 81 drops of
benchmarks/ball_through_cloth.py, 0 with triangles). A point is a triangle with weights (1, 0, 0).

For a candidate, with d = x_a - x_b at the positions the solve linearizes about (the Newton
estimate x + h (v + dv), the prediction x + h v in the first iteration), n = d / |d| (the normal
at the start of the step instead if the prediction has the point past the ball's centre), and
R = r_a + r_b, the end-of-step gap is, to first order in the solve's velocity change ddv,
    phi = g + h n . (ddv_a - ddv_b),     g = n . d - R,   ddv_b = sum_k w_k ddv_k,
and the contact force on a is the one-sided spring -k min(0, phi) n (b gets the opposite, shared
as w_k of it by each corner). Its stiffness k = STIFFNESS m_eff / h^2, m_eff =
1 / (w_a + sum_k w_k^2 w_(b_k)) the pair's reduced mass along n (w_i the inverse masses), so that
a pair alone ends the step with phi = g / (1 + STIFFNESS): backward Euler stays stable for any k,
and this scaling keeps the contact as stiff, relative to the masses, at every h. A pair whose
contact is active adds J^T (h^2 k) J, J = n^T (e_a - sum_k w_k e_(b_k)):
    to the matrix    h^2 k n n^T = STIFFNESS m_eff n n^T   on (a, a), times w_j w_k on
                     (b_j, b_k), times -w_k on (a, b_k) and (b_k, a),
    to the right side  -h k g n  on a, +w_k h k g n on b_k.
The geometric part of the spring's stiffness (across n) is dropped, as for compressed springs
(jacobian.py): it would make the matrix indefinite. Since the block pattern is fixed when the
model is built, none of this is assembled: ``add_contact_product`` adds it to every matrix-vector
product of the solve (cg.py) and ``add_contact_blocks`` to the block-Jacobi preconditioner.

Which contacts are active is an active set, updated between solves together with the terrain
contacts (implicit_euler.solve_with_contacts): a pair starts active if g < 0; after a solve an
active pair with phi > 0 (the spring would pull) is released and an inactive one with phi < 0
becomes active, and the system is solved again (a few passes at most).

Every term acts on the ball and on its contact point with opposite signs (the weights sum to
one), so the contacts conserve momentum like the springs do: the ball feels the reaction of every point it pushes. The impulse
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
from ..geometry import closest_on_triangle

STIFFNESS = 100.0    # h^2 k / m_eff: a pair alone keeps 1/101 of its predicted penetration
REACH_SLACK = 0.1    # share of the ball's radius added to the candidates' search reach


@kernel
def no_ball_contacts():
    """An empty contact set."""
    return candidate_contacts(np.empty((0, 2), np.int64), np.empty((0, 2), np.int64),
                              np.empty((0, 3), np.int64))


@kernel
def candidate_contacts(points, faces, triangles):
    """A contact set (nodes, weights, normal, gap g, coefficient h^2 k, active, on a triangle)
    for the given (ball, point) and (ball, triangle row) pairs, all inactive. Each contact acts
    between ball nodes[p, 0] and the point sum_k weights[p, k] x[nodes[p, 1 + k]]: a point is a
    triangle with weights (1, 0, 0)."""
    count = points.shape[0] + faces.shape[0]
    nodes = np.empty((count, 4), np.int64)
    weights = np.zeros((count, 3))
    on_triangle = np.zeros(count, np.bool_)
    for p in range(points.shape[0]):
        nodes[p, 0] = points[p, 0]
        nodes[p, 1] = nodes[p, 2] = nodes[p, 3] = points[p, 1]
        weights[p, 0] = 1.0
    for f in range(faces.shape[0]):
        p = points.shape[0] + f
        nodes[p, 0] = faces[f, 0]
        for k in range(3):
            nodes[p, 1 + k] = triangles[faces[f, 1], k]
        on_triangle[p] = True
    return (nodes, weights, np.zeros((count, 3)), np.zeros(count), np.zeros(count),
            np.zeros(count, np.bool_), on_triangle)


@kernel
def find_ball_contacts(model, x, v, h):
    """The contact set of a step: every (ball, point) and (ball, sheet triangle) pair the step
    can bring into contact (module doc), all inactive until ``linearize_ball_contacts``. A
    particle of a sheet is touched through its triangles, not as a point."""
    balls = model.balls
    if balls.shape[0] == 0:
        return no_ball_contacts()
    count = x.shape[0]
    fastest = 0.0
    for i in range(count):
        if model.ball_slot[i] < 0 and model.inv_mass[i] > 0.0:
            fastest = max(fastest, math.sqrt(v[i, 0] ** 2 + v[i, 1] ** 2 + v[i, 2] ** 2))
    predicted = np.empty_like(x)
    for i in range(count):
        for c in range(3):
            predicted[i, c] = x[i, c] + h * v[i, c]
    longest_edge = 0.0   # a triangle can touch the ball with its corners this much farther
    triangles = model.sheet_triangles
    for t in range(triangles.shape[0]):
        for k in range(3):
            a, b = triangles[t, k], triangles[t, (k + 1) % 3]
            longest_edge = max(longest_edge, math.sqrt((predicted[a, 0] - predicted[b, 0]) ** 2
                                                       + (predicted[a, 1] - predicted[b, 1]) ** 2
                                                       + (predicted[a, 2] - predicted[b, 2]) ** 2))
    reach = model.radius.copy()
    for a in balls:
        speed = math.sqrt(v[a, 0] ** 2 + v[a, 1] ** 2 + v[a, 2] ** 2)
        reach[a] += h * (speed + fastest) + REACH_SLACK * model.radius[a] + longest_edge
    found = find_contacts(predicted, reach, balls, model.ball_slot)
    start = model.triangle_start
    points = np.empty((found.shape[0], 2), np.int64)
    keys = np.empty(found.shape[0] * max(1, int(np.max(start[1:] - start[:-1]))), np.int64)
    n_points = n_keys = 0
    for k in range(found.shape[0]):
        a, b = found[k, 0], found[k, 1]
        if model.ball_slot[b] >= 0:
            continue   # ball-ball pairs are collisions.py's
        if start[b + 1] == start[b]:
            if distance_squared(predicted, a, b) < (reach[a] - longest_edge) ** 2:
                points[n_points, 0], points[n_points, 1] = a, b
                n_points += 1
            continue
        for j in range(start[b], start[b + 1]):
            keys[n_keys] = model.ball_slot[a] * triangles.shape[0] + model.particle_triangles[j]
            n_keys += 1
    keys = np.unique(keys[:n_keys])
    faces = np.empty((keys.shape[0], 2), np.int64)
    for k in range(keys.shape[0]):
        faces[k, 0] = balls[keys[k] // triangles.shape[0]]
        faces[k, 1] = keys[k] % triangles.shape[0]
    return candidate_contacts(points[:n_points], faces, triangles)


@kernel
def distance_squared(x, a, b):
    return (x[a, 0] - x[b, 0]) ** 2 + (x[a, 1] - x[b, 1]) ** 2 + (x[a, 2] - x[b, 2]) ** 2


@kernel
def linearize_ball_contacts(model, contacts, x, v, dv, h, rhs):
    """Weights, normals, gaps and coefficients about the estimate x + h (v + dv); activate the
    pairs with g < 0 and add their right-hand side (module doc)."""
    nodes, weights, normal, gap, coefficient, active, on_triangle = contacts
    corners = np.empty((3, 3))
    centre, d, start = np.empty(3), np.empty(3), np.empty(3)
    for p in range(nodes.shape[0]):
        a = nodes[p, 0]
        for c in range(3):
            centre[c] = x[a, c] + h * (v[a, c] + dv[a, c])
            for k in range(3):
                b = nodes[p, 1 + k]
                corners[k, c] = x[b, c] + h * (v[b, c] + dv[b, c])
        if on_triangle[p]:
            weights[p, 0], weights[p, 1], weights[p, 2] = closest_on_triangle(centre, corners)
        inverse_mass = model.inv_mass[a]
        for c in range(3):
            d[c] = centre[c]
            start[c] = x[a, c]
        for k in range(3):
            b, w = nodes[p, 1 + k], weights[p, k]
            inverse_mass += w * w * model.inv_mass[b]
            for c in range(3):
                d[c] -= w * corners[k, c]
                start[c] -= w * x[b, c]
        direction = d
        if d[0] * start[0] + d[1] * start[1] + d[2] * start[2] <= 0.0:
            direction = start   # the prediction passed the centre (or one of them is zero)
        length = math.sqrt(direction[0] ** 2 + direction[1] ** 2 + direction[2] ** 2)
        if length > 0.0:
            n0, n1, n2 = direction[0] / length, direction[1] / length, direction[2] / length
        else:
            n0, n1, n2 = 0.0, 1.0, 0.0   # concentric: choose up, as collisions.py does
        normal[p, 0], normal[p, 1], normal[p, 2] = n0, n1, n2
        gap[p] = n0 * d[0] + n1 * d[1] + n2 * d[2] - model.radius[a] - model.radius[nodes[p, 1]]
        coefficient[p] = STIFFNESS / inverse_mass
        active[p] = False
        if gap[p] < 0.0:
            set_active(contacts, p, True, h, rhs)


@kernel
def set_active(contacts, p, value, h, rhs):
    """Make pair p active or not, adding or removing its right-hand side -h k g n on the ball
    (and +h k g n, shared by the weights, on the point or triangle)."""
    nodes, weights, normal, gap, coefficient, active, on_triangle = contacts
    if active[p] == value:
        return
    active[p] = value
    impulse = -coefficient[p] * gap[p] / h   # h k (-g), with h^2 k = coefficient
    if not value:
        impulse = -impulse
    a = nodes[p, 0]
    for c in range(3):
        rhs[a, c] += impulse * normal[p, c]
        for k in range(3):
            rhs[nodes[p, 1 + k], c] -= weights[p, k] * impulse * normal[p, c]


@kernel
def relative_normal(contacts, p, u):
    """n . (u_a - sum_k w_k u_k): the pair's normal component of u, ball against point."""
    nodes, weights, normal = contacts[0], contacts[1], contacts[2]
    total = 0.0
    a = nodes[p, 0]
    for c in range(3):
        along = u[a, c]
        for k in range(3):
            along -= weights[p, k] * u[nodes[p, 1 + k], c]
        total += normal[p, c] * along
    return total


@kernel
def end_gap(contacts, p, h, ddv):
    """phi = g + h n . (ddv_a - ddv_b): the pair's gap at the end of the step, to first order."""
    return contacts[3][p] + h * relative_normal(contacts, p, ddv)


@kernel
def update_ball_contacts(contacts, h, ddv, rhs):
    """One active-set pass after a solve (module doc); returns how many pairs changed."""
    active = contacts[5]
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
    """out += A_c u: each active pair adds h^2 k n n^T (u_a - u_b) to a and subtracts it from b
    (b the point sum_k w_k x_k: shared by the weights)."""
    nodes, weights, normal, gap, coefficient, active, on_triangle = contacts
    for p in range(nodes.shape[0]):
        if not active[p]:
            continue
        along = coefficient[p] * relative_normal(contacts, p, u)
        a = nodes[p, 0]
        for c in range(3):
            out[a, c] += along * normal[p, c]
            for k in range(3):
                out[nodes[p, 1 + k], c] -= weights[p, k] * along * normal[p, c]


@kernel
def add_contact_blocks(contacts, diagonal):
    """diagonal[i] += the diagonal blocks of A_c: h^2 k n n^T on the ball, times w_k^2 on each
    corner of the point."""
    nodes, weights, normal, gap, coefficient, active, on_triangle = contacts
    for p in range(nodes.shape[0]):
        if not active[p]:
            continue
        for r in range(3):
            for c in range(3):
                value = coefficient[p] * normal[p, r] * normal[p, c]
                diagonal[nodes[p, 0], r, c] += value
                for k in range(3):
                    diagonal[nodes[p, 1 + k], r, c] += weights[p, k] ** 2 * value


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
    nodes = contacts[0]
    most = 0.0
    for k in range(nodes.shape[0]):
        a = nodes[k, 0]
        for j in range(1, 4):   # every corner of a triangle: its weights are not known yet
            b = nodes[k, j]
            relative = math.sqrt((v[a, 0] - v[b, 0]) ** 2 + (v[a, 1] - v[b, 1]) ** 2
                                 + (v[a, 2] - v[b, 2]) ** 2)
            most = max(most, h * relative / model.radius[a])
    if most <= SLOW_CONTACT:
        return requested
    return max(requested, int(math.ceil(SOLVES_PER_RADIUS * most)))
