"""The stencils of the contacts at the end of a step (the post-step pass: collision/pipeline.py).

Each contact is a stencil of four particles with signed weights c that sum to zero: the gap
vector d = sum_i c_i x_i runs from the triangle's closest point to the point
(c = (1, -w_0, -w_1, -w_2), w the closest point's barycentric weights), between the closest
points of two edges (c = (1 - s, s, -(1 - t), -t)), or from a ball's partner to the ball's
centre (c = (1, -1, 0, 0)). A surface contact holds while the gap g along its normal n is below
the pair's rest distance r (the mean of the two bodies' ``thickness``); a ball contact while
the centres are closer than r_a + r_b (a partner that is not a ball is a point: r_b = 0), n the
unit vector from the partner to the ball.

Which side: the normal points to the side the pair was on at the start of the step, so a step
that carried a point through a triangle (or an edge past an edge) pushes it back, not through.
A point above a triangle's face uses the face normal; one beside it (closest point on an edge or
corner), the direction of d. The search reaches a thickness either side: a step that carries a
point less than its thickness through a surface is always caught, and at the default time steps
the fastest body moves a few millimetres a step against 2 to 5 cm of thickness.

A ball's contacts take BALL_PASSES pass and no sliding back, as the course's reference resolved
them (one impulse each): a single contact gets exactly its impulse, j = -(1 + e) v_N / W, with
the Coulomb share of the sliding removed.
"""
import math

from ..._jit import inline_kernel
from ...geometry.closest_points import triangle_normal
from . import BALL_PASSES
from .stencils import edge_edge_stencil, point_triangle_stencil


@inline_kernel
def ball_contact(keys, x, a, b, contacts, row):
    """Fill row ``row`` of ``contacts`` for ball a and particle (or ball) b if they overlap: the
    stencil (1, -1) along n, the unit vector from b to a, depth r_a + r_b - |x_a - x_b|.
    ``keys``: the model's radius, ball_slot and ball tables (touching_contacts)."""
    radius, ball_slot, ball_restitution, particle_restitution, particle_friction, correction = keys
    dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    overlap = radius[a] + radius[b] - distance
    if not overlap > 0.0:
        return False
    n = (0.0, 1.0, 0.0)   # concentric: any direction separates them; choose up
    if distance > 0.0:
        n = (dx / distance, dy / distance, dz / distance)
    fill_row(contacts, row, (a, b, b, b), (1.0, -1.0, 0.0, 0.0), n, overlap)
    ball, other = ball_slot[a], ball_slot[b]
    # every key read whichever kind the pair is, and the kind chosen among numbers: reading an
    # array inside the branch kept its reference counting in the loop (several times slower)
    partner = other if other >= 0 else ball
    mean_restitution = 0.5 * (ball_restitution[ball] + ball_restitution[partner])
    mean_correction = 0.5 * (correction[ball] + correction[partner])
    restitution, friction, shared = (particle_restitution[ball], particle_friction[ball],
                                     correction[ball])
    if other >= 0:   # ball-ball: the means of both balls' keys, no friction
        restitution, friction, shared = mean_restitution, 0.0, mean_correction
    params = contacts.params
    params[row, 0] = restitution
    params[row, 1] = params[row, 2] = friction
    params[row, 3] = shared
    params[row, 4] = 0.0   # friction on the velocities only, as the reference's balls
    params[row, 5] = BALL_PASSES
    return True


