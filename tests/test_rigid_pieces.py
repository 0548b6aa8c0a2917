"""Oracles of rigid_pieces.moved_rigidly: a kept pair list may be kept only if every pair of
surface shapes within its rest distance now was listed when the list was found (the pair search
itself, run at both positions, is the oracle), and a motion that is rigid by pieces, which shrinks
no distance, keeps it where the spread of the displacements would not.
"""
import numpy as np
import pytest
from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from springsim.bodies.cloth import Cloth
from springsim.collision.broad_phase.surfaces import surface_pairs
from springsim.collision.pair_lists.rigid_pieces import moved_rigidly
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.collision.pair_lists.keeping import list_holds, surface_skin

N = 30   # particles along each edge of the 4 m test cloth: spacing 0.14 m


@pytest.fixture(scope="module")
def cloth():
    """The model arrays and flat positions of a 30 x 30, 4 m self-colliding cloth, 2 cm
    thick."""
    simulation = Simulation(Scene(bodies=[Cloth(particles_per_edge=N, thickness=0.02)],
                                  terrains=[], dt=1e-3))
    return simulation.model.arrays, simulation.positions.copy()


def listed(arrays, x, beyond):
    points, edges = surface_pairs(arrays, x, beyond, beyond)
    return set(map(tuple, points)), set(map(tuple, edges))


def keeps(arrays, now, then):
    return moved_rigidly(arrays.surface_points, arrays.surface_edges, arrays.body_thickness,
                         surface_skin(arrays), now, then)


def assert_kept_only_if_it_holds(arrays, now, then):
    """The oracle: if moved_rigidly keeps the list found at ``then``, every pair within its
    rest distance ``now`` is in it (both found by the pair search itself)."""
    kept = keeps(arrays, now, then)
    event(f"kept: {kept}")
    if kept:
        points, edges = listed(arrays, now, 0.0)
        kept_points, kept_edges = listed(arrays, then, surface_skin(arrays))
        assert points <= kept_points and edges <= kept_edges


def folded(x, angle_degrees, line_z, bend, gap=0.0):
    """The flat cloth x (in the plane y = 0) bent by a ripple of height ``bend`` and folded up
    about the line y = gap / 2, z = line_z by ``angle_degrees``: a fold of 180 degrees lays the
    far part back over the near one, ``gap`` above it."""
    y = x.copy()
    y[:, 1] += bend * np.sin(1.3 * x[:, 0] + 0.7 * x[:, 2])
    far = x[:, 2] > line_z
    turn = Rotation.from_euler("x", angle_degrees, degrees=True).as_matrix()
    pivot = np.array([0.0, 0.5 * gap, line_z])
    y[far] = (y[far] - pivot) @ turn.T + pivot
    return y


FOLD = st.tuples(st.floats(0, 180), st.floats(-1.5, 1.5), st.floats(0, 0.3), st.floats(0, 0.3))


SLOW_OK = [HealthCheck.too_slow, HealthCheck.function_scoped_fixture]


@settings(max_examples=80, deadline=None, suppress_health_check=SLOW_OK)
@given(first=FOLD, second=FOLD,
       turn=st.tuples(st.floats(-180, 180), st.floats(-180, 180), st.floats(-180, 180)),
       shift=st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-5, 5)),
       closing=st.floats(0, 0.1))
@example(first=(180.0, 0.3, 0.0, 0.075), second=(180.0, 0.3, 0.0, 0.075),
         turn=(0.0, 0.0, 0.0), shift=(0.0, 0.0, 0.0), closing=0.06)
def test_a_kept_list_holds_every_pair_within_reach(cloth, first, second, turn, shift, closing):
    """Whatever the motion between two folds of the cloth (turned and moved as a whole too,
    and the second fold's gap closed by up to 10 cm), if moved_rigidly keeps the list found
    at the first, every pair within its rest distance at the second was in it."""
    arrays, flat = cloth
    then = folded(flat, *first)
    angle, line, bend, gap = second
    now = folded(flat, angle, line, bend, max(gap - closing, 0.0))
    now = now @ Rotation.from_euler("xyz", turn, degrees=True).as_matrix().T + np.array(shift)
    assert_kept_only_if_it_holds(arrays, now, then)


def test_a_fold_closing_past_the_skin_is_not_kept(cloth):
    """The cloth folded flat over itself 7.5 cm apart (beyond its 2 cm thickness and the 4 cm
    skin: the list has no pair across the fold), then closed to 1.5 cm apart: pairs across the
    fold are now within reach, so the list must not be kept; closed to 5 cm it may be."""
    arrays, flat = cloth
    then = folded(flat, 180.0, 0.3, 0.0, 0.075)
    shut = folded(flat, 180.0, 0.3, 0.0, 0.015)
    assert listed(arrays, shut, 0.0)[0] - listed(arrays, then, surface_skin(arrays))[0]
    assert not keeps(arrays, shut, then)
    assert keeps(arrays, folded(flat, 180.0, 0.3, 0.0, 0.05), then)


