"""The geometry of a body-body contact's stencil (body_contact.py): its weights over its four
particles, its normal and its gap, in the closed form of the branch the run took (a point over
a triangle's face, edge or corner, two edges, two balls), written so that the complex step can
differentiate it (``dot`` without a conjugate); and the stencils of backward Euler's penalty
contacts (implicit_bodies.py), in the branches narrow_phase/solve.stencil took."""
from typing import NamedTuple

import numpy as np

from ..collision.contact_sets import (BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE, EDGE_EDGE,
                                      POINT_TRIANGLE)

STEP = 1e-30    # the complex step: its square and products vanish beside any coordinate


class Geometry(NamedTuple):
    """How each contact's stencil was found: its kind and the branches of its closed form."""

    kind: np.ndarray     # (K,) POINT, EDGE or BALL
    face: np.ndarray     # (K,) bool: a point above a triangle's face (the face normal)
    region: np.ndarray   # (K,) a point-triangle's closest-point region (``closest_weights``)
    sign: np.ndarray     # (K,) +-1: the side the start had (a face's normal, an edge pair's)
    rest: np.ndarray     # (K,) m: the rest distance (thickness, or the radii)
    pair: np.ndarray     # (K, 2) a surface contact's two bodies, whose keys it takes; -1 balls


POINT, EDGE, BALL = 0, 1, 2


def dot(u, w):
    """Row-wise u . w, summed as the kernels do (no conjugate: the complex step needs that)."""
    return u[..., 0] * w[..., 0] + u[..., 1] * w[..., 1] + u[..., 2] * w[..., 2]


def cross(u, w):
    return np.stack([u[..., 1] * w[..., 2] - u[..., 2] * w[..., 1],
                     u[..., 2] * w[..., 0] - u[..., 0] * w[..., 2],
                     u[..., 0] * w[..., 1] - u[..., 1] * w[..., 0]], axis=-1)


def closest_weights(p, a, b, c, region=None):
    """(w (K, 3), region (K,)): closest_points.closest_on_triangle for rows, its regions
    0 corner a, 1 corner b, 2 edge ab, 3 corner c, 4 edge ac, 5 edge bc, 6 face, 7 degenerate,
    taken from the real parts unless given."""
    ab, ac = b - a, c - a
    d1, d2 = dot(ab, p - a), dot(ac, p - a)
    d3, d4 = dot(ab, p - b), dot(ac, p - b)
    d5, d6 = dot(ab, p - c), dot(ac, p - c)
    vc, vb, va = d1 * d4 - d3 * d2, d5 * d2 - d1 * d6, d3 * d6 - d5 * d4
    if region is None:
        r = [np.real(value) for value in (d1, d2, d3, d4, d5, d6, va, vb, vc)]
        d1r, d2r, d3r, d4r, d5r, d6r, var, vbr, vcr = r
        region = np.select(
            [(d1r <= 0) & (d2r <= 0), (d3r >= 0) & (d4r <= d3r),
             (vcr <= 0) & (d1r >= 0) & (d3r <= 0), (d6r >= 0) & (d5r <= d6r),
             (vbr <= 0) & (d2r >= 0) & (d6r <= 0),
             (var <= 0) & (d4r - d3r >= 0) & (d5r - d6r >= 0), ~(var + vbr + vcr > 0)],
            [0, 1, 2, 3, 4, 5, 7], 6)
    one, zero = np.ones_like(d1), np.zeros_like(d1)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_ab, t_ac = d1 / (d1 - d3), d2 / (d2 - d6)
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        denominator = va + vb + vc
        t_b, t_c = vb / denominator, vc / denominator
    choices = [(one, zero, zero), (zero, one, zero), (1.0 - t_ab, t_ab, zero),
               (zero, zero, one), (1.0 - t_ac, zero, t_ac), (zero, 1.0 - t_bc, t_bc),
               (1.0 - t_b - t_c, t_b, t_c), (one, zero, zero)]
    w = np.zeros(p.shape, dtype=np.result_type(p, a, b, c))
    for code, (w0, w1, w2) in enumerate(choices):
        rows = region == code
        w[rows, 0], w[rows, 1], w[rows, 2] = w0[rows], w1[rows], w2[rows]
    return w, region


