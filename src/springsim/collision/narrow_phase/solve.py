"""The stencils of the solve's contacts, at the positions the solve linearizes about (the Newton
estimate x + h (v + dv), the prediction x + h v in the first iteration):
    ball-point       c = (1, -1, 0, 0)            (a point is its own contact point)
    ball-triangle    c = (1, -w_0, -w_1, -w_2)    (w: barycentric weights of the triangle's point
    point-triangle   c = (1, -w_0, -w_1, -w_2)     closest to the ball's centre or the point)
    ball-sample      c = (1, -1/3, -1/3, -1/3)    (the triangle's centre, fixed:
                                                   contact_sets/solve.sampled_faces)
    edge-edge        c = (1 - s, s, -(1 - t), -t)  (s, t: the edges' closest points)
The normal n is d / |d| there, or d at the start of the step (same weights) if the step has
carried one side past the other (d . d_start <= 0); a surface point above a triangle's face
takes the face's normal instead, on the side the point was at the start, and one beside it
d / |d| always (``stencil`` says why). Two edges closest at an end, or a surface point on its
triangle's edge, touch through the neighbouring contacts and are left inactive.
"""
import math

from ..._jit import inline_kernel, kernel
from ...geometry.closest_points import triangle_normal
from . import BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE, EDGE_EDGE, POINT_TRIANGLE
from .stencils import edge_edge_stencil, point_triangle_stencil


@kernel
def stencil(shape, estimate, start, c, n):
    """Set the weights c and the normal n of a contact of this shape from its four nodes'
    positions at the estimate and at the start of the step (module doc); False if it cannot
    touch (two edges closest at an end, a surface point on its triangle's edge).

    A surface point beside its triangle (closest to an edge or a corner) keeps the direction of d,
    as narrow_phase/after_step.point_triangle_contact does: going around an edge is no passing
    through (the faces and edges beside it catch that), and taking the start's direction there held
    a cloth's points apart where the cloth folded around a fast ball (its fall was stopped at a
    third of its depth)."""
    if shape == BALL_POINT:
        c[0], c[1], c[2], c[3] = 1.0, -1.0, 0.0, 0.0
    elif shape == BALL_SAMPLE:
        c[0], c[1], c[2], c[3] = 1.0, -1.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0
    elif shape == EDGE_EDGE:
        s, t, _, _, _ = edge_edge_stencil(estimate[0], estimate[1], estimate[2], estimate[3])
        if not (0.0 < s < 1.0 and 0.0 < t < 1.0):
            return False   # the point-triangle contacts of the faces beside it decide
        c[0], c[1], c[2], c[3] = 1.0 - s, s, -(1.0 - t), -t
    else:
        w0, w1, w2, _, _, _ = point_triangle_stencil(estimate[0], estimate[1:])
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
    return shape == BALL_POINT or shape == BALL_TRIANGLE or shape == BALL_SAMPLE


@inline_kernel
def face_normal(estimate, start, c, n):
    """n = the triangle's normal at the estimate, on the side the point was on at the start of
    the step (the post-step pass's rule, narrow_phase/after_step.py), so that a point the step
    carried through the face is pushed back, not on through. The solve takes a body's own pairs
    only where they touch (pair_lists/own_pairs.py), so a fold's points passing far triangles
    of their own are no contacts here. False for a degenerate triangle."""
    n0, n1, n2 = triangle_normal(estimate, 1, 2, 3)
    m0, m1, m2 = triangle_normal(start, 1, 2, 3)
    s0, s1, s2 = weighted_sum(c, start)
    if m0 * s0 + m1 * s1 + m2 * s2 < 0.0:
        n0, n1, n2 = -n0, -n1, -n2
    n[0], n[1], n[2] = n0, n1, n2
    return n0 != 0.0 or n1 != 0.0 or n2 != 0.0


@inline_kernel
def weighted_sum(c, positions):
    """sum_i c_i positions[i], as three scalars."""
    d0 = d1 = d2 = 0.0
    for i in range(4):
        d0 += c[i] * positions[i, 0]
        d1 += c[i] * positions[i, 1]
        d2 += c[i] * positions[i, 2]
    return d0, d1, d2
