"""Closest points between the shapes that touch: a point and a triangle, two segments.

Written on scalars: they run for every candidate contact in every step (and every Newton
iteration of implicit_euler), where array temporaries would allocate.
"""
import math

from .._jit import kernel


@kernel
def closest_on_triangle(p, corners):
    """Barycentric weights of the point of the triangle corners[0], corners[1], corners[2]
    closest to the 3-vector p (Ericson, Real-Time Collision Detection, 5.1.5). Written on
    scalars: it runs for every candidate triangle in every Newton iteration, and array
    temporaries would allocate there."""
    a, b, c = corners[0], corners[1], corners[2]
    ab0, ab1, ab2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    ac0, ac1, ac2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    d1, d2 = along_edges(ab0, ab1, ab2, ac0, ac1, ac2, p[0] - a[0], p[1] - a[1], p[2] - a[2])
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0
    d3, d4 = along_edges(ab0, ab1, ab2, ac0, ac1, ac2, p[0] - b[0], p[1] - b[1], p[2] - b[2])
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return 1.0 - t, t, 0.0
    d5, d6 = along_edges(ab0, ab1, ab2, ac0, ac1, ac2, p[0] - c[0], p[1] - c[1], p[2] - c[2])
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return 1.0 - t, 0.0, t
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - t, t
    denominator = va + vb + vc
    if not denominator > 0.0:   # a degenerate triangle: its first corner
        return 1.0, 0.0, 0.0
    t_b, t_c = vb / denominator, vc / denominator
    return 1.0 - t_b - t_c, t_b, t_c


@kernel
def along_edges(ab0, ab1, ab2, ac0, ac1, ac2, q0, q1, q2):
    """(ab . q, ac . q)."""
    return ab0 * q0 + ab1 * q1 + ab2 * q2, ac0 * q0 + ac1 * q1 + ac2 * q2


@kernel
def closest_on_segments(p0, p1, q0, q1):
    """Parameters (s, t) in [0, 1] of the closest points p0 + s (p1 - p0) and q0 + t (q1 - q0)
    of two segments (Ericson, Real-Time Collision Detection, 5.1.9); parallel segments give
    one of their closest pairs."""
    d1 = (p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2])
    d2 = (q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2])
    r = (p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2])
    a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]
    e = d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]
    f = d2[0] * r[0] + d2[1] * r[1] + d2[2] * r[2]
    if a <= 0.0 and e <= 0.0:
        return 0.0, 0.0
    if a <= 0.0:
        return 0.0, clamp01(f / e)
    c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2]
    if e <= 0.0:
        return clamp01(-c / a), 0.0
    b = d1[0] * d2[0] + d1[1] * d2[1] + d1[2] * d2[2]
    denominator = a * e - b * b
    s = clamp01((b * f - c * e) / denominator) if denominator > 0.0 else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        return clamp01(-c / a), 0.0
    if t > 1.0:
        return clamp01((b - c) / a), 1.0
    return s, t


@kernel
def clamp01(value):
    return min(1.0, max(0.0, value))


@kernel
def triangle_normal(x, i, j, k):
    """The unit normal (x_j - x_i) x (x_k - x_i) / |...| of a triangle of rows of x, or zeros
    for a degenerate one."""
    nx, ny, nz = area_vector(x, i, j, k)
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not length > 0.0:
        return 0.0, 0.0, 0.0
    return nx / length, ny / length, nz / length


@kernel
def area_vector(x, i, j, k):
    """(x_j - x_i) x (x_k - x_i): twice the triangle's area along its normal."""
    ux, uy, uz = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
    wx, wy, wz = x[k, 0] - x[i, 0], x[k, 1] - x[i, 1], x[k, 2] - x[i, 2]
    return uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