def point_geometry(x4, face, region, sign):
    """(weights (K, 4), normal (K, 3), gap (K,)) of point-triangle stencils whose particles'
    positions are x4 (K, 4, 3), in the branches given (narrow_phase/after_step.py)."""
    p, a, b, c = x4[:, 0], x4[:, 1], x4[:, 2], x4[:, 3]
    w, _ = closest_weights(p, a, b, c, region)
    d = p - w[:, 0:1] * a - w[:, 1:2] * b - w[:, 2:3] * c
    area = cross(b - a, c - a)
    length = np.sqrt(dot(area, area))
    distance = np.sqrt(dot(d, d))
    with np.errstate(divide="ignore", invalid="ignore"):
        normal = np.where(face[:, None], sign[:, None] * area / length[:, None],
                          d / distance[:, None])
    gap = np.where(face, dot(normal, d), distance)
    weights = np.concatenate([np.ones_like(w[:, :1]), -w], axis=1)
    return weights, normal, gap


def segment_parameters(a, b, c, q):
    """(s, t, inside): closest_points.closest_on_segments' unclamped branch for the segments
    a-b and c-q (rows, real or complex), and whether that is the branch taken with both closest
    points strictly inside their segments, the only case in which two edges touch."""
    d1, d2, r = b - a, q - c, a - c
    aa, ee, ff = dot(d1, d1), dot(d2, d2), dot(d2, r)
    cc, bb = dot(d1, r), dot(d1, d2)
    denominator = aa * ee - bb * bb
    with np.errstate(divide="ignore", invalid="ignore"):   # parallel edges: no closest pair
        s = (bb * ff - cc * ee) / denominator
        t = (bb * s + ff) / ee
        inside = ((np.real(aa) > 0.0) & (np.real(ee) > 0.0) & (np.real(denominator) > 0.0)
                  & (0.0 < np.real(s)) & (np.real(s) < 1.0) & (0.0 < np.real(t))
                  & (np.real(t) < 1.0))
    return s, t, inside


def edge_geometry(x4, sign):
    """(weights, normal, gap) of edge-edge stencils (segments x4[:, 0]-x4[:, 1] and
    x4[:, 2]-x4[:, 3]) whose closest points are inside both (segment_parameters)."""
    a, b, c, q = x4[:, 0], x4[:, 1], x4[:, 2], x4[:, 3]
    s, t, _ = segment_parameters(a, b, c, q)
    d = ((1.0 - s)[:, None] * a + s[:, None] * b - (1.0 - t)[:, None] * c - t[:, None] * q)
    distance = np.sqrt(dot(d, d))
    weights = np.stack([1.0 - s, s, -(1.0 - t), -t], axis=1)
    return weights, sign[:, None] * d / distance[:, None], sign * distance


def ball_geometry(x4, _sign):
    """(weights, normal, gap) of ball stencils (x4[:, 0] the ball, x4[:, 1] its partner;
    ``_sign`` unused: every kind's geometry takes one). Concentric: the normal is up, as the
    forward chooses, and does not turn."""
    d = x4[:, 0] - x4[:, 1]
    distance = np.sqrt(dot(d, d))
    weights = np.zeros(x4.shape[:2], dtype=x4.dtype)
    weights[:, 0], weights[:, 1] = 1.0, -1.0
    apart = np.real(distance) > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        normal = np.where(apart[:, None], d / distance[:, None], np.array([0.0, 1.0, 0.0]))
    return weights, normal, distance


