"""Body-body contact of the explicit methods (collision/pipeline.py) as differentiable NumPy
(its vector-Jacobian products: body_contact_adjoint.py; its stencils' closed forms:
stencil_geometry.py).

After every step (and after the terrain impacts) the forward finds the touching stencils at the
step's end positions, a point against a triangle, an edge against an edge, a ball against a
particle or a ball (collision/narrow_phase/after_step.py), then changes their velocities in
Jacobi passes of normal and Coulomb friction impulses (collision/response/impulses.py) and
their positions by a share of each overlap, a stuck contact's sliding taken back
(collision/response/overlap.py). ``respond`` does the same, in the same order of arithmetic,
and keeps what each pass did; ``respond_vjp`` (body_contact_adjoint.py) goes back through it.

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
from .stencil_geometry import (BALL, EDGE, POINT, Geometry, ball_geometry, closest_weights,
                               cross, dot, edge_geometry, point_geometry, segment_parameters)



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
