"""Body-body contact after the step: the one pass that every integrator runs, for every pair
that touches. A point of one surface against a triangle of another (or of its own, for a
self-colliding body), two edges of self-colliding bodies, and a ball against any particle or
another ball.

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

Response, after the integrator's step, in Jacobi passes: every contact's impulse is computed
from the same velocities, then all are applied. With W = sum_i c_i^2 n_i / m_i, a contact
approaching at v_N = n . sum_i c_i v_i < 0 gets the normal impulse that brings v_N to -e v_N
(its first pass's), and a Coulomb friction impulse against the tangential velocity that sticks
(stops it) while the accumulated friction stays within the static friction times the
accumulated normal impulse, else slides with the kinetic friction times it. Each contact's
impulse is shared by its stencil, particle i getting c_i / m_i of it. n_i is how many contacts
particle i takes part in: each contact sees 1 / n_i of its mass (mass splitting, Tonge,
Benevolenski and Voroshilov 2012), so that contacts sharing particles do not add up to several
times the push, and the passes converge. Then each overlap is reduced by a share of its depth
the same way, and a surface contact that static friction held has its sliding during the step
taken back.
Why Jacobi and not one contact after another (Gauss-Seidel): the result would depend on the
contacts' order, so on the particle numbering, and a symmetric scene would not stay symmetric
(tests/test_ball_contact_order.py: the balls' sequential pass, before they joined this one,
failed both). Every impulse and shift acts with weights summing to zero, so momentum is
conserved to rounding.

Each contact carries its parameters (PARAMS):
- surfaces: the means of the two bodies' restitution, friction and static friction,
  CORRECTION of the depth a step, PASSES passes;
- a ball and a particle: the ball's ``particle_restitution``, ``particle_friction`` (static and
  kinetic alike) and ``position_correction``; a ball and a ball: the means of their
  ``ball_restitution`` and ``position_correction``, no friction. A ball's contacts take
  BALL_PASSES pass and no sliding back, as the course's reference resolved them (one impulse
  each): a single contact gets exactly its impulse, j = -(1 + e) v_N / W, with the Coulomb
  share of the sliding removed. Eight passes cost cloth-balls's 44 resting contacts 11 to 16 us
  a step instead of 3 (timed in a compiled loop; a step is about 80 us).
Under backward Euler the solve's penalty springs (implicit/ball_contact.py) take part of the
approach speed first, so restitution reflects only what is left: a 10 kg ball hitting a free
2 kg point at 3 m/s with e = 0.5 separates at 1.0 m/s rather than 1.5.

The surface pairs come from proximity.surface_pairs, searched SKIN thinnest thicknesses beyond
contact, and are kept until the surface particles have moved apart by half the skin since (a
Verlet list; moving together does not count: list_holds): a step where nothing touches costs
a pass over the surface particles (two where the displacements' box is too large to
decide). Where they have moved apart (a cloth that swings turns by degrees a step at large
steps), renewed_surface_pairs tries, cheapest first:
- one self-colliding sheet (a cloth alone, or with balls) that lies unfolded has no pair of
  its own within reach, proven from its projection on its mean normal
  (unfolded_sheet.lies_unfolded: 0.5 ms on the 100 x 100 cloth against 9 to 12 ms for a
  search, 40 us on cloth-balls's against 560): the list is then empty, as the search's would be;
- a list at most RIGID_CHECK_STEPS steps old is still kept if the motion since is rigid piece
  by piece: within half the skin of a rigid fit in every window of the finest grid, and within
  more in coarser ones, for farther pairs (rigid_pieces.moved_rigidly, which does what the
  spread does with a rotation per window of the surface). An older list is searched again
  instead: where the spread keeps a list for long, a search costs less than checking every
  step past that;
- where the sheet lies unfolded within its bare thickness (not the skin too), an empty list
  for that step alone (unfolded_now_or_searched);
- else a search.
The 100 x 100 cloth-hang at 1/60 s searched at 193 of its first 199 steps with the spread alone,
at 111 with the rigid check, at 18 with the unfolded sheet first (where its free corner turns
over), and at none with the proof within the bare thickness as well.
A list found afresh gives the same contacts (the narrow phase decides), so results do not
depend on when it was found, with one exception: a point carried through a face by between one
and two rest distances is caught (the side test), but a kept list only promises the pairs
within one rest distance, so whether that point is caught can depend on when the list was
found. The ball pairs are found every
step (broadphase.find_contacts: balls are few and fast).
"""
import math

