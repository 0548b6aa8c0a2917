"""The crossing counter of tests/crossings.py on configurations whose answer is known by hand."""
import time

import numpy as np

from crossings import count_crossings, crossing_pairs, mesh_edges


def pierced_pair(shift=0.0):
    """Triangle A flat in z = 0; triangle B in the plane x = y, standing through A's interior
    (its vertical edge meets A at (0.25, 0.25, 0), and A's edge (1,0,0)-(0,1,0) meets B at
    (0.5, 0.5, 0)): two crossings. ``shift`` moves B along z."""
    x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0],
                  [0.25, 0.25, -1], [0.25, 0.25, 1], [2, 2, 0]], float)
    x[3:, 2] += shift
    return x, np.array([[0, 1, 2]]), np.array([[3, 4, 5]])


def test_two_triangles_that_pierce_each_other_cross_twice():
    x, a, b = pierced_pair()
    assert count_crossings(x, np.concatenate([a, b])) == 2
    assert count_crossings(x, a, b) == 2
    pairs = crossing_pairs(x, np.concatenate([a, b]))
    edges = mesh_edges(np.concatenate([a, b]))
    found = {(tuple(edges[e]), t) for e, t in pairs}
    assert found == {((3, 4), 0), ((1, 2), 1)}


def test_moved_apart_or_touching_only_at_a_corner_they_do_not_cross():
    x, a, b = pierced_pair(shift=1.5)   # B entirely above A
    assert count_crossings(x, np.concatenate([a, b])) == 0
    x, a, b = pierced_pair(shift=1.0)   # B's lowest vertex (0.25, 0.25, 0) touches A's face
    assert count_crossings(x, np.concatenate([a, b])) == 0
    # a fan of triangles sharing vertices never counts against itself
    fan = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], float)
    assert count_crossings(fan, np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])) == 0


def grid(n, size=1.0):
    index = np.arange(n * n).reshape(n, n)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    u, w = np.meshgrid(np.linspace(0, size, n), np.linspace(0, size, n), indexing="ij")
    return np.stack([w.ravel(), np.zeros(n * n), u.ravel()], 1), triangles


def test_a_sheet_folded_through_itself_crosses_and_a_flat_or_stacked_one_does_not():
    x, triangles = grid(10)
    assert count_crossings(x, triangles) == 0
    # a second sheet lying 1 cm above the first: no crossing; pushed through it (tilted so its
    # edges pierce the first sheet's faces): crossings
    other = triangles + 100
    above = x + [0.0, 0.01, 0.0]
    both = np.concatenate([x, above])
    assert count_crossings(both, triangles, other) == 0
    tilted = x.copy()
    tilted[:, 1] = 0.3 * (tilted[:, 0] - 0.5) + 0.01 * tilted[:, 2]
    both = np.concatenate([x, tilted + [0.013, 0.0, 0.007]])
    assert count_crossings(both, triangles, other) > 0
    assert count_crossings(both, np.concatenate([triangles, other])) \
        == count_crossings(both, triangles, other)


def test_a_crumpled_25_by_25_cloth_is_counted_in_well_under_a_second():
    x, triangles = grid(25, 4.0)
    rng = np.random.default_rng(3)
    x = x + rng.normal(scale=0.08, size=x.shape)   # crumpled: many near pairs, some crossings
    assert len(triangles) == 1152 and len(mesh_edges(triangles)) == 1776
    began = time.perf_counter()
    count_crossings(x, triangles)
    assert time.perf_counter() - began < 0.5
