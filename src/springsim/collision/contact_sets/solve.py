"""The contact set of backward Euler's solve (contact_sets.SolveContacts): every pair the step can
bring into contact, all inactive until the solve linearizes them (response/penalty.py).

Ball pairs: every (ball a, point b) pair that the step could bring into contact is a candidate:
the broad phase (broad_phase/balls.find_contacts) run on the predicted positions x + h (v + dv),
with each ball's radius grown by the distance the step can close, h (|v_a| + the fastest point's
speed), plus BALL_REACH_SLACK of its radius. Ball-ball pairs that close fast are left to the
post-step pass (they bounce), and so are those that part fast (leaving a bounce); those that
rest on each other are held here (``resting_pair``).

A particle of a sheet (a cloth: model.sheet_triangles) is touched through its triangles, not as
a point: every triangle with a corner within that reach (grown by the longest triangle edge) is
a candidate. Why: a ball about the size of the cloth's spacing that lands between four
particles touches them at their sides; point contacts then push them apart instead of holding
the ball up, and it went through the cloth (benchmarks/ball_through_cloth.py). A ball at least
as large as a triangle touches it at fixed points instead of its closest point
(``sampled_faces`` says why).

Surface pairs of two bodies come from pair_lists/solve_pairs.py, a body's own pairs from
pair_lists/own_pairs.py.
"""
import math

import numpy as np

from ..._jit import kernel
from ..broad_phase.balls import find_contacts
from ..pair_lists.solve_pairs import find_surface_pairs
from . import BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE, EDGE_EDGE, POINT_TRIANGLE, SolveContacts


BALL_REACH_SLACK = 0.1    # share of the ball's radius added to the candidates' search reach


@kernel
def empty_contacts(count):
    """A SolveContacts of ``count`` contacts, all inactive."""
    return SolveContacts(np.zeros((count, 4), np.int64), np.zeros((count, 4)),
                         np.zeros((count, 3)), np.zeros(count), np.zeros(count),
                         np.zeros(count, np.bool_), np.zeros(count, np.int64), np.zeros(count))


@kernel
def no_contacts():
    """An empty contact set."""
    return empty_contacts(0)


@kernel
def find_solve_contacts(model, x, v, h, kept, own):
    """The contact set of a step: every ball-point and ball-sheet-triangle pair
    (``find_ball_pairs``), every surface point-triangle and edge-edge pair of two bodies
    (solve_pairs.find_surface_pairs, ``kept`` its list) the step can bring into contact,
    and the pairs of one body ``own`` (pair_lists/own_pairs.OwnPairs), all inactive
    until ``linearize_contacts``."""
    points, faces = find_ball_pairs(model, x, v, h)
    sampled = sampled_faces(model, x, faces)
    points = np.concatenate((points, sampled_corners(model, faces, sampled)))
    point_pairs, edge_pairs = find_surface_pairs(model, x, v, h, kept)
    point_pairs = np.concatenate((point_pairs, own.points))
    edge_pairs = np.concatenate((edge_pairs, own.edges))
    contacts = empty_contacts(points.shape[0] + faces.shape[0] + point_pairs.shape[0]
                              + edge_pairs.shape[0])
    nodes, weights, shape, rest = contacts.nodes, contacts.weights, contacts.shape, contacts.rest
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
        shape[p] = BALL_SAMPLE if sampled[k] else BALL_TRIANGLE
        rest[p] = model.radius[a] + model.radius[triangles[t, 0]]
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
        reach[a] += h * (speed + fastest) + BALL_REACH_SLACK * model.radius[a] + longest_edge
    found = find_contacts(predicted, reach, balls, model.ball_slot)
    start = model.triangle_start
    points = np.empty((found.shape[0], 2), np.int64)
    keys = np.empty(found.shape[0] * max(1, int(np.max(start[1:] - start[:-1]))), np.int64)
    n_points = n_keys = 0
    for k in range(found.shape[0]):
        a, b = found[k, 0], found[k, 1]
        if model.ball_slot[b] >= 0:
            if resting_pair(model, x, v, a, b, h):
                points[n_points, 0], points[n_points, 1] = a, b
                n_points += 1
            continue   # other ball-ball pairs are the post-step pass's: they bounce
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
def sampled_faces(model, x, faces):
    """Whether each (ball, sheet triangle) pair touches at fixed points, the triangle's centre
    (BALL_SAMPLE) and its corners (BALL_POINT), rather than at its closest point
    (BALL_TRIANGLE): when the ball's radius is at least the triangle's longest edge.

    Why: the closest point moves between a triangle's features as the solve turns it, and a
    contact linearized there misses the overlap the turn makes; the next step pushed it out as
    a velocity, and the reference cloth under its four balls kept moving at 0.4 m/s at
    frame-size steps (benchmarks/resting_balls.py). The distance to a fixed point is smooth.
    Between the points a ball dips into the triangle by about d^2 / 2r, d the distance to the
    nearest point: a few millimetres for the reference cloth's balls. A smaller ball could
    pass between them, and keeps the closest point."""
    triangles = model.sheet_triangles
    out = np.zeros(faces.shape[0], np.bool_)
    for k in range(faces.shape[0]):
        t = faces[k, 1]
        longest = 0.0
        for j in range(3):
            longest = max(longest, distance_squared(x, triangles[t, j], triangles[t, (j + 1) % 3]))
        out[k] = model.radius[faces[k, 0]] ** 2 >= longest
    return out


@kernel
def sampled_corners(model, faces, sampled):
    """The (ball, particle) pairs of the sampled faces' corners, each once."""
    triangles = model.sheet_triangles
    count = model.radius.shape[0]
    keys = np.empty(3 * faces.shape[0], np.int64)
    n = 0
    for k in range(faces.shape[0]):
        if sampled[k]:
            for j in range(3):
                keys[n] = faces[k, 0] * count + triangles[faces[k, 1], j]
                n += 1
    keys = np.unique(keys[:n])
    out = np.empty((keys.shape[0], 2), np.int64)
    for k in range(keys.shape[0]):
        out[k, 0], out[k, 1] = keys[k] // count, keys[k] % count
    return out


@kernel
def resting_pair(model, x, v, a, b, h):
    """Whether balls a and b close or part slower than gravity's pull adds in a step, |g| h:
    resting contact, in which restitution has nothing to reflect. Such a pair is held in the
    solve, where the cloth that presses the balls together feels it. Left to the post-step
    pass, the reference cloth pressed its four balls 5 cm into each other at 1/30 s, and they
    bounced there without end. A pair that parts faster is leaving a bounce: the pass after
    the step already gave it its restitution, and the solve's penalty, inelastic, would push
    out the overlap the impact left as speed on top of it (at 1e-3 s two balls left head-on
    collisions 0.1 m/s faster than the restitution law has them)."""
    d0, d1, d2 = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
    length = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if length == 0.0:
        return False
    closing = -((v[a, 0] - v[b, 0]) * d0 + (v[a, 1] - v[b, 1]) * d1
                + (v[a, 2] - v[b, 2]) * d2) / length
    g = model.gravity
    return abs(closing) < math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) * h
