"""Ball-particle and surface contact inside the backward-Euler solve: stiff one-sided penalty
springs.

Why: the post-step pass (surface_collisions.py) resolves ball-particle contact after the step
(an impulse with restitution and a position correction of 0.15 of the penetration). The solve
alone knows nothing of the ball, so at large steps it pulls the cloth particles into the ball
faster than the correction pushes them out, and a dropped or thrown ball ends up under the
cloth. Here the contacts are forces of the backward-Euler system, so the springs of the cloth
and the ball feel them in the same step.

Each step, every (ball a, point b) pair that the step could bring into contact is a candidate:
the broad phase (``broadphase.find_contacts``) run on the predicted positions x + h (v + dv),
with each ball's radius grown by the distance the step can close, h (|v_a| + the fastest point's
speed), plus REACH_SLACK of its radius. Ball-ball pairs are left to the post-step pass (they bounce).

A particle of a sheet (a cloth: model.sheet_triangles) is touched through its triangles, not as
a point: every triangle with a corner within that reach (grown by the longest triangle edge) is
a candidate, and its contact point b is the point of the triangle closest to the ball's centre,
x_b = sum_k w_k x_k (barycentric weights w_k, found at the linearization's positions). Why: a
ball about the size of the cloth's spacing that lands between four particles touches them at
their sides; point contacts then push them apart instead of holding the ball up, and it went
through the cloth at every step from 1/60 to 1/20 s (68 of 81 drops of
benchmarks/ball_through_cloth.py, 0 with triangles). A point is a triangle with weights (1, 0, 0).

Surface contacts (point-triangle and edge-edge pairs of two bodies, or of one self-colliding
body: surface_collisions.py) go into the same contact set for the same reason: a cube dropped
onto another at 1/30 s sank through it with the post-step pass alone. Pairs of two bodies are
found by surface_contact.find_surface_pairs; a body's own pairs come from the post-step
pass's list (own_contact.py says which and why).

Every contact is a stencil of four particles with signed weights c_i that sum to zero, and
d = sum_i c_i x_i runs from one side of the contact to the other:
    ball-point       c = (1, -1, 0, 0)            (a point is its own contact point)
    ball-triangle    c = (1, -w_0, -w_1, -w_2)    (w: barycentric weights of the triangle's point
    point-triangle   c = (1, -w_0, -w_1, -w_2)     closest to the ball's centre or the point)
    edge-edge        c = (1 - s, s, -(1 - t), -t)  (s, t: the edges' closest points)
found at the positions the solve linearizes about (the Newton estimate x + h (v + dv), the
prediction x + h v in the first iteration). The normal n is d / |d| there, or d at the start of
the step (same weights) if the step has carried one side past the other (d . d_start <= 0); a
surface point above a triangle's face takes the face's normal instead, on the side the point was
at the start, and one beside it d / |d| always (``stencil`` says why). Two edges closest at an end, or a surface point on its triangle's edge, touch
through the neighbouring contacts and are left inactive. With R the contact's rest distance
(r_a + r_b for a ball, the mean of the two bodies' thickness for surfaces), the end-of-step gap
is, to first order in the solve's velocity change ddv,
    phi = g + h n . sum_i c_i ddv_i,     g = n . d - R,
and the contact force on particle i is the one-sided spring -c_i k min(0, phi) n. Its stiffness
k = STIFFNESS m_eff / h^2, m_eff = 1 / sum_i c_i^2 w_i the contact's reduced mass along n (w_i
the inverse masses), so that a contact alone ends the step with phi = g / (1 + STIFFNESS):
backward Euler stays stable for any k, and this scaling keeps the contact as stiff, relative to
the masses, at every h. An active contact adds J^T (h^2 k) J, J = n^T sum_i c_i e_i:
    to the matrix      c_i c_j h^2 k n n^T = c_i c_j STIFFNESS m_eff n n^T  on (i, j),
    to the right side  -c_i h k g n  on i.
The geometric part of the spring's stiffness (across n) is dropped, as for compressed springs
(jacobian.py): it would make the matrix indefinite. Since the block pattern is fixed when the
model is built, none of this is assembled: ``add_contact_product`` adds it to every matrix-vector
product of the solve (cg.py) and ``add_contact_blocks`` to the block-Jacobi preconditioner.

Which contacts are active is an active set, updated between solves together with the terrain
contacts (implicit_euler.solve_with_contacts): a contact starts active if g < 0; after a solve an
active one with phi > 0 (the spring would pull) is released and an inactive one with phi < 0
becomes active, and the system is solved again (a few passes at most).

Every term acts with weights c_i that sum to zero, so the contacts conserve momentum like the
springs do: the ball feels the reaction of every point it pushes, a surface that of every
surface it pushes. The post-step impulse passes (surface_collisions.py) still run after the
step, unchanged: they remove what approach speed the penalty leaves and part of the small
penetration, and apply restitution and friction to it (the penalty itself is inelastic and
frictionless, so restitution only reflects what is left: see surface_collisions.py). A contact the
penalty already holds at rest gets next to no normal impulse there, so next to no friction: the
surface contacts' friction is applied when the solve is done, against the penalty's own push
(contact_friction.py).

Measured on cloth-balls with one ball dropped from 2.5 m or thrown down at 20 m/s (the
no-tunnelling test): the deepest cloth particle is 0.08 % / 0.16 % of the radius inside the ball at
h = 5 ms, 0.3 % / 0.6 % at 10 ms and 0.8 % / 1.5 % at 1/60 s, and the ball stays 0.43 m above the
cloth beneath it; without these contacts it ended below the cloth at every one of these steps.
Two 5 x 5 x 5 cubes (12.5 kg each): one resting on the other stays within a thickness of it for
3 s at 1/60 and 1/30 s, one thrown at 10 or 20 m/s onto the other or onto a cloth at 1/30 s does
not pass through (tests/test_implicit_surface_contact.py); with the post-step pass alone all of
these went through.
"""
import math

