"""Springs in runs (spring_runs.py): every spring is in exactly one run or in the loose list, with
its own rest length and parameters, and the vectorized run loop gives the reference forces, also
across tiles and bodies."""
import numpy as np
import pytest

from springsim import Simulation, load_scene
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.forces import forces
from springsim.model import build_model
from springsim.reference import reference_forces
from springsim.scene import Scene
from springsim.spring_runs import TILE, build_spring_runs
from springsim.springs import SpringParameters

SCENES = {
    "jelly-plane": lambda: load_scene("jelly-plane"),
    "cloth-balls": lambda: load_scene("cloth-balls"),
    "cube N=2": lambda: Scene(name="t", bodies=[Cube(particles_per_edge=2,
                                                      bend=SpringParameters(0.0, 0.0))]),
    # N = 3: a shear spring and a bend spring share the offset 2 (but not the group)
    "cube N=3": lambda: Scene(name="t", bodies=[Cube(particles_per_edge=3)]),
    "cube N=4 with face springs": lambda: Scene(name="t", bodies=[
        Cube(particles_per_edge=4, face_springs=True, face=SpringParameters(300.0, 9.0))]),
    "cube N=14 and a cloth": lambda: Scene(name="t", bodies=[
        Cube(particles_per_edge=14, position=(0.0, 5.0, 0.0)),
        Cloth(particles_per_edge=9, position=(0.0, 1.0, 0.0))]),
}


def spring_table(springs, rest_length, group):
    """The springs as a sorted list of (low particle, high particle, rest length, group)."""
    low, high = np.minimum(springs[:, 0], springs[:, 1]), np.maximum(springs[:, 0], springs[:, 1])
    return sorted(zip(low.tolist(), high.tolist(), np.asarray(rest_length).tolist(),
                      np.asarray(group).tolist()))


def springs_from_runs(runs, run_rest_length):
    """The springs the runs hold, holes left out."""
    rows = []
    for first, offset, count, start, group in runs:
        for i in range(count):
            if run_rest_length[start + i] >= 0:
                rows.append((first + i, first + i + offset, run_rest_length[start + i], group))
    return rows


def check_partition(springs, rest_length, group):
    runs = build_spring_runs(springs, group, rest_length)
    loose = runs["loose_springs"]
    held = springs_from_runs(runs["spring_runs"], runs["run_rest_length"])
    held += spring_table(springs[loose], rest_length[loose], group[loose])
    assert sorted(held) == spring_table(springs, rest_length, group)
    return runs


@pytest.mark.parametrize("name", SCENES)
def test_every_spring_is_in_one_run_or_loose(name):
    arrays = build_model(SCENES[name]()).arrays
    runs = check_partition(arrays.springs, arrays.rest_length, arrays.spring_group)
    if name in ("jelly-plane", "cloth-balls"):
        assert len(runs["loose_springs"]) == 0   # lattices: all in runs
        assert len(runs["run_rest_length"]) < 1.2 * len(arrays.springs)   # few holes


def test_a_repeated_spring_is_kept_loose():
    springs = np.array([[i, i + 1] for i in range(20)] + [[5, 6], [7, 6]], np.uint32)
    group = np.zeros(len(springs), np.int16)
    rest_length = np.linspace(0.5, 1.5, len(springs))
    runs = check_partition(springs, rest_length, group)
    assert len(runs["spring_runs"]) == 1 and len(runs["loose_springs"]) == 2


@pytest.mark.parametrize("name", SCENES)
def test_forces_match_the_reference(name):
    simulation = Simulation(SCENES[name]())
    model = simulation.model
    rng = np.random.default_rng(5)
    x = model.initial_positions + 0.02 * rng.standard_normal(model.initial_positions.shape)
    v = rng.standard_normal(x.shape)
    v[model.pinned] = 0.0
    expected = reference_forces(model, x, v)
    np.testing.assert_allclose(forces(model.arrays, x, v), expected, rtol=0,
                               atol=1e-13 * np.abs(expected).max())
    if name == "cube N=14 and a cloth":
        assert model.particle_count > TILE   # several tiles


def test_coincident_particles_exert_no_spring_force():
    """All particles at one point: no spring has a direction, so only gravity and drag act (and
    no NaN appears, neither from the springs nor from the holes of the runs)."""
    model = build_model(SCENES["cube N=14 and a cloth"]())
    x = np.zeros_like(model.initial_positions)
    v = np.ones_like(x)
    f = forces(model.arrays, x, v)
    expected = model.mass[:, None] * model.arrays.gravity - model.arrays.drag[:, None] * v
    expected[model.pinned] = -model.arrays.drag[model.pinned, None] * v[model.pinned]
    np.testing.assert_array_equal(f, expected)


@pytest.mark.parametrize("particle", [0, 21, 61])
def test_a_non_finite_particle_reaches_only_its_spring_neighbours(particle):
    """A hole joins two particles by no spring, so NaN must not cross it: the divergence check
    names the first non-finite particle, and that must be where the trouble started."""
    model = build_model(Scene(name="t", bodies=[Cube(particles_per_edge=4)]))
    x = model.initial_positions.copy()
    x[particle] = np.nan
    f = forces(model.arrays, x, np.zeros_like(x))
    springs = model.springs.astype(np.int64)
    touching = springs[(springs == particle).any(axis=1)]
    expected = np.zeros(model.particle_count, bool)
    expected[touching.ravel()] = True
    np.testing.assert_array_equal(~np.isfinite(f).all(axis=1), expected)
