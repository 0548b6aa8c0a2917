"""Body-body contact of the explicit methods (collision/pipeline.py) as differentiable NumPy, and
its vector-Jacobian products.

After every step (and after the terrain impacts) the forward finds the touching stencils at the
step's end positions, a point against a triangle, an edge against an edge, a ball against a
particle or a ball (collision/narrow_phase/after_step.py), then changes their velocities in
Jacobi passes of normal and Coulomb friction impulses (collision/response/impulses.py) and
their positions by a share of each overlap, a stuck contact's sliding taken back
(collision/response/overlap.py). ``respond`` does the same, in the same order of arithmetic,
and keeps what each pass did; ``respond_vjp`` goes back through it.

Which contacts there are, each one's region of the closest point (a face, an edge, a corner),
which side a face's normal points to, whether an impulse pushes and whether friction sticks:
these are the branches the run took, taken as given, as at a terrain (contact.py). The
gradient is that branch's derivative; where a pair starts or stops touching, the motion has a
kink and the gradient is one-sided: finite, never NaN. A stencil's weights, normal and depth
depend on its four particles' positions through the closest points; their Jacobian is taken
by the complex step (f(x + i s e_j) has imaginary part s df/dx_j to rounding, for a step s far
below rounding: Squire and Trapp 1998), on the closed forms of the region the run took.

Parameters: the bodies' contact restitution and friction, and the balls'; the masses (each
contact's reduced mass and each particle's share of an impulse). A self-colliding body's own
contacts (a cloth folded onto itself) are the same stencils, found by the same search with the
forward's rule for which of its own pairs count (broad_phase/surfaces.may_touch_triangle:
not a point and a triangle or two edges that share a surface edge).
"""
from typing import NamedTuple

import numpy as np

from ..collision.broad_phase.balls import find_contacts
from ..collision.broad_phase.surfaces import surface_pairs
from ..collision.contact_sets import BALL_PASSES, CORRECTION, PASSES
from ..errors import SceneError

STEP = 1e-30    # the complex step: its square and products vanish beside any coordinate


class Bodies(NamedTuple):
    """The model's contact arrays (model.py documents each)."""

    body: np.ndarray        # (P,) each particle's contact body
    points: np.ndarray      # (Q,) the surface particles
    triangles: np.ndarray   # (T, 3)
    edges: np.ndarray       # (E, 2)
    thickness: np.ndarray   # (B,) m
    restitution: np.ndarray
    friction: np.ndarray
    static: np.ndarray
    radius: np.ndarray      # (P,) m, 0 for a point
    balls: np.ndarray       # (N,) the balls' particles
    ball_slot: np.ndarray   # (P,) row in the ball tables, or -1
    ball_restitution: np.ndarray
    particle_restitution: np.ndarray
    particle_friction: np.ndarray
    correction: np.ndarray
    arrays: object = None   # the model's arrays, which the forward's broad phase searches
    collide: bool = False   # whether anything can touch: two bodies' surfaces, one that
                            # collides with itself, or a ball
    own: bool = False       # whether some body's surface collides with itself

    @classmethod
    def of(cls, arrays) -> "Bodies":
        ints = [np.asarray(getattr(arrays, name), np.int64) for name in
                ("particle_body", "surface_points", "surface_triangles", "surface_edges")]
        floats = [np.asarray(getattr(arrays, name), float) for name in
                  ("body_thickness", "body_restitution", "body_friction",
                   "body_static_friction", "radius")]
        balls = [np.asarray(arrays.balls, np.int64), np.asarray(arrays.ball_slot, np.int64)]
        tables = [np.asarray(getattr(arrays, name), float) for name in
                  ("ball_restitution", "particle_restitution", "particle_friction",
                   "position_correction")]
        ints[2], ints[3] = ints[2].reshape(-1, 3), ints[3].reshape(-1, 2)
        surface_bodies = np.unique(ints[0][ints[2][:, 0]])
        own = bool(np.any(np.asarray(arrays.body_self_collision, bool)[surface_bodies]))
        collide = bool(len(balls[0])) or len(np.unique(ints[0][ints[1]])) > 1 or own
        return cls(*ints, *floats, *balls, *tables, arrays, collide, own)


