"""Threads: a model's force loop runs in fixed partitions (spring_runs.py), so that its results
are the same bit for bit whatever the number of threads, and still the spring forces.

The partitions, not the model's size, are what the threaded kernel's order of work depends on:
small models with a small ``spring_partition`` (a 6^3 cube and a 10 x 10 cloth on balls, cut
into five and six partitions, their longest springs crossing more than one) take every path a
large model takes, in milliseconds once explicit Euler's threaded kernel is compiled
(`springsim warmup --integrators explicit_euler --variants threaded`; its warmup scenes give
the kernel the types these models have: test_warmup_compiles_the_kernels_these_tests_call).

Integrator.advance takes the threaded kernel for a model of two PARTITION's worth of particles
or more (integrators/base.py), whatever its own ``spring_partition``; ``take_kernel`` makes
these small models' steps take the threaded kernel, or the serial one, and records which ran.
"""
from typing import NamedTuple

import numpy as np
import pytest

from springsim import SceneError, Simulation, warmup
from springsim.errors import SimulationDiverged
from springsim.forces import forces
from springsim.integrators import available_threads
from springsim.integrators._steps import DIVERGENCE_CHUNKS
from springsim.model import build_model
from springsim.reference import reference_forces
from springsim.scenefile import load_scene
from springsim.spring_runs import PARTITION, TILE, partition_count

THREADS = sorted({1, min(2, available_threads()), available_threads()})


class SmallModel(NamedTuple):
    scene: str
    overrides: list
    spring_partition: int
    partitions: int   # what that cuts the model into


# the longest spring (a cube's bend spring, 2 N^2 = 72 particles apart; a cloth's, 2 N = 20)
# spans more than one partition
MODELS = {"cube": SmallModel("jelly-plane", ["bodies.0.particles_per_edge=6"], 40, 5),
          "cloth": SmallModel("cloth-balls", ["bodies.0.particles_per_edge=10"], 16, 6)}


def small_model(name: str) -> Simulation:
    """The model ``name`` of MODELS on explicit Euler, every spring stretched and every damper
    working (random displacements and velocities); the cloth's balls pressed into it."""
    model = MODELS[name]
    simulation = Simulation(load_scene(model.scene, model.overrides), integrator="explicit_euler",
                            dt=1e-4, spring_partition=model.spring_partition)
    rng = np.random.default_rng(3)
    x, v = simulation.state.positions, simulation.state.velocities
    free = ~simulation.model.pinned
    x[free] += 0.01 * rng.standard_normal(x[free].shape)
    v[free] = rng.standard_normal(v[free].shape)
    if name == "cloth":
        balls = simulation.model.arrays.balls
        x[balls, 1] = simulation.model.arrays.radius[balls] - 0.05   # 5 cm into the cloth
        v[balls] = (0.0, -2.0, 0.0)
    return simulation


def take_kernel(monkeypatch, simulation, threaded: bool) -> list:
    """Make ``simulation``'s steps take its integrator's threaded kernel (or its serial one);
    returns the list of kernels its steps then call."""
    integrator = simulation.integrator
    kernel_call = type(integrator).kernel_call
    called = []

    def chosen_call(model, state, dt, steps, threaded_by_size=None):
        call = kernel_call(integrator, model, state, dt, steps, threaded=threaded)
        called.append(call.kernel)
        return call

    monkeypatch.setattr(integrator, "kernel_call", chosen_call)
    return called


def steps_from(simulation, start, threads: int, count: int):
    """The state after ``count`` steps from ``start`` with ``threads`` threads."""
    simulation.state = start.copy()
    simulation.threads = threads
    simulation.step(count)
    return simulation.state.copy()


@pytest.mark.parametrize("name", MODELS)
def test_the_small_models_are_cut_into_partitions(name):
    simulation, model = small_model(name), MODELS[name]
    arrays, count = simulation.model.arrays, simulation.model.particle_count
    assert arrays.spring_partition == model.spring_partition
    assert count >= 2 * model.spring_partition
    assert partition_count(count, arrays.spring_partition) == model.partitions
    assert arrays.spring_runs[:, 1].max() > model.spring_partition   # crossing partitions
    assert partition_count(count) == 1   # by default, one partition
    assert (partition_count(51 ** 3), partition_count(50 ** 3)) == (2, 1)   # 132,651 and 125,000
    default = Simulation(load_scene(model.scene, model.overrides))
    assert default.model.arrays.spring_partition == PARTITION


@pytest.mark.parametrize("name", MODELS)
def test_partitioned_spring_forces_match_the_reference(name):
    simulation = small_model(name)
    x, v = simulation.state.positions, simulation.state.velocities
    expected = reference_forces(simulation.model, x, v)
    assert np.allclose(forces(simulation.model.arrays, x, v), expected, rtol=0, atol=1e-9)


