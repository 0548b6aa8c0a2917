"""Threads: a large model's force loop runs in fixed partitions (spring_runs.py), so that its
results are the same bit for bit whatever the number of threads, and still the spring forces."""
import numpy as np
import pytest

from springsim import SceneError, Simulation
from springsim.errors import SimulationDiverged
from springsim.forces import forces
from springsim.integrators import available_threads
from springsim.integrators._steps import DIVERGENCE_CHUNKS
from springsim.reference import reference_forces
from springsim.scenefile import load_scene
from springsim.spring_runs import PARTITION, partition_count

EDGE = 51   # 132,651 particles: the smallest cube whose force loop has two partitions


@pytest.fixture(scope="module")
def large_cube():
    scene = load_scene("jelly-plane", [f"bodies.0.particles_per_edge={EDGE}"])
    simulation = Simulation(scene, integrator="explicit_euler", dt=1e-4)
    rng = np.random.default_rng(3)
    simulation.state.positions += 0.01 * rng.standard_normal(simulation.state.positions.shape)
    simulation.state.velocities[:] = rng.standard_normal(simulation.state.velocities.shape)
    return simulation


@pytest.mark.slow   # the 51^3 cube and its threaded kernel
def test_the_large_cube_is_cut_into_partitions(large_cube):
    assert large_cube.model.particle_count >= 2 * PARTITION
    assert partition_count(large_cube.model.particle_count) == 2


@pytest.mark.slow   # the 51^3 cube and its threaded kernel
def test_partitioned_spring_forces_match_the_reference(large_cube):
    x, v = large_cube.state.positions, large_cube.state.velocities
    expected = reference_forces(large_cube.model, x, v)
    assert np.allclose(forces(large_cube.model.arrays, x, v), expected, rtol=0, atol=1e-9)


@pytest.mark.slow   # the 51^3 cube and its threaded kernel
def test_steps_are_bit_identical_for_any_number_of_threads(large_cube):
    start = large_cube.state.copy()
    results = []
    for threads in sorted({1, min(2, available_threads()), available_threads()}):
        large_cube.state = start.copy()
        large_cube.threads = threads
        large_cube.step(3)
        results.append((large_cube.state.positions.copy(), large_cube.state.velocities.copy()))
    for positions, velocities in results[1:]:
        assert np.array_equal(positions, results[0][0])
        assert np.array_equal(velocities, results[0][1])
    assert not np.array_equal(results[0][0], start.positions)   # it did move


@pytest.mark.parametrize("threads", [0, -1, 2.0, True, "2", 10 ** 6])
def test_a_bad_thread_count_is_refused_before_any_work(threads):
    with pytest.raises(SceneError, match="threads"):
        Simulation(load_scene("jelly-plane"), threads=threads)


@pytest.mark.slow   # the 51^3 cube and its threaded kernel
def test_terrain_contact_is_bit_identical_for_any_number_of_threads(large_cube):
    """With the lower half of the cube pushed through the plane y = -1 and falling, the steps
    (contact in the force evaluation, impacts after each step) agree bit for bit, and each ends
    with no particle below the plane (the impact pass lifts them out). Explicit Euler's threaded
    kernel, which the other tests compile too: every method's threaded kernel inlines the same
    contact code (integrators/_steps.threaded), and each costs minutes to compile."""
    start = large_cube.state.copy()
    positions = start.positions.copy()
    positions[:, 1] += -1.0 - np.median(positions[:, 1])   # half the particles under the plane
    velocities = np.zeros_like(positions)
    velocities[:, 1] = -2.0
    scene = load_scene("jelly-plane", [f"bodies.0.particles_per_edge={EDGE}"])
    simulation = Simulation(scene, integrator="explicit_euler", dt=1e-4)
    results = []
    for threads in sorted({1, min(2, available_threads()), available_threads()}):
        simulation.state.positions[:] = positions
        simulation.state.velocities[:] = velocities
        simulation.threads = threads
        simulation.step(2)
        results.append((simulation.state.positions.copy(), simulation.state.velocities.copy()))
    for x, v in results[1:]:
        assert np.array_equal(x, results[0][0]) and np.array_equal(v, results[0][1])
    assert results[0][0][:, 1].min() >= -1.0 - 1e-12
    assert (positions[:, 1] < -1.0).sum() > simulation.model.particle_count // 3


@pytest.mark.slow   # the 51^3 cube and its threaded kernel
@pytest.mark.parametrize("threads", sorted({1, min(2, available_threads())}))
def test_the_first_diverged_particle_is_the_smallest_whatever_the_threads(large_cube, threads):
    """The divergence check runs in DIVERGENCE_CHUNKS fixed pieces, on threads: with particles
    diverging in several pieces, the one reported is the smallest index that a plain NumPy
    check of the state after the step finds."""
    start = large_cube.state.copy()
    count = large_cube.model.particle_count
    piece = -(-count // DIVERGENCE_CHUNKS)
    large_cube.state.velocities[[5 * piece + 17, 2 * piece + 3, count - 1]] = 1e9
    large_cube.threads = threads
    try:
        with pytest.raises(SimulationDiverged) as raised:
            large_cube.step(1)
        x, v = large_cube.state.positions, large_cube.state.velocities
        with np.errstate(over="ignore", invalid="ignore"):
            bad = np.flatnonzero(~((v * v).sum(axis=1) <= 1e6) | ~np.isfinite(x.sum(axis=1)))
        assert len(np.unique(bad // piece)) >= 3   # found in several pieces
        assert raised.value.particle == bad[0]
    finally:
        large_cube.state = start
