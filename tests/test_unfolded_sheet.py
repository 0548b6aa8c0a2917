"""Oracles of unfolded_sheet.lies_unfolded: where it says a self-colliding sheet has no pair of its
own within reach, the pair search itself (collision/broad_phase/surfaces.surface_pairs) finds none;
a flat or gently rippled cloth passes (a grid cloth's ring edges are sqrt(2) spacings away against
a reach of at most 0.75); only a surface that is one oriented disk gets the arrays; and a run that
uses it steps bit for bit as one that searches.
"""
import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.collision.broad_phase.surfaces import surface_pairs
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.collision.pair_lists.keeping import sheet_lies_unfolded, surface_skin
from springsim.collision.pair_lists.sheet_arrays import is_disk, no_sheet
from springsim.collision.pair_lists.unfolded_sheet import edges_meet

N = 20   # particles along each edge of the 2 m test cloth: spacing 0.105 m


@pytest.fixture(scope="module")
def cloth():
    """The model arrays and flat positions (the plane y = 0) of a 20 x 20, 2 m self-colliding
    cloth with the default thickness (2 cm: the reach is 6 cm)."""
    simulation = Simulation(Scene(bodies=[Cloth(particles_per_edge=N, width=2.0, height=2.0)],
                                  terrains=[], dt=1e-3))
    return simulation.model.arrays, simulation.positions.copy()


def reach(arrays):
    return arrays.body_thickness.max() + surface_skin(arrays)


def unfolded(arrays, x):
    """The proof as the contact pass asks for it (its own reach: thickness plus skin)."""
    return sheet_lies_unfolded(arrays, x, surface_skin(arrays))


def pair_count(arrays, x, skin=None):
    """The search's pairs within the thickness plus ``skin`` (the contact pass's, by default)."""
    skin = surface_skin(arrays) if skin is None else skin
    points, edges = surface_pairs(arrays, x, skin, skin)
    return len(points) + len(edges)


def shaped(x, ripple, fold_degrees, roll_degrees, twist, turn, jitter, seed):
    """The flat cloth x (in y = 0, centred) rippled (height ``ripple``), rolled in its own plane
    into a ring of ``roll_degrees`` (at 360 its two ends meet), folded about the line z = 0.3
    by ``fold_degrees``, twisted about z (``twist`` radians per metre), turned as a whole and
    its particles moved by up to ``jitter``."""
    y = x - x.mean(axis=0)
    y[:, 1] += ripple * np.sin(2.1 * y[:, 0] + 1.3 * y[:, 2]) * np.cos(1.7 * y[:, 2])
    if roll_degrees >= 1.0:   # x turns about the y axis, z goes out from 0.2 m to 2.2 m
        angle = np.radians(roll_degrees) * (y[:, 0] - y[:, 0].min()) / np.ptp(y[:, 0])
        radius = 0.2 + y[:, 2] - y[:, 2].min()
        y[:, 0], y[:, 2] = radius * np.cos(angle), radius * np.sin(angle)
    far = y[:, 2] > 0.3
    turned = Rotation.from_euler("x", fold_degrees, degrees=True).as_matrix()
    pivot = np.array([0.0, 0.0, 0.3])
    y[far] = (y[far] - pivot) @ turned.T + pivot
    for k in range(len(y)):
        c, s = np.cos(twist * y[k, 2]), np.sin(twist * y[k, 2])
        y[k, 0], y[k, 1] = c * y[k, 0] - s * y[k, 1], s * y[k, 0] + c * y[k, 1]
    y = y @ Rotation.from_euler("xyz", turn, degrees=True).as_matrix().T
    return y + np.random.default_rng(seed).uniform(-jitter, jitter, y.shape)


SLOW_OK = [HealthCheck.too_slow, HealthCheck.function_scoped_fixture]


@settings(max_examples=150, deadline=None, suppress_health_check=SLOW_OK)
@given(ripple=st.floats(0.0, 0.4), fold=st.floats(0.0, 180.0), roll=st.floats(0.0, 400.0),
       twist=st.floats(-2.0, 2.0),
       turn=st.tuples(st.floats(-180, 180), st.floats(-180, 180), st.floats(-180, 180)),
       jitter=st.floats(0.0, 0.02), seed=st.integers(0, 2 ** 16))