import numpy as np

from ._jit import inline_kernel, kernel
from .broadphase import find_contacts
from .geometry import closest_on_segments, closest_on_triangle, triangle_normal
from .proximity import surface_pairs
from .rigid_pieces import moved_rigidly
from .unfolded_sheet import lies_unfolded

PASSES = 8          # Jacobi passes of the velocity impulses per step
CORRECTION = 0.5    # share of an overlap removed per step
BALL_PASSES = 1     # Jacobi passes of a ball's contacts (see the module doc)
PARAMS = 6          # numbers per contact: restitution, kinetic and static friction, share of
                    # the depth corrected, share of a stuck sliding taken back, passes
SKIN = 2.0          # the search reaches this many times the thinnest surface beyond contact
RIGID_CHECK_STEPS = 8   # a list is checked for piecewise rigid motion up to this many steps old


@kernel
def surface_skin(model):
    """How far beyond contact the pair search reaches (m): SKIN times the thinnest surface."""
    return skin_of(model.body_thickness)


@kernel
def skin_of(thickness):
    """SKIN times the thinnest of the bodies' ``thickness`` (m; zero: no surface)."""
    thinnest = np.inf
    for b in range(thickness.shape[0]):
        if thickness[b] > 0.0:
            thinnest = min(thinnest, thickness[b])
    return SKIN * thinnest


@kernel
def no_surface_pairs(model, x):
    """The pair list of a model without surface contact (or before the first search)."""
    return (np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), np.empty((0, 3)),
            np.zeros(1, np.int64))


@kernel
def start_surface_pairs(model, x):
    """The pair list for the state x: (point-triangle pairs, edge-edge pairs, the positions
    when they were found, how many steps it has been kept since: [0])."""
    if model.surface_triangles.shape[0] == 0:
        return no_surface_pairs(model, x)
    skin = surface_skin(model)
    if sheet_lies_unfolded(model, x, skin):   # the search would find nothing
        return no_pairs_at(x)
    return unfolded_now_or_searched(model, x, skin)


@inline_kernel
def pairs_at(model, x, pairs):
    """The pair list at x: ``pairs`` while it still holds there (``list_holds``), else one
    renewed there (``renewed_surface_pairs``; NaN too: a search copes with it). The one rule for
    a list after a step, at a call's start and at a Newton estimate, so that all three agree.
    Inlined: where the list holds, no call takes the model."""
    if list_holds(model.surface_points, model.body_thickness, x, pairs[2]):
        return pairs
    return renewed_surface_pairs(model, x, pairs)


@kernel
def renewed_surface_pairs(model, x, pairs):
    """The pair list at x once the spread no longer keeps ``pairs`` (list_holds): none where
    the sheet lies unfolded (the cheaper proof), ``pairs`` where the motion since was rigid by
    pieces and the list is at most RIGID_CHECK_STEPS steps old, else
    ``unfolded_now_or_searched``."""
    skin = surface_skin(model)
    if sheet_lies_unfolded(model, x, skin):
        return no_pairs_at(x)
    if pairs[3][0] <= RIGID_CHECK_STEPS \
            and moved_rigidly(model.surface_points, model.surface_edges, model.body_thickness,
                              skin, x, pairs[2]):
        return pairs
    return unfolded_now_or_searched(model, x, skin)


@kernel
def unfolded_now_or_searched(model, x, skin):
    """None for this step alone where the sheet lies unfolded within its bare thickness (the
    contacts at x need no more: no_pairs_this_step), else a fresh search ``skin`` beyond
    contact. Why: a swinging, rippling cloth crowds its projection somewhere once the reach
    holds the skin too (the 100 x 100 cloth-hang's turned-over corner, steps 152 to 176,
    rings at 0.75 to 0.88 of it), and each of those steps searched (9 to 12 ms, finding
    nothing) where its proof within the thickness alone holds. Why not within two thicknesses,
    as far as the narrow phase catches a point carried through a face: 10 of those 18 steps
    fail that (measured), while a sheet whose projection is one to one has no edge through any
    of its triangles at x, nothing to push back; the list promises what a kept one does
    (module doc)."""
    if sheet_lies_unfolded(model, x, 0.0):
        return no_pairs_this_step(x)
    return searched_surface_pairs(model, x, skin)


