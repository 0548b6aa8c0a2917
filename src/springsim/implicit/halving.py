"""A backward Euler step that carries a surface through another is taken again in halves.

The solve's contacts are penalty springs (surface_contact.py, own_contact.py): stiff, but not
hard. A heavy load met within one large step can press them past what they hold: a 128 kg
cube dropped at 5 m/s onto a cloth folded in half pushed the top layer through the bottom one
at its corners in 8 of 12 runs at 1/60 and 1/30 s, while at 1/120 and 1/240 s none crossed
(benchmarks/folded_cloth_press.py). So each step is checked for what the post-step pass cannot
undo, a surface carried through another (``carried_through``), and where it finds one, the
step is taken again from its start as two steps of half the size, each checked the same way
(after a half that passes, the steps grow back), down to 1 / 2^MOST_HALVINGS of the step. Where
even that crosses (a cloth already tangled, passing out as well as in, or a load the contacts
cannot hold at any step), halving does not help, and the step is taken whole from its start, as
it would be without the check: a 128 kg cube at 10 m/s, carried on from a crossed 1/16 part,
threw itself 10 m up, where taken whole it stays down, crossed as it was without the check. So
a step never loops, and one that halving cannot help ends as without it, at the cost of the
parts that failed (seven solves where none passes). A step that crosses nothing is taken as
before, bit for bit, at the cost of the check over the pairs in reach and of keeping the state
it started from.

What the check sees: the pairs of the surface lists at the step's end (the post-step pass's,
which holds a body's own pairs within reach there, and the solve's, which holds the pairs of two
bodies the step could bring together). The four points of a pair are taken to move linearly from
the step's start to its end; where the volume they span changes sign they were coplanar during
the step (the moment found by bisection), and if there the point lies within PASS_TOLERANCE of
its rest distance of the triangle (or the edges of each other) it passed through. Edges turning
past parallel at a distance, a point passing beside a triangle, a pair crossed at the start that
stays crossed: none of these counts. Not seen: a pair carried out of the lists' reach by the end
of the step (beyond its rest distance plus the skin, surface_collisions.py), and neighbours along
a surface edge, which self-contact leaves out (a cloth folded sharply along a line can still
cross itself there: a 32 kg cube at 10 m/s did, in 2 of 6 runs at 1/60 s).
"""
import math

import numpy as np

from .._jit import kernel
from ..geometry import closest_on_segments, closest_on_triangle

MOST_HALVINGS = 6   # a step is cut into parts down to 1 / 2^MOST_HALVINGS of it
PASS_TOLERANCE = 0.25   # of the rest distance: how near, where coplanar, counts as through
BISECTIONS = 30   # halvings of the step that find where four points are coplanar


@kernel
def carried_through(model, start, x, pairs, kept):
    """Whether the step from ``start`` to ``x`` carried a point through a triangle or an edge
    past an edge (module doc): a pair of the post-step list ``pairs`` or of the solve's list
    ``kept`` (surface_contact.kept_surface_pairs)."""
    return (any_point_passed(model, start, x, pairs[0])
            or any_point_passed(model, start, x, kept[0][0])
            or any_edge_passed(model, start, x, pairs[1])
            or any_edge_passed(model, start, x, kept[0][1]))


@kernel
def any_point_passed(model, start, x, points):
    """Whether a point-triangle pair of ``points`` passed through (point_passed_face)."""
    corners = np.empty((4, 3))
    for k in range(points.shape[0]):
        if point_passed_face(model.surface_triangles, model.particle_body, model.body_thickness,
                             start, x, points[k, 0], points[k, 1], corners):
            return True
    return False


@kernel
def any_edge_passed(model, start, x, edge_pairs):
    """Whether an edge-edge pair of ``edge_pairs`` passed each other (edge_passed_edge)."""
    ends = np.empty((4, 3))
    for k in range(edge_pairs.shape[0]):
        if edge_passed_edge(model.surface_edges, model.particle_body, model.body_thickness,
                            start, x, edge_pairs[k, 0], edge_pairs[k, 1], ends):
            return True
    return False


@kernel
def point_passed_face(triangles, body, thickness, start, x, p, t, corners):
    """Whether point p passed through triangle t during the step (module doc). ``corners``:
    work space (4, 3)."""
    a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    if not coplanar_between(start, x, a, b, c, p, False, corners):
        return False
    w0, w1, w2 = closest_on_triangle(corners[3], corners)
    apart = 0.0
    for i in range(3):
        apart += (corners[3, i] - w0 * corners[0, i] - w1 * corners[1, i]
                  - w2 * corners[2, i]) ** 2
    rest = 0.5 * (thickness[body[p]] + thickness[body[a]])
    return math.sqrt(apart) < PASS_TOLERANCE * rest


