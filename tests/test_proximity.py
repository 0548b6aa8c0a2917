"""The surface pair search (collision/broad_phase/surfaces.surface_pairs) against a brute force
over every pair.

Oracle: plain-Python closest-point distances (Ericson, Real-Time Collision Detection, 5.1.5 and
5.1.9) over every (point, triangle) and (edge, edge) pair of scenes of overlapping, crumpled
bodies, with the rules of which pairs count written out again from the README: two bodies
always; one body only if it collides with itself, and then not a point and a triangle with the
point or its neighbour as a corner, nor two edges with an end that is the same or neighbours.
Pairs within 1e-9 m of the search distance are left out of the comparison (round-off).
"""
import numpy as np
import pytest

from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.collision.broad_phase.surfaces import surface_pairs
from springsim.scene import Scene
from springsim.simulation import Simulation

ROUND_OFF = 1e-9


def closest_on_triangle(p, a, b, c):
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = ab @ ap, ac @ ap
    if d1 <= 0 and d2 <= 0:
        return a
    bp = p - b
    d3, d4 = ab @ bp, ac @ bp
    if d3 >= 0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0 and d1 >= 0 and d3 <= 0:
        return a + d1 / (d1 - d3) * ab
    cp = p - c
    d5, d6 = ab @ cp, ac @ cp
    if d6 >= 0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0 and d2 >= 0 and d6 <= 0:
        return a + d2 / (d2 - d6) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
    denominator = 1.0 / (va + vb + vc)
    return a + ab * vb * denominator + ac * vc * denominator


def segment_distance(p1, q1, p2, q2):
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f = d1 @ d1, d2 @ d2, d2 @ r
    c, b = d1 @ r, d1 @ d2
    denominator = a * e - b * b
    s = np.clip((b * f - c * e) / denominator, 0, 1) if denominator > 1e-30 else 0.0
    t = (b * s + f) / e
    if t < 0:
        t, s = 0.0, np.clip(-c / a, 0, 1)
    elif t > 1:
        t, s = 1.0, np.clip((b - c) / a, 0, 1)
    return np.linalg.norm(p1 + d1 * s - (p2 + d2 * t))


def crumpled_scene(seed):
    """A self-colliding 6 x 6 cloth and two 3^3 cubes, one self-colliding, all overlapping,
    every particle moved by up to a third of a metre: folds, contacts and passings."""
    rng = np.random.default_rng(seed)
    bodies = [Cloth(particles_per_edge=6, width=1.0, height=1.0, thickness=0.05),
              Cube(particles_per_edge=3, edge_length=0.8, position=(0.2, 0.1, 0.0),
                   thickness=0.08),
              Cube(particles_per_edge=3, edge_length=0.6, position=(-0.2, -0.1, 0.3),
                   thickness=0.03, self_collision=True)]
    simulation = Simulation(Scene(bodies=bodies, terrains=[], dt=1e-3))
    x = simulation.positions + rng.uniform(-0.33, 0.33, simulation.positions.shape)
    return simulation.model.arrays, x


def brute_force(model, x, beyond, self_beyond):
    """The pairs that count and are closer than their search distance, and those within
    round-off of it (left out of the comparison)."""
    body, thickness = model.particle_body, model.body_thickness
    neighbours = {int(p): set() for p in model.surface_points}
    for a, b in model.surface_edges:
        neighbours[int(a)].add(int(b))
        neighbours[int(b)].add(int(a))

    def search(p, q):
        own = body[p] == body[q]
        return 0.5 * (thickness[body[p]] + thickness[body[q]]) + (self_beyond if own else beyond)

    def counts(ends_one, ends_other):
        if body[ends_one[0]] != body[ends_other[0]]:
            return True
        if not model.body_self_collision[body[ends_one[0]]]:
            return False
        return not any(p == q or q in neighbours[int(p)] for p in ends_one for q in ends_other)

    points, edges, unsure = set(), set(), set()
    for p in model.surface_points:
        for t, corners in enumerate(model.surface_triangles):
            if not counts([p], corners):
                continue
            gap = np.linalg.norm(x[p] - closest_on_triangle(x[p], *x[corners]))
            limit = search(p, corners[0])
            if abs(gap - limit) < ROUND_OFF:
                unsure.add(("point", int(p), t))
            elif gap < limit:
                points.add((int(p), t))
    all_edges = model.surface_edges
    for e in range(len(all_edges)):
        for f in range(e + 1, len(all_edges)):
            if not counts(all_edges[e], all_edges[f]):
                continue
            gap = segment_distance(*x[all_edges[e]], *x[all_edges[f]])
            limit = search(all_edges[e][0], all_edges[f][0])
            if abs(gap - limit) < ROUND_OFF:
                unsure.add(("edge", e, f))
            elif gap < limit:
                edges.add((e, f))
    return points, edges, unsure


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("beyond, self_beyond", [(0.1, 0.1), (0.05, 0.2), (0.2, -np.inf)])
def test_the_grid_finds_exactly_the_pairs_of_a_brute_force(seed, beyond, self_beyond):
    model, x = crumpled_scene(seed)
    points, edges = surface_pairs(model, x, beyond, self_beyond)
    expected_points, expected_edges, unsure = brute_force(model, x, beyond, self_beyond)
    found_points = {tuple(map(int, pair)) for pair in points}
    found_edges = {tuple(map(int, pair)) for pair in edges}
    unsure_points = {(p, t) for kind, p, t in unsure if kind == "point"}
    unsure_edges = {(e, f) for kind, e, f in unsure if kind == "edge"}
    assert found_points - unsure_points == expected_points
    assert found_edges - unsure_edges == expected_edges
    assert len(expected_points) > 20 and len(expected_edges) > 20   # the scene does touch
    # one canonical order: sorted by (point, triangle) and (lower edge, higher edge)
    assert np.array_equal(points, points[np.lexsort((points[:, 1], points[:, 0]))])
    assert np.array_equal(edges, edges[np.lexsort((edges[:, 1], edges[:, 0]))])
    assert np.all(edges[:, 0] < edges[:, 1])