@kernel
def no_pairs_at(x):
    """An empty pair list found at x."""
    return (np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), x.copy(),
            np.zeros(1, np.int64))


@kernel
def no_pairs_this_step(x):
    """An empty pair list for the contacts at x alone: no pair is within its rest distance
    there, but none is promised beyond it, so nothing may keep it: its positions are NaN
    (list_holds fails on them) and its age is past the rigid check's."""
    return (np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), np.full_like(x, np.nan),
            np.full(1, RIGID_CHECK_STEPS + 1, np.int64))


@kernel
def searched_surface_pairs(model, x, skin):
    """The pair list of a search at x, ``skin`` beyond contact."""
    points, edges = surface_pairs(model, x, skin, skin)
    return points, edges, x.copy(), np.zeros(1, np.int64)


@kernel
def sheet_lies_unfolded(model, x, skin):
    """Whether one self-colliding sheet is the only surface and has no pair within its
    thickness plus ``skin`` at x (unfolded_sheet.py; False without such a sheet)."""
    return lies_unfolded(model.surface_triangles, model.sheet_ring_start, model.sheet_ring_edges,
                         model.sheet_boundary, model.sheet_near_boundary, model.neighbour_start,
                         model.neighbours, x, model.body_thickness.max() + skin)


@kernel
def list_holds(points, thickness, x, then):
    """Whether a pair list found at the positions ``then`` still holds every pair within
    reach: the surface points have moved apart by less than the skin since (``spread_since``;
    NaN fails). First the half diagonal of the displacements' box, which bounds the spread
    from above and takes one pass instead of two; the spread only where that bound is too
    large. Arrays, not the model: it runs every step, and a step where nothing touches is to
    make no call that takes the model's ~50 arrays."""
    allowed = 0.5 * skin_of(thickness)
    low0, low1, low2, high0, high1, high2, total = displacement_box(points, x, then)
    if not abs(total) < np.inf:   # NaN or inf somewhere: min and max may have passed over it
        return False
    if (high0 - low0) ** 2 + (high1 - low1) ** 2 + (high2 - low2) ** 2 <= (2.0 * allowed) ** 2:
        return True
    return spread_about(points, x, then, low0, low1, low2, high0, high1, high2) <= allowed


@kernel
def spread_since(points, now, then):
    """max_k |d_k - c| over the points, d_k = now - then, c the middle of the d's box (m); NaN
    if any is, which keeps no list. Two points' distance changes by at most |d_p - d_q|, which
    is at most twice this for any c: with c the middle of the displacements, a cloth or a body
    that moves as a whole keeps its pair list. (Scalars, not small arrays, in the loops: this
    runs every step, and it is the whole cost of contact where nothing touches.)"""
    low0, low1, low2, high0, high1, high2, total = displacement_box(points, now, then)
    if not abs(total) < np.inf:   # min and max may have passed over a NaN
        return np.nan
    return spread_about(points, now, then, low0, low1, low2, high0, high1, high2)


@kernel
def displacement_box(points, now, then):
    """The box of the displacements d_k = now - then over the points (low x, y, z, high x, y,
    z), and the sum of all their components (NaN or inf if any is)."""
    low0 = low1 = low2 = np.inf
    high0 = high1 = high2 = -np.inf
    total = 0.0
    for p in points:
        d0, d1, d2 = now[p, 0] - then[p, 0], now[p, 1] - then[p, 1], now[p, 2] - then[p, 2]
        low0, high0 = min(low0, d0), max(high0, d0)
        low1, high1 = min(low1, d1), max(high1, d1)
        low2, high2 = min(low2, d2), max(high2, d2)
        total += d0 + d1 + d2
    return low0, low1, low2, high0, high1, high2, total


@kernel
def spread_about(points, now, then, low0, low1, low2, high0, high1, high2):
    """max_k |d_k - c|, c the middle of the displacements' box (displacement_box)."""
    c0, c1, c2 = 0.5 * (low0 + high0), 0.5 * (low1 + high1), 0.5 * (low2 + high2)
    farthest = 0.0
    for p in points:
        apart = ((now[p, 0] - then[p, 0] - c0) ** 2 + (now[p, 1] - then[p, 1] - c1) ** 2
                 + (now[p, 2] - then[p, 2] - c2) ** 2)
        farthest = max(farthest, apart)
    return math.sqrt(farthest)