@kernel
def edge_passed_edge(edges, body, thickness, start, x, e, f, ends):
    """Whether edges e and f passed each other during the step (module doc). ``ends``: work
    space (4, 3)."""
    a, b, c, q = edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]
    if not coplanar_between(start, x, a, b, c, q, True, ends):
        return False
    s, t = closest_on_segments(ends[0], ends[1], ends[2], ends[3])
    apart = 0.0
    for i in range(3):
        apart += ((1.0 - s) * ends[0, i] + s * ends[1, i] - (1.0 - t) * ends[2, i]
                  - t * ends[3, i]) ** 2
    rest = 0.5 * (thickness[body[a]] + thickness[body[c]])
    return math.sqrt(apart) < PASS_TOLERANCE * rest


@kernel
def coplanar_between(start, x, i, j, k, m, edges, at):
    """Whether the four particles, moving linearly from ``start`` to ``x``, change sides
    (``volume``) during the step; if so, ``at`` holds their positions where they are
    coplanar (found by BISECTIONS halvings of the step)."""
    interpolate(start, x, i, j, k, m, 0.0, at)
    before = volume(at, edges)
    interpolate(start, x, i, j, k, m, 1.0, at)
    if not before * volume(at, edges) < 0.0:
        return False
    low, high = 0.0, 1.0
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        interpolate(start, x, i, j, k, m, middle, at)
        if volume(at, edges) * before > 0.0:
            low = middle
        else:
            high = middle
    interpolate(start, x, i, j, k, m, high, at)
    return True


@kernel
def interpolate(start, x, i, j, k, m, share, at):
    """at = the particles i, j, k, m at ``share`` of the step (linear motion)."""
    for c in range(3):
        at[0, c] = start[i, c] + share * (x[i, c] - start[i, c])
        at[1, c] = start[j, c] + share * (x[j, c] - start[j, c])
        at[2, c] = start[k, c] + share * (x[k, c] - start[k, c])
        at[3, c] = start[m, c] + share * (x[m, c] - start[m, c])


@kernel
def volume(at, edges):
    """The signed volume that vanishes when the four points are coplanar:
    (at1 - at0) x (at2 - at0) . (at3 - at0) for a triangle (at0, at1, at2) and a point at3;
    (at1 - at0) x (at3 - at2) . (at2 - at0) for edges at0-at1 and at2-at3."""
    u0, u1, u2 = at[1, 0] - at[0, 0], at[1, 1] - at[0, 1], at[1, 2] - at[0, 2]
    if edges:
        v0, v1, v2 = at[3, 0] - at[2, 0], at[3, 1] - at[2, 1], at[3, 2] - at[2, 2]
        w0, w1, w2 = at[2, 0] - at[0, 0], at[2, 1] - at[0, 1], at[2, 2] - at[0, 2]
    else:
        v0, v1, v2 = at[2, 0] - at[0, 0], at[2, 1] - at[0, 1], at[2, 2] - at[0, 2]
        w0, w1, w2 = at[3, 0] - at[0, 0], at[3, 1] - at[0, 1], at[3, 2] - at[0, 2]
    return (u1 * v2 - u2 * v1) * w0 + (u2 * v0 - u0 * v2) * w1 + (u0 * v1 - u1 * v0) * w2


@kernel
def saved_state(state):
    """A copy of the implicit step's state (implicit_euler.implicit_euler_step's tuple)."""
    x, v, kind, terrain, normal_floor, friction_damping, last_change = state
    return (x.copy(), v.copy(), kind.copy(), terrain.copy(), normal_floor.copy(),
            friction_damping.copy(), last_change.copy())


@kernel
def copy_state(out, state):
    """Copy the implicit step's ``state`` into ``out`` (one like it, saved_state), in place."""
    copy_rows(out[0], state[0])
    copy_rows(out[1], state[1])
    copy_rows(out[6], state[6])
    for i in range(state[2].shape[0]):
        out[2][i] = state[2][i]
        out[3][i] = state[3][i]
        out[4][i] = state[4][i]
        out[5][i] = state[5][i]


@kernel
def copy_rows(out, x):
    for i in range(x.shape[0]):
        for c in range(3):
            out[i, c] = x[i, c]