import numpy as np

from .._jit import inline_kernel, kernel
from ..broadphase import find_contacts
from ..geometry import closest_on_segments, closest_on_triangle, triangle_normal
from .surface_contact import find_surface_pairs

STIFFNESS = 100.0    # h^2 k / m_eff: a pair alone keeps 1/101 of its predicted penetration
REACH_SLACK = 0.1    # share of the ball's radius added to the candidates' search reach

# What a contact's stencil is (its ``shape``): how its weights and normal are found
BALL_POINT = 0       # a ball (node 0) and a point (node 1): c = (1, -1, 0, 0)
BALL_TRIANGLE = 1    # a ball and a sheet triangle: c = (1, -w_0, -w_1, -w_2)
POINT_TRIANGLE = 2   # a surface point and a surface triangle: c = (1, -w_0, -w_1, -w_2)
EDGE_EDGE = 3        # two surface edges: c = (1 - s, s, -(1 - t), -t)
MET = 0.5            # edges whose gap shrank below this share of its start on the way met


@kernel
def empty_contacts(count):
    """A contact set of ``count`` contacts, all inactive: (nodes (K, 4), weights c (K, 4),
    normal (K, 3), gap g, coefficient h^2 k, active, shape, rest distance). Contact p pushes
    the point sum_i c[p, i] x[nodes[p, i]] along its normal (module doc)."""
    return (np.zeros((count, 4), np.int64), np.zeros((count, 4)), np.zeros((count, 3)),
            np.zeros(count), np.zeros(count), np.zeros(count, np.bool_),
            np.zeros(count, np.int64), np.zeros(count))


@kernel
def no_contacts():
    """An empty contact set."""
    return empty_contacts(0)


no_ball_contacts = no_contacts   # the name the solve's tests know it by


@kernel
def find_solve_contacts(model, x, v, h, kept, own_points, own_edges):
    """The contact set of a step: every ball-point and ball-sheet-triangle pair
    (``find_ball_pairs``), every surface point-triangle and edge-edge pair of two bodies
    (surface_contact.find_surface_pairs, ``kept`` its list) the step can bring into contact,
    and the pairs of one body ``own_points``, ``own_edges`` (own_contact.py), all inactive
    until ``linearize_contacts``."""
    points, faces = find_ball_pairs(model, x, v, h)
    point_pairs, edge_pairs = find_surface_pairs(model, x, v, h, kept)
    point_pairs = np.concatenate((point_pairs, own_points))
    edge_pairs = np.concatenate((edge_pairs, own_edges))
    contacts = empty_contacts(points.shape[0] + faces.shape[0] + point_pairs.shape[0]
                              + edge_pairs.shape[0])
    nodes, weights, shape, rest = contacts[0], contacts[1], contacts[6], contacts[7]
    p = 0
    for k in range(points.shape[0]):
        a, b = points[k, 0], points[k, 1]
        nodes[p, 0], nodes[p, 1], nodes[p, 2], nodes[p, 3] = a, b, b, b
        weights[p, 0], weights[p, 1] = 1.0, -1.0
        shape[p], rest[p] = BALL_POINT, model.radius[a] + model.radius[b]
        p += 1
    triangles = model.sheet_triangles
    for k in range(faces.shape[0]):
        a, t = faces[k, 0], faces[k, 1]
        nodes[p, 0], nodes[p, 1], nodes[p, 2], nodes[p, 3] = a, triangles[t, 0], \
            triangles[t, 1], triangles[t, 2]
        shape[p], rest[p] = BALL_TRIANGLE, model.radius[a] + model.radius[triangles[t, 0]]
        p += 1
    triangles, edges = model.surface_triangles, model.surface_edges
    body, thickness = model.particle_body, model.body_thickness
    for k in range(point_pairs.shape[0]):
        q, t = point_pairs[k, 0], point_pairs[k, 1]
        nodes[p, 0], nodes[p, 1], nodes[p, 2], nodes[p, 3] = q, triangles[t, 0], \
            triangles[t, 1], triangles[t, 2]
        shape[p] = POINT_TRIANGLE
        rest[p] = 0.5 * (thickness[body[q]] + thickness[body[triangles[t, 0]]])
        p += 1
    for k in range(edge_pairs.shape[0]):
        e, f = edge_pairs[k, 0], edge_pairs[k, 1]
        nodes[p, 0], nodes[p, 1], nodes[p, 2], nodes[p, 3] = edges[e, 0], edges[e, 1], \
            edges[f, 0], edges[f, 1]
        shape[p] = EDGE_EDGE
        rest[p] = 0.5 * (thickness[body[edges[e, 0]]] + thickness[body[edges[f, 0]]])
        p += 1
    return contacts