@inline_kernel
def resolve_contacts(model, x, v, start, pairs):
    """Apply every body-body contact of (x, v) in place (module doc): those of the surface pair
    list and those of the balls; ``start`` holds the positions at the start of the step.
    Returns the surface list for the next step: ``pairs``, or a renewed one once it no longer
    holds (``list_holds``, ``renewed_surface_pairs``). Inlined, with the model passed on only
    where there is a search or a contact: a step where nothing touches makes no call that takes
    the model."""
    if model.surface_triangles.shape[0] > 0:
        pairs[3][0] += 1   # the steps it has been kept
        pairs = pairs_at(model, x, pairs)
    balls = ball_pairs(x, model.radius, model.balls, model.ball_slot)
    if pairs[0].shape[0] + pairs[1].shape[0] + balls.shape[0] > 0:
        respond_to_contacts(model, x, v, start, pairs[0], pairs[1], balls)
    return pairs


@kernel
def ball_pairs(x, radius, balls, ball_slot):
    """The (ball, partner) pairs that overlap (broadphase.find_contacts; none without balls)."""
    if balls.shape[0] == 0:
        return np.empty((0, 2), np.int64)
    return find_contacts(x, radius, balls, ball_slot)


@kernel
def respond_to_contacts(model, x, v, start, point_pairs, edge_pairs, balls):
    """The touching pairs' impulses and overlap corrections (module doc)."""
    contacts = touching_contacts(model, x, start, point_pairs, edge_pairs, balls)
    if contacts[0].shape[0] > 0:
        mobility = split_mobilities(model.inv_mass, contacts[0], contacts[1])
        stuck = apply_impulses(model.inv_mass, v, contacts, mobility)
        correct_overlaps(model.inv_mass, x, start, contacts, stuck, mobility)


@inline_kernel
def touching_contacts(model, x, start, point_pairs, edge_pairs, balls):
    """The touching pairs as stencils: (nodes (K, 4), weights c (K, 4), normal n (K, 3),
    depth (K,), their parameters (K, PARAMS): restitution, kinetic and static friction, the
    share of the depth corrected a step and the share of a stuck contact's sliding in the step
    taken back). Surfaces first (point-triangle, edge-edge), then balls."""
    capacity = point_pairs.shape[0] + edge_pairs.shape[0] + balls.shape[0]
    nodes = np.empty((capacity, 4), np.int64)
    weights = np.empty((capacity, 4))
    normal = np.empty((capacity, 3))
    depth = np.empty(capacity)
    params = np.empty((capacity, PARAMS))
    bodies = np.empty((1, 2), np.int64)   # the touching pair's bodies, from the tests
    corners = np.empty((3, 3))   # work space of closest_on_triangle
    triangles, edges = model.surface_triangles, model.surface_edges
    body, thickness = model.particle_body, model.body_thickness
    # the arrays read in the loops, taken from the model once (each read of one from the model
    # inside them cost about 20 ns a contact)
    surface_keys = surface_contact_keys(model)
    ball_keys = (model.radius, model.ball_slot, model.ball_restitution,
                 model.particle_restitution, model.particle_friction, model.position_correction)
    count = 0
    for k in range(point_pairs.shape[0]):
        if point_triangle_contact(triangles, body, thickness, x, start, point_pairs[k, 0],
                                  point_pairs[k, 1], count, nodes, weights, normal, depth,
                                  bodies, corners):
            surface_params(surface_keys, bodies[0, 0], bodies[0, 1], params[count])
            count += 1
    for k in range(edge_pairs.shape[0]):
        if edge_edge_contact(edges, body, thickness, x, start, edge_pairs[k, 0],
                             edge_pairs[k, 1], count, nodes, weights, normal, depth, bodies):
            surface_params(surface_keys, bodies[0, 0], bodies[0, 1], params[count])
            count += 1
    for k in range(balls.shape[0]):
        if ball_contact(ball_keys, x, balls[k, 0], balls[k, 1], count, nodes, weights, normal,
                        depth, params):
            count += 1
    return nodes[:count], weights[:count], normal[:count], depth[:count], params[:count]


@inline_kernel
def surface_contact_keys(model):
    """The bodies' restitution, kinetic and static friction (surface_params reads them)."""
    return model.body_restitution, model.body_friction, model.body_static_friction


