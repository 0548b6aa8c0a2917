"""The plain kernels (plain.py): a model with none of what they leave out runs them, bit for bit
as the whole kernel runs it, and a model with any of it runs the whole kernel."""
import hashlib

import numpy as np
import pytest

from springsim import plain
from springsim.clock import CALL_START
from springsim.forces import accelerations
from springsim.integrators import _steps, midpoint, rk4
from springsim.scenefile import load_scene
from springsim.simulation import Simulation

# the methods whose serial step has a plain twin (implicit_euler's is its own kernel, whole)
PLAIN_METHODS = ["explicit_euler", "symplectic_euler", "midpoint", "rk4", "predict_reevaluate",
                 "vbd"]
SMALL = ["bodies.0.particles_per_edge=4"]


def run_hash(scene, integrator, kernel_of, steps=150):
    """The hash of (x, v) after ``steps`` steps of the kernel ``kernel_of(integrator)`` gives."""
    simulation = Simulation(scene, integrator=integrator)
    call = simulation.integrator.kernel_call(simulation.model, simulation.state,
                                             simulation.dt, steps, threaded=False)
    kernel = kernel_of(simulation.integrator)
    simulation.model.arrays.clock[CALL_START] = simulation.state.time
    done, particle, _ = kernel(*call.arguments)
    assert done == steps and particle == -1
    state = simulation.state
    return hashlib.sha256(state.positions.tobytes() + state.velocities.tobytes()).hexdigest()


@pytest.mark.parametrize("integrator", PLAIN_METHODS)
@pytest.mark.parametrize("scene, changes", [
    ("jelly-plane", SMALL),
    ("jelly-bowl", SMALL),
    # a sphere that moves: the moving world stays in the plain kernels
    ("jelly-sphere", SMALL + ["terrains.0.motion.velocity=[0.3, 0.0, 0.1]"]),
])
def test_a_plain_model_moves_bit_for_bit_as_under_the_whole_kernel(integrator, scene, changes):
    scene = load_scene(scene, changes)
    assert plain.is_plain(Simulation(scene, integrator=integrator).model.arrays)
    whole = run_hash(scene, integrator, lambda method: method.kernel)
    twin = run_hash(scene, integrator, lambda method: plain.plain_twin(method.kernel))
    assert twin == whole


@pytest.mark.parametrize("scene, changes", [
    ("jelly-balls", []),                 # balls
    ("cloth-hang", []),                  # pins
    ("jelly-stack", []),                 # body contact: surfaces
    ("jelly-torus", []),                 # a mesh terrain
    ("cape", []),                        # a deforming mesh terrain, pins following it
    ("flag", []),                        # wind
    ("jelly-plane", ["forces=[{type = 'attractor', point = [0, 1, 0], bodies = [0], "
                     "stiffness = 10.0}]"]),   # a term of its own table
])
def test_a_model_with_anything_the_plain_kernels_leave_out_runs_the_whole_kernel(scene, changes):
    simulation = Simulation(load_scene(scene, changes), integrator="rk4")
    assert not plain.is_plain(simulation.model.arrays)
    call = simulation.integrator.kernel_call(simulation.model, simulation.state, simulation.dt,
                                             0, threaded=False)
    assert call.kernel is rk4.advance


def test_the_serial_steps_share_one_twin_of_each_kernel_they_share():
    """rk4's and midpoint's plain steps call one plain force evaluation and one plain pass
    after the step, compiled once; a kernel that reaches nothing left out is its own twin."""
    plain.plain_twin(rk4.advance)
    plain.plain_twin(midpoint.advance)
    twin_of = plain._twins
    assert twin_of[id(accelerations)] is plain.plain_twin(accelerations)
    assert plain.plain_twin(accelerations).py_func.__qualname__ == "accelerations_plain"
    assert plain.plain_twin(_steps.collide).py_func.__qualname__ == "collide_plain"
    assert plain.plain_twin(_steps.force_columns) is _steps.force_columns
    forces = plain.plain_twin(rk4.rk4_step).py_func.__globals__["accelerations"]
    assert forces is plain.plain_twin(midpoint.midpoint_step).py_func.__globals__["accelerations"]


def test_a_plain_models_penetration_is_measured_as_by_the_whole_kernel():
    """The recording's clearance from each terrain (clearance.terrain_clearance) uses the plain twin
    for a plain model: the same numbers, bit for bit."""
    from springsim.clearance import terrain_clearance
    from springsim.world import terrain_clearances

    simulation = Simulation(load_scene("jelly-bowl", SMALL), integrator="rk4")
    simulation.step(2000)   # in the bowl by then
    model, x = simulation.model, simulation.positions
    plain_clearance = terrain_clearance(model, x, simulation.time)
    whole = np.full(1, np.inf)
    terrain_clearances(model.arrays, x, model.arrays.radius, simulation.time, whole)
    assert plain_clearance.tobytes() == whole.tobytes() and plain_clearance[0] < 0.05