@kernel
def find_ball_pairs(model, x, v, h):
    """The (ball, point) and (ball, sheet triangle row) pairs the step can bring into contact
    (module doc). A particle of a sheet is touched through its triangles, not as a point."""
    balls = model.balls
    if balls.shape[0] == 0:
        return np.empty((0, 2), np.int64), np.empty((0, 2), np.int64)
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
            continue   # ball-ball pairs are the post-step pass's
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
    return points[:n_points], faces


@kernel
def distance_squared(x, a, b):
    return (x[a, 0] - x[b, 0]) ** 2 + (x[a, 1] - x[b, 1]) ** 2 + (x[a, 2] - x[b, 2]) ** 2


@kernel
def linearize_contacts(model, contacts, x, v, dv, h, rhs):
    """Weights, normals, gaps and coefficients about the estimate x + h (v + dv); activate the
    contacts with g < 0 and add their right-hand side (module doc)."""
    nodes, weights, normal, gap, coefficient, active, shape, rest = contacts
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
def stencil(shape, estimate, start, c, n):
    """Set the weights c and the normal n of a contact of this shape from its four nodes'
    positions at the estimate and at the start of the step (module doc); False if it cannot
    touch (two edges closest at an end, a surface point on its triangle's edge).

    A surface point beside its triangle (closest to an edge or a corner) keeps the direction of
    d, as surface_collisions.py does: going around an edge is no passing through (the faces and
    edges beside it catch that), and taking the start's direction there held a cloth's points
    apart where the cloth folded around a fast ball (its fall was stopped at a third of its
    depth)."""
    if shape == BALL_POINT:
        c[0], c[1], c[2], c[3] = 1.0, -1.0, 0.0, 0.0
    elif shape == EDGE_EDGE:
        s, t = closest_on_segments(estimate[0], estimate[1], estimate[2], estimate[3])
        if not (0.0 < s < 1.0 and 0.0 < t < 1.0):
            return False   # the point-triangle contacts of the faces beside it decide
        c[0], c[1], c[2], c[3] = 1.0 - s, s, -(1.0 - t), -t
    else:
        w0, w1, w2 = closest_on_triangle(estimate[0], estimate[1:])
        c[0], c[1], c[2], c[3] = 1.0, -w0, -w1, -w2
        if shape == POINT_TRIANGLE and w0 > 0.0 and w1 > 0.0 and w2 > 0.0:
            return face_normal(estimate, start, c, n)
    d0, d1, d2 = weighted_sum(c, estimate)
    s0, s1, s2 = weighted_sum(c, start)
    if shape != POINT_TRIANGLE and d0 * s0 + d1 * s1 + d2 * s2 <= 0.0:
        d0, d1, d2 = s0, s1, s2   # the step passed it through (or one of them is zero)
    length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if length > 0.0:
        n[0], n[1], n[2] = d0 / length, d1 / length, d2 / length
        return True
    n[0], n[1], n[2] = 0.0, 1.0, 0.0   # concentric: choose up, as the post-step pass does
    return shape == BALL_POINT or shape == BALL_TRIANGLE


@kernel
def edges_met(d0, d1, d2, s0, s1, s2):
    """Whether two edges whose gap vector turned from s (start) to d (estimate) met on the way:
    on the straight path from s to d, the gap across s's direction vanishes within a thickness
    of where the gap along it does. A gap that merely turned (edges sliding past each other at
    a distance) is no passing through."""
    along_s, along_d = s0 * s0 + s1 * s1 + s2 * s2, s0 * d0 + s1 * d1 + s2 * d2
    if not along_s > along_d:
        return True   # s is zero: nothing to go by
    tau = along_s / (along_s - along_d)
    m0, m1, m2 = s0 + tau * (d0 - s0), s1 + tau * (d1 - s1), s2 + tau * (d2 - s2)
    return m0 * m0 + m1 * m1 + m2 * m2 <= MET * MET * along_s