@inline_kernel
def surface_params(keys, first, second, out):
    """A surface contact's parameters between bodies ``first`` and ``second`` (the means of
    their ``keys``, surface_contact_keys; CORRECTION of the depth a step; a stuck contact's
    sliding all taken back) into ``out`` (PARAMS,)."""
    restitution, kinetic, static = keys
    out[0] = 0.5 * (restitution[first] + restitution[second])
    out[1] = 0.5 * (kinetic[first] + kinetic[second])
    out[2] = 0.5 * (static[first] + static[second])
    out[3] = CORRECTION
    out[4] = 1.0
    out[5] = PASSES


@inline_kernel
def ball_contact(keys, x, a, b, row, nodes, weights, normal, depth, params):
    """Fill contact ``row`` for ball a and particle (or ball) b if they overlap: the stencil
    (1, -1) along n, the unit vector from b to a, depth r_a + r_b - |x_a - x_b|. ``keys``: the
    model's radius, ball_slot and ball tables (touching_contacts)."""
    radius, ball_slot, ball_restitution, particle_restitution, particle_friction, correction = keys
    dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    overlap = radius[a] + radius[b] - distance
    if not overlap > 0.0:
        return False
    if distance > 0.0:
        normal[row, 0] = dx / distance
        normal[row, 1] = dy / distance
        normal[row, 2] = dz / distance
    else:   # concentric: any direction separates them; choose up
        normal[row, 0], normal[row, 1], normal[row, 2] = 0.0, 1.0, 0.0
    nodes[row, 0], nodes[row, 1], nodes[row, 2], nodes[row, 3] = a, b, b, b
    weights[row, 0], weights[row, 1], weights[row, 2], weights[row, 3] = 1.0, -1.0, 0.0, 0.0
    depth[row] = overlap
    ball, other = ball_slot[a], ball_slot[b]
    # every key read whichever kind the pair is, and the kind chosen among numbers: reading an
    # array inside the branch kept its reference counting in the loop (43 ns a contact, not 9)
    partner = other if other >= 0 else ball
    mean_restitution = 0.5 * (ball_restitution[ball] + ball_restitution[partner])
    mean_correction = 0.5 * (correction[ball] + correction[partner])
    restitution, friction, shared = (particle_restitution[ball], particle_friction[ball],
                                     correction[ball])
    if other >= 0:   # ball-ball: the means of both balls' keys, no friction
        restitution, friction, shared = mean_restitution, 0.0, mean_correction
    params[row, 0] = restitution
    params[row, 1] = params[row, 2] = friction
    params[row, 3] = shared
    params[row, 4] = 0.0   # friction on the velocities only, as the reference's balls
    params[row, 5] = BALL_PASSES
    return True


@inline_kernel
def point_triangle_contact(triangles, body, thickness, x, start, p, t, row, nodes, weights,
                           normal, depth, bodies, corners):
    """Fill contact ``row`` for point p and triangle t if they touch (module doc)."""
    a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    rest = 0.5 * (thickness[body[p]] + thickness[body[a]])
    for i in range(3):   # most listed pairs are further apart: a cheap test first
        if not (min(x[a, i], x[b, i], x[c, i]) - 2.0 * rest < x[p, i]
                < max(x[a, i], x[b, i], x[c, i]) + 2.0 * rest):
            return False
    for i in range(3):
        corners[0, i], corners[1, i], corners[2, i] = x[a, i], x[b, i], x[c, i]
    w0, w1, w2 = closest_on_triangle(x[p], corners)
    d0 = x[p, 0] - w0 * x[a, 0] - w1 * x[b, 0] - w2 * x[c, 0]
    d1 = x[p, 1] - w0 * x[a, 1] - w1 * x[b, 1] - w2 * x[c, 1]
    d2 = x[p, 2] - w0 * x[a, 2] - w1 * x[b, 2] - w2 * x[c, 2]
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
    nodes[row, 0], nodes[row, 1], nodes[row, 2], nodes[row, 3] = p, a, b, c
    weights[row, 0], weights[row, 1], weights[row, 2], weights[row, 3] = 1.0, -w0, -w1, -w2
    normal[row, 0], normal[row, 1], normal[row, 2] = n0, n1, n2
    depth[row] = rest - gap
    bodies[0, 0], bodies[0, 1] = body[p], body[a]
    return True