NO_BODIES = Bodies(np.empty(0, np.int64), np.empty(0, np.int64), np.empty((0, 3), np.int64),
                   np.empty((0, 2), np.int64), *(np.empty(0),) * 5, np.empty(0, np.int64),
                   np.empty(0, np.int64), *(np.empty(0),) * 4)


class Geometry(NamedTuple):
    """How each contact's stencil was found: its kind and the branches of its closed form."""

    kind: np.ndarray     # (K,) POINT, EDGE or BALL
    face: np.ndarray     # (K,) bool: a point above a triangle's face (the face normal)
    region: np.ndarray   # (K,) a point-triangle's closest-point region (``closest_weights``)
    sign: np.ndarray     # (K,) +-1: the side the start had (a face's normal, an edge pair's)
    rest: np.ndarray     # (K,) m: the rest distance (thickness, or the radii)
    pair: np.ndarray     # (K, 2) a surface contact's two bodies, whose keys it takes; -1 balls


POINT, EDGE, BALL = 0, 1, 2


class Contacts(NamedTuple):
    """The touching stencils (contact_sets.ImpulseContacts) and how they were found."""

    nodes: np.ndarray     # (K, 4)
    weights: np.ndarray   # (K, 4) summing to zero
    normal: np.ndarray    # (K, 3)
    depth: np.ndarray     # (K,)
    params: np.ndarray    # (K, 6) as ImpulseContacts.params
    geometry: Geometry


class Pass(NamedTuple):
    """One Jacobi pass of the impulses: what its adjoint needs."""

    active: np.ndarray    # (K,) bool: the contacts that took part
    v: np.ndarray         # (P, 3) the velocities it started from
    relative: np.ndarray  # (K, 3)
    approach: np.ndarray  # (K,)
    pushed: np.ndarray    # (K,) bool: a normal impulse
    j: np.ndarray         # (K,) the normal impulse (N s)
    w: np.ndarray         # (K, 3) the friction wanted before the cone
    stuck: np.ndarray     # (K,) bool
    total: np.ndarray     # (K,) the accumulated normal impulse after this pass
    impulse: np.ndarray   # (K, 3) this pass's, per contact


class Response(NamedTuple):
    """What ``respond`` did: the contacts, their mobilities and every pass, and the overlap
    correction's inputs."""

    contacts: Contacts
    count: np.ndarray     # (P,) how many contacts each particle takes part in
    mobility: np.ndarray  # (K,)
    passes: list
    stuck: np.ndarray     # (K,) static friction held it in its last pass
    x: np.ndarray         # (P, 3) the positions before the correction
    start: np.ndarray     # (P, 3) the step's start
    shift: np.ndarray     # (K, 3)


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


# ---- finding the contacts -------------------------------------------------------------------

def touching(physical, x, start) -> Contacts:
    """The touching stencils at x (``start``: the step's start positions), surfaces first
    (point-triangle, edge-edge), then balls, as contact_sets.after_step.touching_contacts."""
    bodies = physical.bodies
    points, edges = (near_pairs(bodies, x, float(bodies.thickness.max()))   # within 2 rest
                     if len(bodies.triangles) else (None, None))
    found = [point_contacts(bodies, x, start, points), edge_contacts(bodies, x, start, edges),
             ball_contacts(bodies, x)]
    return Contacts(*(np.concatenate([part[i] for part in found]) for i in range(5)),
                    Geometry(*(np.concatenate([part[5][i] for part in found])
                               for i in range(6))))