@inline_kernel
def face_normal(estimate, start, c, n):
    """n = the triangle's normal at the estimate, on the side the point was at the start
    (surface_collisions.py's rule) if it went through the face: the point where its path
    relative to the triangle crosses the plane (both moving straight) lies inside the
    triangle; else on the side it is now. Why: a cloth pulled into a cone by a fast ball
    carries points past far triangles of its own; taking the start's side for them made gaps of
    -1 m and threw the ball 13 m up. False for a degenerate triangle."""
    n0, n1, n2 = triangle_normal(estimate, 1, 2, 3)
    m0, m1, m2 = triangle_normal(start, 1, 2, 3)
    s0, s1, s2 = weighted_sum(c, start)
    d0, d1, d2 = weighted_sum(c, estimate)
    before, after = m0 * s0 + m1 * s1 + m2 * s2, n0 * d0 + n1 * d1 + n2 * d2
    if before < 0.0:
        n0, n1, n2 = -n0, -n1, -n2
    n[0], n[1], n[2] = n0, n1, n2
    return n0 != 0.0 or n1 != 0.0 or n2 != 0.0


@kernel
def crossed_inside(estimate, start, before, after):
    """Whether the point (row 0) crosses the triangle (rows 1 to 3) inside it, all moving
    straight from start to estimate, at the fraction before / (before - after) of the way
    (the signed distances to the plane at the two ends)."""
    tau = before / (before - after)
    between = np.empty((4, 3))
    for i in range(4):
        for k in range(3):
            between[i, k] = start[i, k] + tau * (estimate[i, k] - start[i, k])
    w0, w1, w2 = closest_on_triangle(between[0], between[1:])
    return w0 > 0.0 and w1 > 0.0 and w2 > 0.0


@inline_kernel
def weighted_sum(c, positions):
    """sum_i c_i positions[i], as three scalars."""
    d0 = d1 = d2 = 0.0
    for i in range(4):
        d0 += c[i] * positions[i, 0]
        d1 += c[i] * positions[i, 1]
        d2 += c[i] * positions[i, 2]
    return d0, d1, d2


@kernel
def set_active(contacts, p, value, h, rhs):
    """Make contact p active or not, adding or removing its right-hand side, -h k g n shared
    as c_i of it by its nodes."""
    nodes, weights, normal, gap, coefficient, active = contacts[:6]
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
    nodes, weights, normal = contacts[0], contacts[1], contacts[2]
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
    return contacts[3][p] + h * relative_normal(contacts, p, ddv)


@kernel
def update_active_contacts(contacts, h, ddv, rhs):
    """One active-set pass after a solve (module doc); returns how many contacts changed."""
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
    """out += A_c u: each active contact adds c_i h^2 k n n^T sum_j c_j u_j to node i."""
    nodes, weights, normal, gap, coefficient, active = contacts[:6]
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
    nodes, weights, normal, gap, coefficient, active = contacts[:6]
    for p in range(nodes.shape[0]):
        if not active[p]:
            continue
        for r in range(3):
            for c in range(3):
                value = coefficient[p] * normal[p, r] * normal[p, c]
                for i in range(4):
                    diagonal[nodes[p, i], r, c] += weights[p, i] ** 2 * value


# How many linearized solves a step takes per radius a ball moves against a point it may touch.
# Measured on cloth-balls with a 20 m/s ball: at 1/30 s (1.3 radii per step) 3 solves hold it and 1
# does not; at 0.05 s (2 radii) 8 do and 5 do not.
SOLVES_PER_RADIUS = 4.0
SLOW_CONTACT = 0.5   # below half a radius per step one solve holds the ball (tests up to 1/60 s)


@kernel
def newton_iterations_needed(model, contacts, v, h, requested):
    """``requested``, or more when a ball moves more than half its radius against a point it may
    touch within this step: the contact normal then turns during the step, and the one-sided
    springs, linearized once, let the ball through; and at least IMPACT_SOLVES when a body
    closes fast on another's surface (``impact_solves``)."""
    nodes, shape, rest = contacts[0], contacts[6], contacts[7]
    most = 0.0
    needed = requested
    for k in range(nodes.shape[0]):
        if shape[k] != BALL_POINT and shape[k] != BALL_TRIANGLE:
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
# linearized once per stride: linearized once, at x + h v, a cube thrown at 10 m/s onto another
# at 1/30 s (0.33 m a step, past the 0.25 m particle spacing) was held with its lowest particles
# 0.37 m inside, its points linearized against triangles they had already passed. Measured with
# 5 cm thickness: at 10 m/s 3 solves hold it at the thickness, at 20 m/s 5 leave it 5.4 cm in
# and 8 hold it (tests/test_implicit_surface_contact.py).
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