@inline_kernel
def point_triangle_contact(triangles, body, thickness, x, start, p, t, contacts, row, bodies,
                           corners):
    """Fill row ``row`` of ``contacts`` for point p and triangle t if they touch (module doc);
    their bodies into ``bodies[0]``. ``corners``: (3, 3) work space."""
    a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    rest = 0.5 * (thickness[body[p]] + thickness[body[a]])
    for i in range(3):   # most listed pairs are further apart: a cheap test first
        if not (min(x[a, i], x[b, i], x[c, i]) - 2.0 * rest < x[p, i]
                < max(x[a, i], x[b, i], x[c, i]) + 2.0 * rest):
            return False
    for i in range(3):
        corners[0, i], corners[1, i], corners[2, i] = x[a, i], x[b, i], x[c, i]
    w0, w1, w2, d0, d1, d2 = point_triangle_stencil(x[p], corners)
    distance = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if not distance < 2.0 * rest:   # a point carried through the face: up to a thickness
        return False
    if w0 > 0.0 and w1 > 0.0 and w2 > 0.0:   # above the face: the face normal, on the start side
        n0, n1, n2 = triangle_normal(x, a, b, c)
        s0, s1, s2 = triangle_normal(start, a, b, c)
        side = ((start[p, 0] - w0 * start[a, 0] - w1 * start[b, 0] - w2 * start[c, 0]) * s0
                + (start[p, 1] - w0 * start[a, 1] - w1 * start[b, 1] - w2 * start[c, 1]) * s1
                + (start[p, 2] - w0 * start[a, 2] - w1 * start[b, 2] - w2 * start[c, 2]) * s2)
        if side < 0.0:
            n0, n1, n2 = -n0, -n1, -n2
        gap = n0 * d0 + n1 * d1 + n2 * d2
    elif distance > 0.0:
        n0, n1, n2 = d0 / distance, d1 / distance, d2 / distance
        gap = distance
    else:
        return False   # on an edge, no direction known: the faces beside it decide
    if not gap < rest:
        return False
    fill_row(contacts, row, (p, a, b, c), (1.0, -w0, -w1, -w2), (n0, n1, n2), rest - gap)
    bodies[0, 0], bodies[0, 1] = body[p], body[a]
    return True


@inline_kernel
def edge_edge_contact(edges, body, thickness, x, start, e, f, contacts, row, bodies):
    """Fill row ``row`` of ``contacts`` for edges e and f if they touch between their ends
    (where an end is closest, the point-triangle contacts of the faces beside it decide); their
    bodies into ``bodies[0]``."""
    a, b, c, q = edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]
    rest = 0.5 * (thickness[body[a]] + thickness[body[c]])
    for i in range(3):   # most listed pairs are further apart: a cheap test first
        if max(x[a, i], x[b, i]) + rest < min(x[c, i], x[q, i]) \
                or max(x[c, i], x[q, i]) + rest < min(x[a, i], x[b, i]):
            return False
    s, t, d0, d1, d2 = edge_edge_stencil(x[a], x[b], x[c], x[q])
    if not (0.0 < s < 1.0 and 0.0 < t < 1.0):
        return False
    distance = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    if not (distance < rest and distance > 0.0):
        return False
    along = (d0 * ((1.0 - s) * start[a, 0] + s * start[b, 0] - (1.0 - t) * start[c, 0]
                   - t * start[q, 0])
             + d1 * ((1.0 - s) * start[a, 1] + s * start[b, 1] - (1.0 - t) * start[c, 1]
                     - t * start[q, 1])
             + d2 * ((1.0 - s) * start[a, 2] + s * start[b, 2] - (1.0 - t) * start[c, 2]
                     - t * start[q, 2]))
    sign = 1.0 if along >= 0.0 else -1.0   # the edges passed each other during the step: back
    fill_row(contacts, row, (a, b, c, q), (1.0 - s, s, -(1.0 - t), -t),
             (sign * d0 / distance, sign * d1 / distance, sign * d2 / distance),
             rest - sign * distance)
    bodies[0, 0], bodies[0, 1] = body[a], body[c]
    return True


@inline_kernel
def fill_row(contacts, row, nodes, weights, normal, depth):
    """Write one contact into row ``row`` of ``contacts`` (contact_sets.ImpulseContacts, at
    its capacity: touching_contacts): its stencil's four particles and signed weights, its
    unit normal and its depth. The narrow phase reads the value by its field names only, so it
    need not import contact_sets (which imports it)."""
    out_nodes, out_weights, out_normal = contacts.nodes, contacts.weights, contacts.normal
    out_nodes[row, 0], out_nodes[row, 1], out_nodes[row, 2], out_nodes[row, 3] = nodes
    out_weights[row, 0], out_weights[row, 1], out_weights[row, 2], out_weights[row, 3] = weights
    out_normal[row, 0], out_normal[row, 1], out_normal[row, 2] = normal
    contacts.depth[row] = depth