@inline_kernel
def edge_edge_contact(edges, body, thickness, x, start, e, f, row, nodes, weights, normal, depth,
                      bodies):
    """Fill contact ``row`` for edges e and f if they touch between their ends (where an end is
    closest, the point-triangle contacts of the faces beside it decide)."""
    a, b, c, q = edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]
    rest = 0.5 * (thickness[body[a]] + thickness[body[c]])
    for i in range(3):   # most listed pairs are further apart: a cheap test first
        if max(x[a, i], x[b, i]) + rest < min(x[c, i], x[q, i]) \
                or max(x[c, i], x[q, i]) + rest < min(x[a, i], x[b, i]):
            return False
    s, t = closest_on_segments(x[a], x[b], x[c], x[q])
    if not (0.0 < s < 1.0 and 0.0 < t < 1.0):
        return False
    d0 = (1.0 - s) * x[a, 0] + s * x[b, 0] - (1.0 - t) * x[c, 0] - t * x[q, 0]
    d1 = (1.0 - s) * x[a, 1] + s * x[b, 1] - (1.0 - t) * x[c, 1] - t * x[q, 1]
    d2 = (1.0 - s) * x[a, 2] + s * x[b, 2] - (1.0 - t) * x[c, 2] - t * x[q, 2]
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
    nodes[row, 0], nodes[row, 1], nodes[row, 2], nodes[row, 3] = a, b, c, q
    weights[row, 0], weights[row, 1] = 1.0 - s, s
    weights[row, 2], weights[row, 3] = -(1.0 - t), -t
    normal[row, 0] = sign * d0 / distance
    normal[row, 1] = sign * d1 / distance
    normal[row, 2] = sign * d2 / distance
    depth[row] = rest - sign * distance
    bodies[0, 0], bodies[0, 1] = body[a], body[c]
    return True


@kernel
def split_mobilities(inv_mass, nodes, weights):
    """(K,) W = sum_i c_i^2 n_i / m_i, each particle's mass split among the n_i contacts it
    takes part in (module doc)."""
    count = np.zeros(inv_mass.shape[0], np.int32)
    for k in range(nodes.shape[0]):
        for i in range(4):
            if weights[k, i] != 0.0:   # a ball's stencil pads its two nodes with zeros
                count[nodes[k, i]] += 1
    mobility = np.empty(nodes.shape[0])
    for k in range(nodes.shape[0]):
        total = 0.0
        for i in range(4):
            total += weights[k, i] ** 2 * inv_mass[nodes[k, i]] * count[nodes[k, i]]
        mobility[k] = total
    return mobility


@kernel
def apply_impulses(inv_mass, v, contacts, mobility):
    """The Jacobi passes of normal and friction impulses (module doc; each contact takes part in
    params[k, 5] of them; ``mobility``: split_mobilities); returns which contacts stuck (static
    friction held them) in their last pass."""
    return impulse_passes(inv_mass, v, contacts, mobility, np.zeros(contacts[0].shape[0]), True)


@kernel
def apply_friction(inv_mass, v, contacts, pushed):
    """The friction passes of ``apply_impulses`` alone, each contact's normal impulse given
    (``pushed``, N s: implicit_euler's penalty contacts push inside the solve,
    implicit/contact_friction.py); returns which stuck."""
    mobility = split_mobilities(inv_mass, contacts[0], contacts[1])
    return impulse_passes(inv_mass, v, contacts, mobility, pushed, False)   # never writes pushed