def surface_params(bodies, first, second):
    """(K, 6): contact_sets.after_step.surface_params for body pairs."""
    out = np.empty((len(first), 6))
    out[:, 0] = 0.5 * (bodies.restitution[first] + bodies.restitution[second])
    out[:, 1] = 0.5 * (bodies.friction[first] + bodies.friction[second])
    out[:, 2] = 0.5 * (bodies.static[first] + bodies.static[second])
    out[:, 3], out[:, 4], out[:, 5] = CORRECTION, 1.0, PASSES
    return out


def empty_part():
    return (np.empty((0, 4), np.int64), np.empty((0, 4)), np.empty((0, 3)), np.empty(0),
            np.empty((0, 6)), (np.empty(0, np.int64), np.empty(0, bool), np.empty(0, np.int64),
                               np.empty(0), np.empty(0), np.empty((0, 2), np.int64)))


def near_pairs(bodies, x, beyond):
    """((K, 2) point-triangle pairs (particle, triangle row), (L, 2) edge-edge pairs (edge rows,
    lower first)) closer than their rest distance plus ``beyond`` (m): the forward's own broad
    phase (collision/broad_phase/surfaces.py), searched afresh, a self-colliding body's own
    pairs included."""
    return surface_pairs(bodies.arrays, np.ascontiguousarray(x), beyond, beyond)


def point_contacts(bodies, x, start, pairs):
    """narrow_phase.after_step.point_triangle_contact for the (point, triangle) ``pairs`` of
    two bodies (near_pairs)."""
    if pairs is None:
        return empty_part()
    body, thickness = bodies.body, bodies.thickness
    triangle_body = body[bodies.triangles[:, 0]]
    points, t = pairs[:, 0], pairs[:, 1]
    triangles = bodies.triangles[t]
    rest = 0.5 * (thickness[body[points]] + thickness[triangle_body[t]])
    x4 = x[np.column_stack([points, triangles])]
    w, region = closest_weights(x4[:, 0], x4[:, 1], x4[:, 2], x4[:, 3])
    face = (w[:, 0] > 0.0) & (w[:, 1] > 0.0) & (w[:, 2] > 0.0)
    s4 = start[np.column_stack([points, triangles])]
    start_normal = cross(s4[:, 2] - s4[:, 1], s4[:, 3] - s4[:, 1])
    side = dot(s4[:, 0] - w[:, 0:1] * s4[:, 1] - w[:, 1:2] * s4[:, 2] - w[:, 2:3] * s4[:, 3],
               start_normal)
    sign = np.where(side < 0.0, -1.0, 1.0)
    weights, normal, gap = point_geometry(x4, face, region, sign)
    d = x4[:, 0] - w[:, 0:1] * x4[:, 1] - w[:, 1:2] * x4[:, 2] - w[:, 2:3] * x4[:, 3]
    distance = np.sqrt(dot(d, d))
    keep = np.flatnonzero((distance < 2.0 * rest) & (face | (distance > 0.0)) & (gap < rest))
    nodes = np.column_stack([points, triangles])[keep]
    pair = np.column_stack([body[points[keep]], triangle_body[t[keep]]])
    params = surface_params(bodies, pair[:, 0], pair[:, 1])
    geometry = (np.full(len(keep), POINT), face[keep], region[keep], sign[keep], rest[keep],
                pair)
    return nodes, weights[keep], normal[keep], rest[keep] - gap[keep], params, geometry