def test_partitions_of_several_tiles_give_the_reference_forces():
    """A partition longer than a tile (spring_runs.TILE) walks its tiles in turn: a 17^3 cube
    in two partitions of over 2,400 particles."""
    model = build_model(load_scene("jelly-plane", ["bodies.0.particles_per_edge=17"]),
                        spring_partition=TILE + 52)
    assert partition_count(model.particle_count, model.arrays.spring_partition) == 2
    rng = np.random.default_rng(5)
    x = model.initial_positions + 0.02 * rng.standard_normal(model.initial_positions.shape)
    v = rng.standard_normal(x.shape)
    expected = reference_forces(model, x, v)
    assert np.allclose(forces(model.arrays, x, v), expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("name", MODELS)
def test_threaded_steps_are_bit_identical_to_serial_ones_for_any_number_of_threads(
        name, monkeypatch):
    """The threaded kernel with any number of threads, and the serial kernel, take the same
    steps bit for bit (the cloth's with its balls and its own surface in contact)."""
    simulation = small_model(name)
    start = simulation.state.copy()
    take_kernel(monkeypatch, simulation, threaded=False)
    serial = steps_from(simulation, start, 1, 3)
    called = take_kernel(monkeypatch, simulation, threaded=True)
    for threads in THREADS:
        threaded = steps_from(simulation, start, threads, 3)
        assert np.array_equal(threaded.positions, serial.positions)
        assert np.array_equal(threaded.velocities, serial.velocities)
    assert called == [simulation.integrator.parallel_kernel] * len(THREADS)
    assert not np.array_equal(serial.positions, start.positions)   # it did move


def test_the_balls_pressed_into_the_cloth_are_pushed_back(monkeypatch):
    """The cloth's steps above meet contact: its balls, 5 cm into it and falling at 2 m/s, fall
    at least 5 mm/s slower after three threaded steps than gravity alone would let them (their
    drag changes 1e-9 m/s)."""
    simulation = small_model("cloth")
    start = simulation.state.copy()
    take_kernel(monkeypatch, simulation, threaded=True)
    velocities = steps_from(simulation, start, THREADS[-1], 3).velocities
    balls = simulation.model.arrays.balls
    free_fall = -2.0 - 9.8 * 3 * simulation.dt
    assert np.all(velocities[balls, 1] > free_fall + 0.005)


@pytest.mark.parametrize("threads", [0, -1, 2.0, True, "2", 10 ** 6])
def test_a_bad_thread_count_is_refused_before_any_work(threads):
    with pytest.raises(SceneError, match="threads"):
        Simulation(load_scene("jelly-plane"), threads=threads)


@pytest.mark.parametrize("partition", [0, -1, 64.0, True, "64", 2 ** 62 + 1])
def test_a_bad_spring_partition_is_refused_in_one_line(partition):
    with pytest.raises(SceneError) as raised:
        Simulation(load_scene("jelly-plane"), spring_partition=partition)
    assert str(raised.value) == (f"spring_partition = {partition!r}: must be a whole number of "
                                 f"particles from 1 to 2^62 (default {PARTITION})")


def test_terrain_contact_is_bit_identical_for_any_number_of_threads(monkeypatch):
    """With the lower half of the cube pushed through the plane y = -1 and falling, the threaded
    steps (contact in the force evaluation, impacts after each step) agree bit for bit with each
    other and with the serial ones, and each ends with no particle below the plane (the impact
    pass lifts them out). Explicit Euler's threaded kernel, which the other tests compile too:
    every method's threaded kernel inlines the same contact code (integrators/_steps.threaded),
    and each costs minutes to compile."""
    simulation = small_model("cube")
    positions = simulation.state.positions.copy()
    positions[:, 1] += -1.0 - np.median(positions[:, 1])   # half the particles under the plane
    start = simulation.state.copy()
    start.positions[:] = positions
    start.velocities[:] = 0.0
    start.velocities[:, 1] = -2.0
    take_kernel(monkeypatch, simulation, threaded=False)
    serial = steps_from(simulation, start, 1, 2)
    called = take_kernel(monkeypatch, simulation, threaded=True)
    for threads in THREADS:
        threaded = steps_from(simulation, start, threads, 2)
        assert np.array_equal(threaded.positions, serial.positions)
        assert np.array_equal(threaded.velocities, serial.velocities)
    assert called == [simulation.integrator.parallel_kernel] * len(THREADS)
    assert serial.positions[:, 1].min() >= -1.0 - 1e-12
    assert (positions[:, 1] < -1.0).sum() > simulation.model.particle_count // 3


@pytest.mark.parametrize("threads", sorted({1, min(2, available_threads())}))
def test_the_first_diverged_particle_is_the_smallest_whatever_the_threads(threads, monkeypatch):
    """The divergence check runs in DIVERGENCE_CHUNKS fixed pieces, on threads: with particles
    diverging in several pieces, the one reported is the smallest index that a plain NumPy
    check of the state after the step finds."""
    simulation = small_model("cube")
    count = simulation.model.particle_count
    piece = -(-count // DIVERGENCE_CHUNKS)
    simulation.state.velocities[[5 * piece + 17, 2 * piece + 3, count - 1]] = 1e9
    simulation.threads = threads
    called = take_kernel(monkeypatch, simulation, threaded=True)
    with pytest.raises(SimulationDiverged) as raised:
        simulation.step(1)
    assert called == [simulation.integrator.parallel_kernel]
    x, v = simulation.state.positions, simulation.state.velocities
    with np.errstate(over="ignore", invalid="ignore"):
        bad = np.flatnonzero(~((v * v).sum(axis=1) <= 1e6) | ~np.isfinite(x.sum(axis=1)))
    assert len(np.unique(bad // piece)) >= 3   # found in several pieces
    assert raised.value.particle == bad[0]


@pytest.mark.parametrize("name", MODELS)
def test_warmup_compiles_the_kernels_these_tests_call(name):
    """The threaded call these tests make has the types of one that `springsim warmup
    --variants threaded` compiles for explicit Euler (its warmup scenes'), so that with the
    cache warm these tests compile nothing."""
    simulation = small_model(name)
    call = simulation.integrator.kernel_call(simulation.model, simulation.state, simulation.dt,
                                             0, threaded=True)
    compiled = warmup.variant_calls("explicit_euler", ["threaded"]).values()
    assert any(each.kernel is call.kernel and types_of(each) == types_of(call)
               for each in compiled)


def types_of(call) -> tuple:
    return tuple(call.kernel.typeof_pyval(argument) for argument in call.arguments)