@kernel
def impulse_passes(inv_mass, v, contacts, mobility, pushed, push):
    """Jacobi passes, as many as the contact that takes most (params[:, 5]): friction against
    the accumulated normal impulse ``pushed``, plus, if ``push``, the normal impulses that stop
    each approach (adding to ``pushed``)."""
    nodes, weights, normal, depth, params = contacts
    count = nodes.shape[0]
    stuck = np.zeros(count, np.bool_)
    impulse = np.zeros((count, 3))      # this pass's, per contact
    rubbed = np.zeros((count, 3))       # friction impulse applied so far
    target = np.zeros(count)            # normal velocity wanted: -e (first approach), or 0
    relative = np.empty(3)
    passes = 0
    for k in range(count):
        passes = max(passes, int(params[k, 5]))
    for sweep in range(passes):
        for k in range(count):
            impulse[k, 0] = impulse[k, 1] = impulse[k, 2] = 0.0
            if not (mobility[k] > 0.0 and sweep < params[k, 5]):
                continue   # every particle of the stencil pinned, or its passes done
            for c in range(3):
                relative[c] = 0.0
                for i in range(4):
                    relative[c] += weights[k, i] * v[nodes[k, i], c]
            approach = relative[0] * normal[k, 0] + relative[1] * normal[k, 1] \
                + relative[2] * normal[k, 2]
            j = 0.0
            if push:
                if sweep == 0:
                    target[k] = -params[k, 0] * min(approach, 0.0)   # restitution
                j = max(target[k] - approach, 0.0) / mobility[k]
                pushed[k] += j
            stuck[k] = friction_impulse(k, params, relative, approach, normal, mobility[k],
                                        pushed[k], rubbed, impulse)
            for c in range(3):
                impulse[k, c] += j * normal[k, c]
        for k in range(count):
            for i in range(4):
                share = weights[k, i] * inv_mass[nodes[k, i]]
                for c in range(3):
                    v[nodes[k, i], c] += share * impulse[k, c]
    return stuck


@inline_kernel
def friction_impulse(k, params, relative, approach, normal, mobility, pushed, rubbed, impulse):
    """Set impulse[k] to this pass's friction: the change of the accumulated friction ``rubbed``
    that stops the sliding, kept within the static friction (params[k, 2]) x ``pushed`` or else
    cut to the kinetic (params[k, 1]) x ``pushed`` (Coulomb; ``mobility`` is the split W).
    Returns whether it sticks (never without friction)."""
    kinetic, static = params[k, 1], params[k, 2]
    w0 = rubbed[k, 0] - (relative[0] - approach * normal[k, 0]) / mobility
    w1 = rubbed[k, 1] - (relative[1] - approach * normal[k, 1]) / mobility
    w2 = rubbed[k, 2] - (relative[2] - approach * normal[k, 2]) / mobility
    size = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    sticks = size <= static * pushed
    if not sticks:
        cut = kinetic * pushed / size
        w0, w1, w2 = w0 * cut, w1 * cut, w2 * cut
    impulse[k, 0], impulse[k, 1], impulse[k, 2] = (w0 - rubbed[k, 0], w1 - rubbed[k, 1],
                                                   w2 - rubbed[k, 2])
    rubbed[k, 0], rubbed[k, 1], rubbed[k, 2] = w0, w1, w2
    return sticks and static > 0.0   # a frictionless contact has no sliding to take back


@kernel
def correct_overlaps(inv_mass, x, start, contacts, stuck, mobility):
    """Move each touching stencil apart by its share of its depth (params[k, 3]), and take back
    params[k, 4] of the sliding of a stuck one during the step (all for surfaces, none for
    balls), shared like the impulses (module doc). All shifts are found from the same positions
    before any is made (Jacobi, as the impulses)."""
    nodes, weights, normal, depth, params = contacts
    shift = np.zeros((nodes.shape[0], 3))
    for k in range(nodes.shape[0]):
        if not mobility[k] > 0.0:
            continue
        push = params[k, 3] * max(depth[k], 0.0)   # the contact's share of its depth
        for c in range(3):
            shift[k, c] = push * normal[k, c]
        if stuck[k] and params[k, 4] > 0.0:
            slid0 = slid1 = slid2 = 0.0
            for i in range(4):
                n = nodes[k, i]
                slid0 += weights[k, i] * (x[n, 0] - start[n, 0])
                slid1 += weights[k, i] * (x[n, 1] - start[n, 1])
                slid2 += weights[k, i] * (x[n, 2] - start[n, 2])
            along = slid0 * normal[k, 0] + slid1 * normal[k, 1] + slid2 * normal[k, 2]
            back = params[k, 4]
            shift[k, 0] -= back * (slid0 - along * normal[k, 0])
            shift[k, 1] -= back * (slid1 - along * normal[k, 1])
            shift[k, 2] -= back * (slid2 - along * normal[k, 2])
        for c in range(3):
            shift[k, c] /= mobility[k]
    for k in range(nodes.shape[0]):
        for i in range(4):
            share = weights[k, i] * inv_mass[nodes[k, i]]
            for c in range(3):
                x[nodes[k, i], c] += share * shift[k, c]
