"""The one stencil builder: a point against a triangle, an edge against an edge.

Every stage that measures a pair of surface shapes goes through these: the post-step pass's
contacts (after_step.py), the solve's contacts at its Newton estimate (solve.py), the surface
search's and the own pairs' distances (``point_triangle_distance``, ``edge_distance``) and the
continuous check (ccd/). A stencil is the weights c, summing to zero, with which
d = sum_i c_i x_i runs from one shape to the other:
    point-triangle   c = (1, -w_0, -w_1, -w_2)     (w: the closest point's barycentric weights)
    edge-edge        c = (1 - s, s, -(1 - t), -t)  (s, t: the edges' closest points)
A ball and its partner need none: c = (1, -1, 0, 0), d = x_a - x_b. Inlined: they take arrays,
and a call that passes arrays costs more than they do (_jit.inline_kernel).
"""
import math

from ..._jit import inline_kernel, kernel
from ...geometry.closest_points import closest_on_segments, closest_on_triangle


@inline_kernel
def point_triangle_stencil(point, corners):
    """(w0, w1, w2, d0, d1, d2): the barycentric weights of the point of the triangle
    ``corners`` (3, 3) closest to ``point``, and d = point - sum_k w_k corners[k], from that
    closest point to the point."""
    w0, w1, w2 = closest_on_triangle(point, corners)
    d0 = point[0] - w0 * corners[0, 0] - w1 * corners[1, 0] - w2 * corners[2, 0]
    d1 = point[1] - w0 * corners[0, 1] - w1 * corners[1, 1] - w2 * corners[2, 1]
    d2 = point[2] - w0 * corners[0, 2] - w1 * corners[1, 2] - w2 * corners[2, 2]
    return w0, w1, w2, d0, d1, d2


@inline_kernel
def edge_edge_stencil(a, b, c, q):
    """(s, t, d0, d1, d2): the parameters of the closest points of the segments a-b and c-q,
    and d = (1 - s) a + s b - (1 - t) c - t q, from the second's to the first's."""
    s, t = closest_on_segments(a, b, c, q)
    d0 = (1.0 - s) * a[0] + s * b[0] - (1.0 - t) * c[0] - t * q[0]
    d1 = (1.0 - s) * a[1] + s * b[1] - (1.0 - t) * c[1] - t * q[1]
    d2 = (1.0 - s) * a[2] + s * b[2] - (1.0 - t) * c[2] - t * q[2]
    return s, t, d0, d1, d2


@kernel
def point_triangle_distance(x, triangles, p, t, corners):
    """The distance (m) from particle p to triangle t (``corners``: work space (3, 3))."""
    for k in range(3):
        for c in range(3):
            corners[k, c] = x[triangles[t, k], c]
    _, _, _, d0, d1, d2 = point_triangle_stencil(x[p], corners)
    return math.sqrt(d0 ** 2 + d1 ** 2 + d2 ** 2)


@kernel
def edge_distance(x, edges, e, f):
    """The distance (m) between edges e and f."""
    a, b, c, q = edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]
    _, _, d0, d1, d2 = edge_edge_stencil(x[a], x[b], x[c], x[q])
    return math.sqrt(d0 ** 2 + d1 ** 2 + d2 ** 2)
