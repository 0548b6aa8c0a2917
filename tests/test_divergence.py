"""Divergence is caught at the step it happens, with a message a user can act on; pinned particles
never move."""
import re

import numpy as np
import pytest

import springsim
from springsim import SimulationDiverged
from springsim.terrains import Plane

INTEGRATORS = ["explicit_euler", "symplectic_euler", "midpoint", "rk4"]
EARTH_GRAVITY = (0.0, -9.8, 0.0)


def test_explicit_euler_at_a_large_step_diverges_with_an_actionable_message():
    """The course framework's cube is stable with explicit Euler up to dt = 0.0018 s only."""
    dt = 0.005
    simulation = springsim.Simulation(springsim.load_scene("jelly-plane"),
                                      integrator="explicit_euler", dt=dt)
    with pytest.raises(SimulationDiverged) as caught:
        simulation.advance(2.0)
    error = caught.value
    assert error.integrator == "explicit_euler" and error.dt == dt
    assert error.step == simulation.steps_taken < 2.0 / dt
    assert error.time == pytest.approx(error.step * dt, rel=1e-12) == simulation.time
    assert error.speed_squared > 1e6 or not np.isfinite(error.speed_squared)
    message = str(error)
    for said in (f"t = {error.time:.6g} s", f"step {error.step}", "'explicit_euler'",
                 f"dt = {dt:g} s", "Try a smaller dt", "rk4"):
        assert said in message, said
    # the step it suggests is at most half the one that diverged, and no more than the
    # automatic step (step_size.py), and a run at it stays bounded
    suggested = float(re.search(r"for example ([0-9.e-]+)\)", message).group(1))
    assert suggested <= dt / 2
    springsim.Simulation(springsim.load_scene("jelly-plane"), integrator="explicit_euler",
                         dt=suggested).advance(0.5)


@pytest.mark.parametrize("integrator", INTEGRATORS)
@pytest.mark.parametrize("where", ["positions", "velocities"])
def test_a_nan_in_the_state_is_caught_at_the_next_step(integrator, where):
    simulation = springsim.Simulation(springsim.load_scene("jelly-plane"), integrator=integrator,
                                      dt=1e-3)
    simulation.step(10)
    getattr(simulation.state, where)[417, 1] = np.nan
    with pytest.raises(SimulationDiverged) as caught:
        simulation.step(100)
    assert caught.value.step == 11 == simulation.steps_taken
    assert caught.value.time == pytest.approx(0.011, rel=1e-12)
    assert "diverged at t = 0.011 s (step 11)" in str(caught.value)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_pinned_particles_never_move(cube_simulation, integrator):
    """A 4 x 4 x 4 jelly hung from its four top corners sags, swings and touches the ground."""
    n = 4
    # particle (i, j, k) is number i n^2 + j n + k, and j counts along y
    top_corners = tuple(i * n * n + (n - 1) * n + k for i in (0, n - 1) for k in (0, n - 1))
    simulation = cube_simulation(
        integrator, 1e-3, gravity=EARTH_GRAVITY, drag=0.3, ks=300.0, kd=5.0,
        particles_per_edge=n, edge_length=1.5, position=(0.0, 0.0, 0.0), pinned=top_corners,
        velocity=(0.5, 0.0, 0.0), terrains=[Plane(point=(0.0, -1.05, 0.0))])
    model = simulation.model
    pinned = model.pinned
    assert pinned.sum() == 4
    start = simulation.positions.copy()
    closest = np.inf
    for _ in range(15):
        simulation.advance(0.1)
        closest = min(closest, model.terrains[0].signed_distance(simulation.positions).min())
    assert np.array_equal(simulation.positions[pinned], start[pinned])
    assert np.all(simulation.velocities[pinned] == 0.0)
    # the rest really moved: the body sagged onto the ground and swung
    assert np.abs(simulation.positions[~pinned] - start[~pinned]).max() > 0.05
    assert closest < model.terrains[0].epsilon