def edge_contacts(bodies, x, start, pairs):
    """narrow_phase.after_step.edge_edge_contact for the edge ``pairs`` of two bodies (the
    lower row first, as the broad phase lists them: near_pairs)."""
    edges = bodies.edges
    if pairs is None or not len(edges):
        return empty_part()
    edge_body = bodies.body[edges[:, 0]]
    thickness = bodies.thickness
    e, f = pairs[:, 0], pairs[:, 1]
    nodes = np.column_stack([edges[e], edges[f]])
    x4 = x[nodes]
    a, b, c, q = x4[:, 0], x4[:, 1], x4[:, 2], x4[:, 3]
    s, t, inside = segment_parameters(a, b, c, q)
    with np.errstate(invalid="ignore"):   # parallel edges: NaN, and never inside
        d = ((1.0 - s)[:, None] * a + s[:, None] * b - (1.0 - t)[:, None] * c - t[:, None] * q)
        distance = np.sqrt(dot(d, d))
        s4 = start[nodes]
        along = dot(d, (1.0 - s)[:, None] * s4[:, 0] + s[:, None] * s4[:, 1]
                    - (1.0 - t)[:, None] * s4[:, 2] - t[:, None] * s4[:, 3])
    rest = 0.5 * (thickness[edge_body[e]] + thickness[edge_body[f]])
    sign = np.where(along >= 0.0, 1.0, -1.0)
    keep = np.flatnonzero(inside & (distance < rest) & (distance > 0.0))
    weights, normal, gap = edge_geometry(x4[keep], sign[keep])
    pair = np.column_stack([edge_body[e[keep]], edge_body[f[keep]]])
    params = surface_params(bodies, pair[:, 0], pair[:, 1])
    geometry = (np.full(len(keep), EDGE), np.zeros(len(keep), bool),
                np.zeros(len(keep), np.int64), sign[keep], rest[keep], pair)
    return nodes[keep], weights, normal, rest[keep] - gap, params, geometry


def ball_contacts(bodies, x):
    """narrow_phase.after_step.ball_contact for every overlapping (ball, partner) pair
    (broad_phase.balls.find_contacts, the forward's own search)."""
    if not len(bodies.balls):
        return empty_part()
    pairs = find_contacts(np.ascontiguousarray(x), bodies.radius, bodies.balls,
                          bodies.ball_slot)
    nodes = np.column_stack([pairs[:, 0], pairs[:, 1], pairs[:, 1], pairs[:, 1]])
    weights, normal, distance = ball_geometry(x[nodes], None)
    rest = bodies.radius[pairs[:, 0]] + bodies.radius[pairs[:, 1]]
    # the search compares squares; the contact holds where the overlap itself is positive
    keep = np.flatnonzero(rest - distance > 0.0)
    nodes, weights, normal, distance, rest = (nodes[keep], weights[keep], normal[keep],
                                              distance[keep], rest[keep])
    a, b = nodes[:, 0], nodes[:, 1]
    ball, other = bodies.ball_slot[a], bodies.ball_slot[b]
    partner = np.where(other >= 0, other, ball)
    both = other >= 0
    params = np.empty((len(a), 6))
    params[:, 0] = np.where(both, 0.5 * (bodies.ball_restitution[ball]
                                         + bodies.ball_restitution[partner]),
                            bodies.particle_restitution[ball])
    params[:, 1] = params[:, 2] = np.where(both, 0.0, bodies.particle_friction[ball])
    params[:, 3] = np.where(both, 0.5 * (bodies.correction[ball] + bodies.correction[partner]),
                            bodies.correction[ball])
    params[:, 4], params[:, 5] = 0.0, BALL_PASSES
    geometry = (np.full(len(a), BALL), np.zeros(len(a), bool), np.zeros(len(a), np.int64),
                np.ones(len(a)), rest, np.full((len(a), 2), -1))
    return nodes, weights, normal, rest - distance, params, geometry


# ---- the response -----------------------------------------------------------------------------

def gather(weights, nodes, u):
    """sum_i c_i u[n_i] per contact, summed in the kernels' order."""
    parts = weights[:, :, None] * u[nodes]
    return ((parts[:, 0] + parts[:, 1]) + parts[:, 2]) + parts[:, 3]


def scatter(weights, nodes, inv_mass, values, out):
    """out[n_i] += c_i m_i^-1 values_k, contact by contact, as the kernels add them."""
    share = weights * inv_mass[nodes]
    np.add.at(out, nodes.ravel(), (share[:, :, None] * values[:, None, :]).reshape(-1, 3))