@example(ripple=0.0, fold=0.0, roll=355.0, twist=0.0, turn=(0.0, 0.0, 0.0), jitter=0.0, seed=0)
@example(ripple=0.0, fold=178.0, roll=0.0, twist=0.0, turn=(0.0, 0.0, 0.0), jitter=0.0, seed=0)
@example(ripple=0.35, fold=0.0, roll=0.0, twist=0.0, turn=(10.0, 0.0, 0.0), jitter=0.0, seed=0)
def test_an_unfolded_sheet_has_no_pair_within_reach(cloth, ripple, fold, roll, twist, turn,
                                                    jitter, seed):
    """The oracle: wherever the proof passes, the search finds nothing within reach; the same
    within the bare thickness (the proof a step's contacts alone need)."""
    arrays, flat = cloth
    x = shaped(flat, ripple, fold, roll, twist, turn, jitter, seed)
    passed = unfolded(arrays, x)
    passed_bare = sheet_lies_unfolded(arrays, x, 0.0)
    event(f"passed: {passed}, within the thickness: {passed_bare}")
    if passed:
        assert pair_count(arrays, x) == 0
    if passed_bare:
        assert pair_count(arrays, x, skin=0.0) == 0


def test_a_sheet_rolled_until_its_ends_nearly_meet_has_pairs_and_fails(cloth):
    """Rolled in its own plane until its two ends are 2 to 20 cm apart, the cloth has pairs
    between them: every triangle still faces the axis and every particle's ring is clear, so
    only the boundary check can see them."""
    arrays, flat = cloth
    x = shaped(flat, 0.0, 0.0, 355.0, 0.0, (0.0, 0.0, 0.0), 0.0, 0)
    assert pair_count(arrays, x) > 0
    assert not unfolded(arrays, x)
    assert unfolded(arrays, shaped(flat, 0.0, 0.0, 300.0, 0.0, (0.0, 0.0, 0.0), 0.0, 0))


def test_a_sheet_rolled_into_a_spiral_over_itself_fails():
    """A thin cloth (0.5 mm: its rings stay clear) rolled in its own plane into a spiral of 1.1
    turns lies over itself: its boundary crosses itself, which only the crossing check of the
    boundary sees."""
    simulation = Simulation(Scene(bodies=[Cloth(particles_per_edge=N, width=2.0, height=2.0,
                                                 thickness=0.0005)], terrains=[], dt=1e-3))
    arrays, flat = simulation.model.arrays, simulation.positions.copy()
    y = flat - flat.mean(axis=0)
    turn = 2.0 * np.pi * 1.1 * (y[:, 0] - y[:, 0].min()) / np.ptp(y[:, 0])
    radius = 0.3 + 0.25 * turn / (2.0 * np.pi) + 0.2 * (y[:, 2] - y[:, 2].min())
    x = np.stack([radius * np.cos(turn), y[:, 1], radius * np.sin(turn)], axis=1)
    assert pair_count(arrays, x) > 0
    assert not unfolded(arrays, x)


def test_a_sheet_pinched_in_its_middle_has_pairs_and_fails(cloth):
    """Pinched about its centre (each particle drawn in to 1 - 0.75 exp(-(r / 0.3 m)^2) of its
    distance, which keeps every triangle's orientation), the middle's spacing shrinks to a
    quarter, and each particle there comes within reach of the triangles two columns over
    (0.053 m against 0.06), far from the boundary: only the ring check can see them."""
    arrays, flat = cloth
    x = flat - flat.mean(axis=0)
    r = np.hypot(x[:, 0], x[:, 2])
    x[:, [0, 2]] *= (1.0 - 0.75 * np.exp(-(r / 0.3) ** 2))[:, None]
    assert pair_count(arrays, x) > 0
    assert not unfolded(arrays, x)


def test_a_list_proven_within_the_thickness_alone_serves_its_step_and_is_never_kept(cloth):
    """Pinched until pairs lie between the thickness and the thickness plus the skin (no pair
    within the thickness), the cloth fails the proof within the skin and passes it within the
    thickness: the renewed list is then empty, as the search within the thickness is, and
    holds for that step alone. Pinched further, with pairs within the thickness now, the next
    step does not keep it (neither by the spread nor by the rigid check, though the motion is
    small) and renews it with exactly the search's pairs."""
    from springsim.collision.pair_lists.keeping import (list_holds, renewed_surface_pairs,
                                                        start_surface_pairs)
    arrays, flat = cloth

    def pinched(depth):
        x = flat - flat.mean(axis=0)
        r = np.hypot(x[:, 0], x[:, 2])
        x[:, [0, 2]] *= (1.0 - depth * np.exp(-(r / 0.3) ** 2))[:, None]
        return x

    before, now = pinched(0.92), pinched(0.94)
    assert pair_count(arrays, before) > 0 and pair_count(arrays, before, skin=0.0) == 0
    assert pair_count(arrays, now, skin=0.0) > 0
    # so little motion that a list found by a search at ``before`` would be kept
    assert list_holds(arrays.surface_points, arrays.body_thickness, now, before)
    old = start_surface_pairs(arrays, flat)
    listed = renewed_surface_pairs(arrays, before, old)
    assert len(listed.points) == 0 and len(listed.edges) == 0
    assert not list_holds(arrays.surface_points, arrays.body_thickness, now, listed.found_at)
    renewed = renewed_surface_pairs(arrays, now, listed)
    skin = surface_skin(arrays)
    searched_pairs = surface_pairs(arrays, now, skin, skin)
    for got, searched in zip((renewed.points, renewed.edges), searched_pairs):
        assert np.array_equal(got, searched)


