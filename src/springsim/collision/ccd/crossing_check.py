"""A backward Euler step that carries a surface through another is taken again in halves.

The solve's contacts are penalty springs (pair_lists/solve_pairs.py, pair_lists/own_pairs.py):
stiff, but not hard. A heavy load met within one large step can press them past what they hold:
a heavy cube dropped fast onto a cloth folded in half pushes the top layer through the bottom one
at its corners at frame-sized steps, and not at steps a few times shorter
(benchmarks/folded_cloth_press.py prints how often). So each step is checked for what the post-step
pass cannot undo, a surface carried through another (``carried_through``), and where it finds one,
the step is taken again from its start as two steps of half the size, each checked the same way
(after a half that passes, the steps grow back), down to 1 / 2^MOST_HALVINGS of the step. Where
even that crosses (a cloth already tangled, passing out as well as in, or a load the contacts
cannot hold at any step), halving does not help, and the step is taken whole from its start, as it
would be without the check (a heavy cube carried on from a crossed part instead threw itself up,
where taken whole it stays down, crossed as it was without the check). So a step never loops, and
one that halving cannot help ends as without it (but for the solve's own pair list,
pair_lists/solve_pairs.py, which a rejected part may have renewed and which is not put back: a list
kept longer only holds more candidates, farther than the solve's reach), at the cost of the parts
it tried: seven steps' work where no part passes, more where some pass before one fails. A step
that crosses nothing is taken as before, bit for bit, at the cost of the check over the pairs in
reach and of copying the state it started from.

What the check sees: the pairs of the surface lists at the step's end (the solve's, which holds
the pairs of two bodies the step could bring together, and for a self-colliding body the
post-step pass's, which holds its own pairs within reach there). The four points of a pair are
taken to move linearly from the step's start to its end; where the volume they span changes sign
they were coplanar during the step (the moment found by bisection), and if there the point lies
within PASS_TOLERANCE of its rest distance of the triangle (or the edges of each other) it
passed through. Edges turning past parallel at a distance, a point passing beside a triangle, a
pair crossed at the start that stays crossed: none of these counts (a pair crossed at the start
that passes back out does, so a tangled cloth pays for halvings that cannot help). Not seen: a
pass through and back within one step (the volume's sign is the same at both ends), a pair whose
volume changes sign more than once (the bisection finds one of the moments), a pair carried out
of the lists' reach by the end of the step (beyond its rest distance plus the skin,
pair_lists/keeping.py), and neighbours along a surface edge, which self-contact leaves out (a
cloth folded sharply along a line can still cross itself there under a fast, heavy load).
"""
import numpy as np

from ..._jit import kernel
from ..narrow_phase.stencils import edge_distance, point_triangle_distance
from ..pair_lists import EDGES, POINTS
from ..pair_lists.keeping import pairs_at
from ..pair_lists.own_pairs import any_self_collision


MOST_HALVINGS = 6   # a step is cut into parts down to 1 / 2^MOST_HALVINGS of it
PASS_TOLERANCE = 0.25   # of the rest distance: how near, where coplanar, counts as through
BISECTIONS = 30   # halvings of the step that find where four points are coplanar
# the four points where they are coplanar, as narrow_phase/stencils.py's distances read them
ONE_TRIANGLE = np.array([[0, 1, 2]])   # a triangle (rows 0, 1, 2) and a point (row 3)
TWO_EDGES = np.array([[0, 1], [2, 3]])


@kernel
def carried_through(model, start, x, pairs, kept):
    """Whether the step from ``start`` to ``x`` carried a point through a triangle or an edge
    past an edge (module doc): a pair of the solve's list ``kept``
    (solve_pairs.kept_surface_pairs) or, for a self-colliding body, of the post-step list
    ``pairs`` where it holds at x, else of one renewed there (only for the check: the step
    hands on its own list, so the post-step pass keeps or renews it as before)."""
    if any_passed(model, start, x, kept.pairs[POINTS], True) \
            or any_passed(model, start, x, kept.pairs[EDGES], False):
        return True
    if not any_self_collision(model):
        return False
    own = pairs_at(model, x, pairs)
    return any_passed(model, start, x, own.points, True) \
        or any_passed(model, start, x, own.edges, False)


@kernel
def any_passed(model, start, x, pairs, point_triangle):
    """Whether a pair of ``pairs`` (point-triangle if ``point_triangle``, else edge-edge) passed
    through during the step (point_passed_face, edge_passed_edge)."""
    at = np.empty((4, 3))   # the work space of both
    for k in range(pairs.shape[0]):
        if point_triangle:
            passed = point_passed_face(model.surface_triangles, model.particle_body,
                                       model.body_thickness, start, x, pairs[k, 0], pairs[k, 1],
                                       at)
        else:
            passed = edge_passed_edge(model.surface_edges, model.particle_body,
                                      model.body_thickness, start, x, pairs[k, 0], pairs[k, 1], at)
        if passed:
            return True
    return False


@kernel
def point_passed_face(triangles, body, thickness, start, x, p, t, corners):
    """Whether point p passed through triangle t during the step (module doc). ``corners``:
    work space (4, 3)."""
    a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
    if not coplanar_between(start, x, a, b, c, p, False, corners):
        return False
    rest = 0.5 * (thickness[body[p]] + thickness[body[a]])
    # its work space is the rows it reads: it copies them onto themselves
    return point_triangle_distance(corners, ONE_TRIANGLE, 3, 0, corners[:3]) \
        < PASS_TOLERANCE * rest


@kernel
def edge_passed_edge(edges, body, thickness, start, x, e, f, ends):
    """Whether edges e and f passed each other during the step (module doc). ``ends``: work
    space (4, 3)."""
    a, b, c, q = edges[e, 0], edges[e, 1], edges[f, 0], edges[f, 1]
    if not coplanar_between(start, x, a, b, c, q, True, ends):
        return False
    rest = 0.5 * (thickness[body[a]] + thickness[body[c]])
    return edge_distance(ends, TWO_EDGES, 0, 1) < PASS_TOLERANCE * rest


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