def test_a_turned_and_moved_cloth_keeps_its_list_where_the_spread_would_not(cloth):
    """A bent cloth turned by 40 degrees and moved 3 m keeps every distance: moved_rigidly
    keeps the list, which the displacements' spread (list_holds) throws away; the same cloth
    also folded shut by a further 170 degrees brings its halves within their thickness, and
    the list, which had none of those pairs, is not kept."""
    arrays, flat = cloth
    then = folded(flat, 10.0, 0.4, 0.2)
    turn = Rotation.from_euler("xyz", (40.0, -25.0, 15.0), degrees=True).as_matrix()
    now = then @ turn.T + np.array([3.0, -1.0, 0.5])
    assert not list_holds(arrays.surface_points, arrays.body_thickness, now, then)
    assert keeps(arrays, now, then)
    shut = folded(flat, 179.0, 0.4, 0.2) @ turn.T
    assert listed(arrays, shut, 0.0)[0] - listed(arrays, then, surface_skin(arrays))[0]
    assert not keeps(arrays, shut, then)


def test_a_swinging_cloth_keeps_its_list_by_pieces(cloth):
    """Each half of the cloth turned its own way about the middle line, by 1.5 degrees
    (the cloth bends there, as a swinging one does): no single rotation fits, but one per
    window does, so the list is kept; NaN is never kept."""
    arrays, flat = cloth
    then = folded(flat, 0.0, 0.0, 0.0)
    now = folded(flat, 1.5, 0.0, 0.0)
    assert not list_holds(arrays.surface_points, arrays.body_thickness, now, then)
    assert keeps(arrays, now, then)
    now[5] = np.nan
    assert not keeps(arrays, now, then)


@pytest.fixture(scope="module")
def two_cloths():
    """Two 15 x 15, 2 m cloths, 2 cm thick, one 3.5 m above the other (no window of the
    finest level holds both)."""
    cloths = [Cloth(particles_per_edge=15, width=2.0, height=2.0, thickness=0.02,
                    position=(0.0, height, 0.0)) for height in (0.0, 3.5)]
    simulation = Simulation(Scene(bodies=cloths, terrains=[], dt=1e-3))
    return simulation.model.arrays, simulation.positions.copy(), simulation.model.bodies[1]


@settings(max_examples=40, deadline=None, suppress_health_check=SLOW_OK)
@given(drop=st.floats(0.0, 3.6), slide=st.floats(-2.5, 2.5),
       turn=st.tuples(st.floats(-20, 20), st.floats(-180, 180), st.floats(-20, 20)))
@example(drop=3.49, slide=0.0, turn=(0.0, 0.0, 0.0))
def test_two_bodies_each_moved_rigidly_are_kept_only_while_far_apart(two_cloths, drop, slide,
                                                                      turn):
    """The upper cloth turned and lowered by up to 3.6 m onto the lower one: each moves
    rigidly, so only the coarser levels see them close in; whenever the list is kept, every
    pair within reach now was in it."""
    arrays, then, upper = two_cloths
    now = then.copy()
    piece = now[upper.start:upper.stop]
    middle = piece.mean(axis=0)
    turned = Rotation.from_euler("xyz", turn, degrees=True).as_matrix()
    now[upper.start:upper.stop] = (piece - middle) @ turned.T + middle + (slide, -drop, 0.0)
    assert_kept_only_if_it_holds(arrays, now, then)


def test_positions_then_with_nan_are_never_kept(cloth):
    """A list found where a position was NaN (a search after a diverged step) is not kept,
    and the check reads no cell outside its grid (NaN has no cell)."""
    arrays, flat = cloth
    then = flat.copy()
    then[arrays.surface_points[400]] = np.nan
    assert not keeps(arrays, flat, then)
    assert not keeps(arrays, then, then)


def test_a_state_loaded_after_a_diverged_step_steps_on(tmp_path):
    """The integrator keeps the pair list searched at the diverged step's NaN positions; the
    state loaded after it (finite) is searched afresh and steps like the saved run did."""
    from springsim.errors import SimulationDiverged

    def simulation():
        return Simulation(Scene(bodies=[Cloth(particles_per_edge=30, thickness=0.02)],
                                terrains=[], dt=1e-3))
    diverged, reference = simulation(), simulation()
    diverged.step(2)
    reference.step(2)
    diverged.save_state(tmp_path / "state.npz")
    diverged.state.positions[diverged.model.arrays.surface_points[400]] = np.nan
    with pytest.raises(SimulationDiverged):
        diverged.step(1)
    diverged.load_state(tmp_path / "state.npz")
    diverged.step(3)
    reference.step(3)
    assert np.array_equal(diverged.positions, reference.positions)
