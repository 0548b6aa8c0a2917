"""The check that sends a backward Euler step back to be taken in halves
(collision/ccd/crossing_check.py): did a point pass through a triangle, or an edge past an edge,
during the step? Oracles: straight-line motions whose answer is plain geometry (a point driven
through a triangle's middle passes it; the same motion beside the triangle, short of it, or an edge
turning past a parallel one at a distance does not)."""
import numpy as np
import pytest

from springsim.collision.ccd.crossing_check import edge_passed_edge, point_passed_face

THICKNESS = np.array([0.02])        # one body: the rest distance is 0.02 m
BODY = np.zeros(8, np.int64)
TRIANGLE = np.array([[0, 1, 2]])    # the triangle of particles 0, 1, 2; the point is 3
EDGES = np.array([[0, 1], [2, 3]])  # two edges: particles 0-1 and 2-3


def triangle_and_point(point):
    return np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], point])


def passed_face(point_from, point_to):
    return point_passed_face(TRIANGLE, BODY, THICKNESS, triangle_and_point(point_from),
                             triangle_and_point(point_to), 3, 0, np.empty((4, 3)))


@pytest.mark.parametrize("through", [(0.25, 0.25), (0.1, 0.7), (0.6, 0.3)])
def test_a_point_driven_through_a_triangle_passed_it(through):
    x, z = through
    assert passed_face((x, 0.3, z), (x, -0.05, z))
    assert passed_face((x, -0.3, z), (x, 0.4, z))   # from below, any depth


def test_a_point_driven_past_a_triangle_short_of_it_or_beside_it_did_not_pass():
    assert not passed_face((0.25, 0.3, 0.25), (0.25, 0.001, 0.25))   # stops above it
    assert not passed_face((0.8, 0.3, 0.8), (0.8, -0.3, 0.8))        # beside its long edge
    assert not passed_face((-0.2, 0.3, 0.5), (-0.2, -0.3, 0.5))      # beside its short edge


def test_a_point_that_crossed_the_plane_beside_the_triangle_within_its_reach_passed_it():
    """Within a quarter of the rest distance of an edge is through: contact should have held
    it off there."""
    assert passed_face((0.502, 0.3, 0.502), (0.502, -0.3, 0.502))   # 0.0028 m out
    assert not passed_face((0.51, 0.3, 0.51), (0.51, -0.3, 0.51))   # 0.014 m out


def test_a_triangle_moving_through_a_resting_point_passed_it():
    """Only the relative motion counts: the triangle swept down through the point."""
    start = triangle_and_point((0.25, 0.0, 0.25))
    end = start.copy()
    start[:3, 1] += 0.1
    end[:3, 1] -= 0.1
    assert point_passed_face(TRIANGLE, BODY, THICKNESS, start, end, 3, 0, np.empty((4, 3)))


def edges_passed(start, end):
    return edge_passed_edge(EDGES, BODY, THICKNESS, np.array(start, float),
                            np.array(end, float), 0, 1, np.empty((4, 3)))


def test_an_edge_swept_across_another_passed_it():
    fixed = [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]
    assert edges_passed(fixed + [[0.1, 0.2, -0.5], [0.1, 0.2, 0.5]],
                        fixed + [[0.1, -0.2, -0.5], [0.1, -0.2, 0.5]])


def test_an_edge_swept_past_the_end_of_another_did_not_pass_it():
    fixed = [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]
    assert not edges_passed(fixed + [[0.7, 0.2, -0.5], [0.7, 0.2, 0.5]],
                            fixed + [[0.7, -0.2, -0.5], [0.7, -0.2, 0.5]])


def test_an_edge_turning_past_a_parallel_one_at_a_distance_did_not_pass_it():
    """Turning through parallel flips the sign of the edges' volume, as passing does, but
    where they are coplanar they lie 0.1 m apart, five rest distances."""
    fixed = [[-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]]
    angle = np.radians(10.0)

    def turned(by):
        half = 0.5 * np.array([np.cos(by), 0.0, np.sin(by)])
        return fixed + [list(np.array([0.0, 0.1, 0.0]) - half),
                        list(np.array([0.0, 0.1, 0.0]) + half)]

    assert not edges_passed(turned(angle), turned(-angle))