def test_boundary_edges_meet_where_they_cross_touch_or_fold_back():
    """edges_meet against the plane's answer: two segments cross, touch, run apart, or (one
    following the other) fold back onto it or turn away."""
    flat = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, -0.5], [0.5, 0.5], [0.5, 0.0], [2.0, 0.0],
                     [0.3, 0.0], [1.0, 1.0]])
    assert edges_meet(flat, 0, 1, 2, 3)        # an X
    assert edges_meet(flat, 0, 1, 2, 4)        # one ends on the other
    assert not edges_meet(flat, 0, 4, 7, 5)    # apart
    assert edges_meet(flat, 0, 1, 1, 6)        # 1 -> 6 runs back along 0 -> 1
    assert not edges_meet(flat, 0, 1, 1, 5)    # straight on
    assert not edges_meet(flat, 0, 1, 1, 7)    # turns


@pytest.mark.parametrize("ripple, turn", [(0.0, (0.0, 0.0, 0.0)), (0.15, (30.0, 50.0, -20.0)),
                                          (0.0, (90.0, 0.0, 0.0))])
def test_a_flat_or_rippled_cloth_passes(cloth, ripple, turn):
    """The proof is of use: a flat cloth (ring edges sqrt(2) spacings away, 0.15 m, against a
    reach of 0.06 m), also rippled and turned any way, passes."""
    arrays, flat = cloth
    assert unfolded(arrays, shaped(flat, ripple, 0.0, 0.0, 0.0, turn, 0.0, 0))


def test_a_cloth_folded_flat_onto_itself_fails(cloth):
    arrays, flat = cloth
    x = shaped(flat, 0.0, 179.0, 0.0, 0.0, (0.0, 0.0, 0.0), 0.0, 0)
    assert pair_count(arrays, x) > 0 and not unfolded(arrays, x)


def test_nan_positions_fail(cloth):
    arrays, flat = cloth
    x = flat.copy()
    x[7, 1] = np.nan
    assert not unfolded(arrays, x)


def arrays_of(*bodies):
    return Simulation(Scene(bodies=list(bodies), terrains=[], dt=1e-3)).model.arrays


@pytest.mark.parametrize("bodies", [
    [Cube(self_collision=True)],                                    # closed: no boundary
    [Cloth(), Cloth(position=(0.0, 2.0, 0.0))],                     # two sheets
    [Cloth(self_collision=False), Cube(position=(0.0, 3.0, 0.0))],  # no self-contact
])
def test_only_one_self_colliding_disk_gets_a_sheet(bodies):
    arrays = arrays_of(*bodies)
    assert arrays.surface_triangles.shape[0] > 0
    assert arrays.sheet_boundary.shape[0] == 0 and arrays.sheet_ring_edges.shape[0] == 0


def test_is_disk_tells_a_disk_from_what_is_not():
    square = np.array([[0, 1, 2], [0, 2, 3]])
    assert is_disk(square, 4)
    assert not is_disk(np.array([[0, 1, 2], [0, 3, 2]]), 4)            # flipped: not oriented
    assert not is_disk(np.array([[0, 1, 2], [0, 3, 4]]), 5)            # two fans at 0
    strip = np.array([[i, (i + 1) % 6, 6 + i] for i in range(6)]
                     + [[(i + 1) % 6, 6 + (i + 1) % 6, 6 + i] for i in range(6)])
    assert not is_disk(strip, 12)                                      # an annulus
    assert not is_disk(np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]), 4)  # closed


def test_a_run_with_the_proof_steps_as_one_that_searches():
    """The standing 12 x 12 cloth collapsing and folding onto the floor (test_surface_contact):
    with the sheet's arrays and without them (no proof: every list then from a search or kept
    by the spread or the rigid check), the same positions bit for bit, while the proof passed
    at the start."""
    from test_surface_contact import standing_cloth

    runs = []
    for keep_sheet in (True, False):
        simulation, _ = standing_cloth("symplectic_euler", 2e-4)
        if not keep_sheet:
            arrays = simulation.model.arrays._replace(**no_sheet())
            simulation.model = dataclasses.replace(simulation.model, arrays=arrays)
        else:
            assert unfolded(simulation.model.arrays, simulation.positions)
        simulation.step(5000)
        runs.append(simulation.positions.copy())
    assert np.array_equal(runs[0], runs[1])