def geometry_of(geometry: Geometry, rows, x4):
    """(weights, normal, gap) of the contacts ``rows`` (all of one kind) at x4."""
    kind = int(geometry.kind[rows[0]])
    if kind == POINT:
        return point_geometry(x4, geometry.face[rows], geometry.region[rows],
                              geometry.sign[rows])
    if kind == EDGE:
        return edge_geometry(x4, geometry.sign[rows])
    return ball_geometry(x4, geometry.sign[rows])


# ---- the stencils of backward Euler's penalty contacts (collision/narrow_phase/solve.stencil) ----

def stencil_branches(shape, c, n, e4, s4):
    """The branches narrow_phase/solve.stencil took: the normal from the start (the step passed
    the pair through), a point's face, its closest-point region, the face normal's side."""
    point = shape == POINT_TRIANGLE
    with np.errstate(divide="ignore", invalid="ignore"):   # a ball-point's "triangle" is a point
        w, region = closest_weights(e4[:, 0], e4[:, 1], e4[:, 2], e4[:, 3])
    face = point & (w[:, 0] > 0.0) & (w[:, 1] > 0.0) & (w[:, 2] > 0.0)
    d, s = np.einsum("kj,kjc->kc", c, e4), np.einsum("kj,kjc->kc", c, s4)
    flipped = ~point & (dot(d, s) <= 0.0)
    start_normal = cross(s4[:, 2] - s4[:, 1], s4[:, 3] - s4[:, 1])
    sign = np.where(dot(start_normal, s) < 0.0, -1.0, 1.0)
    return flipped, face, region, sign


def solve_stencil(shape, flipped, face, region, sign, e4, s4):
    """(weights, normal) of narrow_phase/solve.stencil in the branches given, for complex
    positions (the complex step)."""
    point = shape == POINT_TRIANGLE
    kind = np.result_type(e4, s4)
    weights = np.zeros((len(shape), 4), dtype=kind)
    normal = np.zeros((len(shape), 3), dtype=kind)
    if point.any():   # the post-step pass's stencil, at the estimate
        weights[point], normal[point], _ = point_geometry(e4[point], face[point], region[point],
                                                          sign[point])
    for rows, stencil_weights in ((shape == EDGE_EDGE, edge_weights),
                                  (shape == BALL_TRIANGLE, ball_triangle_weights),
                                  (shape == BALL_POINT, lambda e4, _: BALL_POINT_WEIGHTS),
                                  (shape == BALL_SAMPLE, lambda e4, _: BALL_SAMPLE_WEIGHTS)):
        if rows.any():
            w = stencil_weights(e4[rows], region[rows]) * np.ones((rows.sum(), 1))
            weights[rows] = w
            normal[rows] = stencil_normal(w, e4[rows], s4[rows], flipped[rows])
    return weights, normal


BALL_POINT_WEIGHTS = np.array([1.0, -1.0, 0.0, 0.0])
BALL_SAMPLE_WEIGHTS = np.array([1.0, -1.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0])


def edge_weights(e4, _region):
    s, t, _ = segment_parameters(*(e4[:, i] for i in range(4)))
    return np.stack([1.0 - s, s, -(1.0 - t), -t], axis=1)


def ball_triangle_weights(e4, region):
    w, _ = closest_weights(e4[:, 0], e4[:, 1], e4[:, 2], e4[:, 3], region)
    return np.concatenate([np.ones_like(w[:, :1]), -w], axis=1)


def stencil_normal(w, e4, s4, flipped):
    """d / |d|, d = sum_i c_i e_i, or the start's sum where the step passed the pair through;
    up where the two are concentric (a ball about a point), as the forward chooses."""
    d = np.einsum("kj,kjc->kc", w, e4)
    start = np.einsum("kj,kjc->kc", w, s4)
    chosen = np.where(flipped[:, None], start, d)
    length = np.sqrt(dot(chosen, chosen))
    apart = np.real(length) > 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(apart[:, None], chosen / length[:, None], np.array([0.0, 1.0, 0.0]))