def respond(physical, x, v, start):
    """(x, v) after collision/pipeline.respond_to_contacts, and a Response (None if nothing
    touched)."""
    contacts = touching(physical, x, start)
    if not len(contacts.nodes):
        return x, v, None
    inv = physical.inv_mass
    nodes, c = contacts.nodes, contacts.weights
    count, mobility = mobilities(inv, nodes, c)
    v, passes, stuck = impulse_passes(inv, v, contacts, mobility, np.zeros(len(c)), True)
    shift = overlap_shifts(contacts, x, start, stuck, mobility)
    x_out = x.copy()
    scatter(c, nodes, inv, shift, x_out)
    return x_out, v, Response(contacts, count, mobility, passes, stuck, x, start, shift)


def mobilities(inv, nodes, c):
    """(how many contacts each particle takes part in (P,), each contact's mobility
    W = sum_i c_i^2 n_i / m_i (K,)): response/impulses.split_mobilities."""
    count = np.zeros(len(inv))
    np.add.at(count, nodes[c != 0.0], 1.0)
    terms = c * c * inv[nodes] * count[nodes]
    return count, ((terms[:, 0] + terms[:, 1]) + terms[:, 2]) + terms[:, 3]


def impulse_passes(inv, v, contacts, mobility, pushed, push):
    """response/impulses.impulse_passes: (v after them, [Pass], which contacts stuck). Friction
    against the accumulated normal impulse, which starts at ``pushed``; with ``push`` the
    normal impulses that stop each approach too (restitution in the first pass)."""
    nodes, c, n, params = contacts.nodes, contacts.weights, contacts.normal, contacts.params
    restitution, kinetic, static = params[:, 0], params[:, 1], params[:, 2]
    total, rubbed, target = pushed.copy(), np.zeros((len(c), 3)), np.zeros(len(c))
    stuck = np.zeros(len(c), bool)
    v, passes = v.copy(), []
    for sweep in range(int(params[:, 5].max(initial=0))):
        active = (mobility > 0.0) & (sweep < params[:, 5])
        relative = gather(c, nodes, v)
        approach = dot(relative, n)
        if sweep == 0 and push:
            target = -restitution * np.minimum(approach, 0.0)
        pushes = push & (target - approach > 0.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            j = np.where(active & pushes, (target - approach) / mobility, 0.0)
            total = total + j
            w = rubbed - (relative - approach[:, None] * n) / mobility[:, None]
            size = np.sqrt(dot(w, w))
            sticks = size <= static * total
            cut = np.where(sticks, 1.0, kinetic * total / size)
        wanted = np.where(sticks[:, None], w, w * cut[:, None])
        impulse = np.where(active[:, None], (wanted - rubbed) + j[:, None] * n, 0.0)
        passes.append(Pass(active, v.copy(), relative, approach, pushes, j, w, sticks, total,
                           impulse))
        rubbed = np.where(active[:, None], wanted, rubbed)
        stuck = np.where(active, sticks & (static > 0.0), stuck)
        scatter(c, nodes, inv, impulse, v)
    return v, passes, stuck


def slid(contacts, x, start):
    """sum_i c_i (x - start)[n_i] per contact: its sliding during the step."""
    return gather(contacts.weights, contacts.nodes, x - start)


def overlap_shifts(contacts, x, start, stuck, mobility):
    """response/overlap.correct_overlaps' shift per contact (K, 3)."""
    n, params = contacts.normal, contacts.params
    shift = (params[:, 3] * np.maximum(contacts.depth, 0.0))[:, None] * n
    back = stuck & (params[:, 4] > 0.0)
    sliding = slid(contacts, x, start)
    along = dot(sliding, n)
    shift = np.where(back[:, None], shift - params[:, 4, None]
                     * (sliding - along[:, None] * n), shift)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where((mobility > 0.0)[:, None], shift / mobility[:, None], 0.0)


# ---- the adjoint ------------------------------------------------------------------------------

class Bars(NamedTuple):
    """The cotangents of the contacts' stencils and of the inverse masses, gathered on the way
    back before they go to the positions."""

    weights: np.ndarray   # (K, 4)
    normal: np.ndarray    # (K, 3)
    depth: np.ndarray     # (K,)
    mobility: np.ndarray  # (K,)
    inv_mass: np.ndarray  # (P,)
    kinetic: np.ndarray   # (K,) each contact's kinetic friction
    restitution: np.ndarray   # (K,) and restitution


def scatter_vjp(weights, nodes, inv_mass, values, out_bar, bars):
    """Of out[n_i] += c_i m_i^-1 values_k: the values' cotangent (K, 3), the weights' and the
    inverse masses' added to ``bars``."""
    after = out_bar[nodes]                                # (K, 4, 3)
    moved = np.einsum("kjc,kc->kj", after, values)
    bars.weights[...] += inv_mass[nodes] * moved
    np.add.at(bars.inv_mass, nodes.ravel(), (weights * moved).ravel())
    return np.einsum("kj,kjc->kc", weights * inv_mass[nodes], after)


def gather_vjp(weights, nodes, u, g, u_bar, bars):
    """Of sum_i c_i u[n_i]: g (K, 3) to u_bar and the weights."""
    np.add.at(u_bar, nodes.ravel(), (weights[:, :, None] * g[:, None, :]).reshape(-1, 3))
    bars.weights[...] += np.einsum("kjc,kc->kj", u[nodes], g)


def respond_vjp(physical, response, x_bar, v_bar, bar):
    """The cotangents of (x, v) before ``respond`` and of the step's start positions, from
    those after it (the masses' share added to ``bar``)."""
    contacts = response.contacts
    count = len(contacts.nodes)
    bars = Bars(np.zeros((count, 4)), np.zeros((count, 3)), np.zeros(count), np.zeros(count),
                np.zeros(len(x_bar)), np.zeros(count), np.zeros(count))
    x_bar, v_bar = x_bar.copy(), v_bar.copy()
    start_bar = np.zeros_like(x_bar)
    overlap_vjp(physical, response, x_bar, start_bar, bars)
    impulse_passes_vjp(physical, contacts, response.mobility, response.passes, v_bar, bars)
    mobility_vjp(physical, contacts, response.count, bars)
    geometry_vjp(contacts, response.x, bars, x_bar)
    inv = physical.inv_mass
    bar.mass += np.where(physical.free, -bars.inv_mass * inv * inv, 0.0)
    keys_vjp(physical, contacts, bars, bar)
    return x_bar, v_bar, start_bar


def keys_vjp(physical, contacts, bars, bar):
    """The contacts' restitution and kinetic friction cotangents to the keys they came from
    (surface_params, ball_contacts): a surface contact's are the means of its two bodies', a
    ball-ball contact's restitution the mean of the two balls', a ball-particle contact's the
    ball's own."""
    surface = contacts.geometry.pair[:, 0] >= 0
    for side in (0, 1):
        bodies = contacts.geometry.pair[surface, side]
        np.add.at(bar.body_friction, bodies, 0.5 * bars.kinetic[surface])
        np.add.at(bar.body_restitution, bodies, 0.5 * bars.restitution[surface])
    slot = physical.bodies.ball_slot
    ball, partner = slot[contacts.nodes[~surface, 0]], slot[contacts.nodes[~surface, 1]]
    both = partner >= 0
    restitution, kinetic = bars.restitution[~surface], bars.kinetic[~surface]
    np.add.at(bar.ball_restitution, ball[both], 0.5 * restitution[both])
    np.add.at(bar.ball_restitution, partner[both], 0.5 * restitution[both])
    np.add.at(bar.particle_restitution, ball[~both], restitution[~both])
    # static and kinetic friction are one key: only the kinetic is differentiable
    np.add.at(bar.particle_friction, ball[~both], kinetic[~both])


def overlap_vjp(physical, response, x_bar, start_bar, bars):
    """Back through x' = x + sum c m^-1 shift, shift = S / W (overlap_shifts)."""
    contacts, mobility = response.contacts, response.mobility
    nodes, c, n, params = contacts.nodes, contacts.weights, contacts.normal, contacts.params
    shift_bar = scatter_vjp(c, nodes, physical.inv_mass, response.shift, x_bar, bars)
    moving = mobility > 0.0
    safe = np.where(moving, mobility, 1.0)
    s_bar = np.where(moving[:, None], shift_bar / safe[:, None], 0.0)
    bars.mobility[...] -= np.where(moving, dot(shift_bar, response.shift) / safe, 0.0)
    pushed = params[:, 3] * np.maximum(contacts.depth, 0.0)
    bars.depth[...] += np.where(contacts.depth > 0.0, params[:, 3] * dot(n, s_bar), 0.0)
    bars.normal[...] += pushed[:, None] * s_bar
    back = np.where(response.stuck & (params[:, 4] > 0.0), params[:, 4], 0.0)
    sliding = slid(contacts, response.x, response.start)
    along, s_n = dot(sliding, n), dot(n, s_bar)
    sliding_bar = -back[:, None] * (s_bar - s_n[:, None] * n)
    bars.normal[...] += back[:, None] * (along[:, None] * s_bar + s_n[:, None] * sliding)
    gather_vjp(c, nodes, response.x - response.start, sliding_bar, x_bar, bars)
    np.add.at(start_bar, nodes.ravel(), -(c[:, :, None] * sliding_bar[:, None, :])
              .reshape(-1, 3))


def impulse_passes_vjp(physical, contacts, mobility, passes, v_bar, bars):
    """Back through ``impulse_passes``, last pass first: v_bar in place, the contacts' and the
    masses' cotangents into ``bars``; returns the cotangent of the starting ``pushed``."""
    nodes, c, n, params = contacts.nodes, contacts.weights, contacts.normal, contacts.params
    restitution, kinetic = params[:, 0], params[:, 1]
    inv = physical.inv_mass
    count = len(c)
    total_bar, rubbed_bar, target_bar = np.zeros(count), np.zeros((count, 3)), np.zeros(count)
    safe = np.where(mobility > 0.0, mobility, 1.0)
    for sweep in reversed(range(len(passes))):
        this_pass = passes[sweep]
        active = this_pass.active
        impulse_bar = np.where(active[:, None], scatter_vjp(c, nodes, inv, this_pass.impulse,
                                                            v_bar, bars), 0.0)
        wanted_bar = impulse_bar + rubbed_bar
        previous_bar = np.where(active[:, None], -impulse_bar, rubbed_bar)
        j_bar = dot(impulse_bar, n)
        bars.normal[...] += this_pass.j[:, None] * impulse_bar
        w, total = this_pass.w, this_pass.total
        with np.errstate(divide="ignore", invalid="ignore"):
            size = np.sqrt(dot(w, w))
            along_w = dot(w, wanted_bar)
            slide = active & ~this_pass.stuck
            q = np.where(slide, kinetic * total / size, 1.0)
            w_bar = q[:, None] * wanted_bar - np.where(
                slide, kinetic * total * along_w / size ** 3, 0.0)[:, None] * w
            total_bar = total_bar + np.where(slide, kinetic * along_w / size, 0.0)
            bars.kinetic[...] += np.where(slide, total * along_w / size, 0.0)
        w_bar = np.where(active[:, None], w_bar, 0.0)
        previous_bar = previous_bar + w_bar
        tangential = this_pass.relative - this_pass.approach[:, None] * n
        tangential_bar = -w_bar / safe[:, None]
        bars.mobility[...] += np.where(active, dot(tangential, w_bar) / (safe * safe), 0.0)
        relative_bar = tangential_bar.copy()
        approach_bar = -dot(tangential_bar, n)
        bars.normal[...] -= this_pass.approach[:, None] * tangential_bar
        j_bar = np.where(active, j_bar + total_bar, 0.0)
        push = active & this_pass.pushed
        target_bar = target_bar + np.where(push, j_bar / safe, 0.0)
        approach_bar -= np.where(push, j_bar / safe, 0.0)
        bars.mobility[...] -= np.where(push, j_bar * this_pass.j / safe, 0.0)
        if sweep == 0:
            approach_bar += np.where(this_pass.approach < 0.0, -restitution * target_bar, 0.0)
            bars.restitution[...] -= np.minimum(this_pass.approach, 0.0) * target_bar
        relative_bar += approach_bar[:, None] * n
        bars.normal[...] += approach_bar[:, None] * this_pass.relative
        relative_bar = np.where(active[:, None], relative_bar, 0.0)
        gather_vjp(c, nodes, this_pass.v, relative_bar, v_bar, bars)
        rubbed_bar = previous_bar
    return total_bar


def mobility_vjp(physical, contacts, count, bars):
    """W = sum_i c_i^2 m_i^-1 n_i (the particles' contact counts n_i fixed)."""
    nodes, c = contacts.nodes, contacts.weights
    inv, count = physical.inv_mass[nodes], count[nodes]
    bars.weights[...] += 2.0 * c * inv * count * bars.mobility[:, None]
    np.add.at(bars.inv_mass, nodes.ravel(), (c * c * count * bars.mobility[:, None]).ravel())


def geometry_vjp(contacts, x, bars, x_bar):
    """The stencils' weights, normals and depths depend on their particles' positions:
    their cotangents go there through the complex step (module doc), kind by kind."""
    geometry = contacts.geometry
    for kind in (POINT, EDGE, BALL):
        rows = np.flatnonzero(geometry.kind == kind)
        if not len(rows):
            continue
        x4 = x[contacts.nodes[rows]].astype(complex)
        x4_bar = np.zeros((len(rows), 4, 3))
        for corner in range(4):
            for axis in range(3):
                x4[:, corner, axis] += 1j * STEP
                weights, normal, gap = geometry_of(geometry, rows, x4)
                x4[:, corner, axis] -= 1j * STEP
                x4_bar[:, corner, axis] = (
                    dot4(bars.weights[rows], weights.imag) + dot(bars.normal[rows], normal.imag)
                    - bars.depth[rows] * gap.imag) / STEP
        np.add.at(x_bar, contacts.nodes[rows].ravel(), x4_bar.reshape(-1, 3))


def dot4(u, w):
    return u[:, 0] * w[:, 0] + u[:, 1] * w[:, 1] + u[:, 2] * w[:, 2] + u[:, 3] * w[:, 3]


def check_replayed(replayed, end, h, allowed, what):
    """Refuse a step whose replay (x, v) does not end where the forward did, ``end``, within
    ``allowed`` m/s (and h ``allowed`` m): a gradient of another step would be no gradient.
    ``what`` says which step and what to try."""
    x_out, v_out = replayed
    if not (np.abs(v_out - end[1]).max() <= allowed
            and np.abs(x_out - end[0]).max() <= h * allowed):
        raise SceneError("bodies", "contact", what)


def far_from_bodies(physical, h, start, end) -> bool:
    """Whether no body contact can have acted in the step from ``start`` to ``end``: nothing
    touched at the step's end before the correction, which moved each particle by less than
    the rest distance plus what it slid. Tested at the end with every reach doubled and the
    fastest particle's step added, generously."""
    bodies = physical.bodies
    if not bodies.collide:
        return True
    x = end[0]
    slack = 2.0 * h * float(np.sqrt(np.max(dot(start[1], start[1]), initial=0.0)
                                    + np.max(dot(end[1], end[1]), initial=0.0)))
    if len(bodies.triangles):
        # 2 rest distances (a contact's reach) and the correction's move (a rest distance
        # and what the particle slid)
        points, edges = near_pairs(bodies, x, 2.0 * float(bodies.thickness.max()) + slack)
        if len(points) or len(edges):
            return False
    for a in bodies.balls:
        distance = np.sqrt(dot(x - x[a], x - x[a]))
        close = distance < 2.0 * (bodies.radius[a] + bodies.radius) + slack
        close[a] = False
        if close.any():
            return False
    return True
