"""Surface contact inside backward Euler's solve (collision/response/penalty.py,
collision/pair_lists/solve_pairs.py).

Oracles: a cube resting on another stays on top of it, its surface never more than a thickness
into the other's, at frame-sized steps; a cube thrown at 10 to 20 m/s onto a cube or a cloth does
not pass through it in one 1/30 s step (it moves 0.33 to 0.67 m, more than its particle spacing);
two free cubes thrown at each other keep their total momentum to rounding (the contact forces act
with weights summing to zero, and the solve conserves momentum when nothing is constrained).

The cubes' particles weigh 0.1 kg (a 12.5 kg cube on its 2000 N/m springs): a 125 kg jelly cube
sags into a bowl under its own weight on another, and the lowest-against-highest test would then
measure the sag, not the contact.
"""
import numpy as np
import pytest

import springsim
from crossings import count_crossings, crossing_pairs
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.scene import Scene
from springsim.terrains.plane import Plane

EDGE = 1.0
PER_EDGE = 5
COUNT = PER_EDGE ** 3
MASS = 0.1
THICKNESS = 0.05


def cube(centre, velocity=(0.0, 0.0, 0.0)):
    return Cube(particles_per_edge=PER_EDGE, edge_length=EDGE, particle_mass=MASS,
                position=centre, velocity=velocity, thickness=THICKNESS)


def stack(upper_height, upper_speed, dt):
    """A cube on a plane and a second cube above it, falling at ``upper_speed``."""
    lower = cube((0.0, 0.5 * EDGE, 0.0))
    upper = cube((0.0, upper_height, 0.0), (0.0, -upper_speed, 0.0))
    scene = Scene(bodies=[lower, upper], terrains=[Plane(point=(0.0, 0.0, 0.0))], dt=dt)
    return springsim.Simulation(scene, integrator="implicit_euler")


def separation(x):
    """The upper cube's lowest particle's height over the lower cube's highest."""
    return x[COUNT:, 1].min() - x[:COUNT, 1].max()


@pytest.mark.parametrize("dt", [1.0 / 60.0, 1.0 / 30.0])
def test_a_cube_resting_on_a_cube_stays_on_it(dt):
    """Placed a thickness above the lower cube, the upper one settles on it and stays there for
    3 s: at no step does its surface sink more than a thickness into the lower one's."""
    sim = stack(1.5 * EDGE + THICKNESS, 0.0, dt)
    for _ in range(round(3.0 / dt)):
        sim.step(1)
        assert separation(sim.positions) >= -THICKNESS
    x, v = sim.positions, sim.velocities
    assert x[COUNT:, 1].mean() > x[:COUNT, 1].max()   # on top
    assert np.abs(v[COUNT:, 1].mean()) < 0.05        # and at rest on it


@pytest.mark.parametrize("speed", [10.0, 20.0])
def test_a_fast_cube_does_not_pass_through_a_cube(speed):
    dt = 1.0 / 30.0
    sim = stack(1.6 * EDGE, speed, dt)
    for _ in range(round(0.6 / dt)):
        sim.step(1)
        assert separation(sim.positions) >= -THICKNESS
    assert sim.velocities[COUNT:, 1].mean() > -1.0   # stopped by the lower cube


@pytest.mark.parametrize("speed", [10.0, 20.0])
def test_a_fast_cube_does_not_pass_through_a_cloth(speed):
    """A cloth pinned at its corners catches a cube thrown down at it: the cube's lowest particle
    stays above the cloth's lowest, less the distance the two surfaces keep (the mean of their
    thicknesses), and the cube ends held in the cloth."""
    dt = 1.0 / 30.0
    cloth = Cloth(particles_per_edge=15, width=3.0, height=3.0, position=(0.0, 1.0, 0.0),
                  particle_mass=0.1)
    thrown = cube((0.1, 2.0, -0.05), (0.0, -speed, 0.0))
    sim = springsim.Simulation(Scene(bodies=[cloth, thrown], dt=dt), integrator="implicit_euler")
    sheet = 15 * 15
    rest = 0.5 * (cloth.contact_thickness() + THICKNESS)
    for _ in range(round(1.0 / dt)):
        sim.step(1)
        x = sim.positions
        assert x[sheet:, 1].min() >= x[:sheet, 1].min() - rest
    assert sim.positions[sheet:, 1].mean() > sim.positions[:sheet, 1].min()


@pytest.mark.parametrize("dt", [1.0 / 60.0, 1.0 / 30.0])
def test_free_cubes_thrown_at_each_other_keep_their_momentum(dt):
    """No gravity, no terrain, no drag: whatever the contacts do, the total momentum stays what
    it was, while each cube's own momentum changes a lot (they did collide)."""
    first = cube((-0.8, 0.0, 0.0), (6.0, 0.0, 0.0))
    second = cube((0.8, 0.3, 0.2), (-3.0, 0.0, 0.0))
    scene = Scene(bodies=[first, second], gravity=(0.0, 0.0, 0.0), dt=dt)
    sim = springsim.Simulation(scene, integrator="implicit_euler")
    mass = sim.model.mass
    momentum = mass @ sim.velocities
    first_before = mass[:COUNT] @ sim.velocities[:COUNT]
    for _ in range(round(0.5 / dt)):
        sim.step(1)
        np.testing.assert_allclose(mass @ sim.velocities, momentum, rtol=0,
                                   atol=1e-9 * np.abs(momentum).max())
    first_after = mass[:COUNT] @ sim.velocities[:COUNT]
    assert np.linalg.norm(first_after - first_before) > 0.3 * np.linalg.norm(first_before)
    assert np.all(np.isfinite(sim.positions))


# -- a body's own contacts in the solve: a folded cloth pressed by a cube ----------------------

FOLDED_EDGE = 16   # particles along each edge of the 1 m cloth (spacing 0.067 m)


def cube_onto_folded_cloth(dt, speed, folded=True, shift=0.023, particle_mass=2.0):
    """A 1 m cloth lying on the floor folded in half (the half z > 0 laid back over the other,
    1.5 thicknesses above it and ``shift`` aside along x: 0.023 m, so that no particle lies
    exactly over one of the other layer), and a 0.3 m cube of 64 particles (128 kg) falling
    onto the folded part at ``speed``."""
    cloth = Cloth(particles_per_edge=FOLDED_EDGE, width=1.0, height=1.0, rotation_degrees=0.0,
                  pinned="none", position=(0.0, 0.05, 0.0))
    weight = Cube(particles_per_edge=4, edge_length=0.3, particle_mass=particle_mass,
                  position=(0.0, 0.6, -0.2), velocity=(0.0, -speed, 0.0))
    simulation = springsim.Simulation(Scene(bodies=[cloth, weight],
                                            terrains=[Plane(point=(0.0, 0.0, 0.0))], dt=dt),
                                      integrator="implicit_euler")
    if not folded:
        return simulation
    x = simulation.positions
    sheet = x[:FOLDED_EDGE ** 2]
    far = sheet[:, 2] > 0.0
    sheet[far, 2] = -sheet[far, 2]
    sheet[far, 1] += 1.5 * cloth.contact_thickness()
    sheet[far, 0] += shift
    x[:FOLDED_EDGE ** 2] = sheet
    return simulation


def assert_the_cloth_never_crosses_itself(simulation, dt):
    """Step 1 s of ``cube_onto_folded_cloth``: no edge of the cloth crosses one of its
    triangles at the start or after any step, and the cube comes down onto the cloth."""
    sheet = np.asarray(simulation.model.bodies[0].surface, np.int64).reshape(-1, 3)
    assert count_crossings(simulation.positions, sheet) == 0
    lowest = np.inf
    for _ in range(round(1.0 / dt)):
        simulation.step(1)
        assert count_crossings(simulation.positions, sheet) == 0, simulation.time
        lowest = min(lowest, simulation.positions[FOLDED_EDGE ** 2:, 1].min())
    assert lowest < 0.1   # the cube came down onto the cloth


@pytest.mark.parametrize("dt", [1.0 / 60.0, 1.0 / 30.0])
def test_a_cube_pressing_a_folded_cloth_never_pushes_one_layer_through_the_other(dt):
    """The cube, dropped at 2 m/s, pushes the top layer onto the bottom one, which lies on the
    floor. The solve holds the cube off the top layer (a contact of two bodies) and, since it
    also takes the cloth's own pairs listed at the start of each step, the top layer off the
    bottom one: no edge of the cloth ever crosses one of its triangles, at any step. With the
    post-step pass alone for the cloth's own pairs, the solve pressed the top layer through the
    bottom one at 1/60 s (8 crossings)."""
    simulation = cube_onto_folded_cloth(dt, 2.0)
    assert_the_cloth_never_crosses_itself(simulation, dt)


@pytest.mark.parametrize("shift", [0.0, 0.007])
def test_a_cube_dropped_fast_onto_a_folded_cloth_never_pushes_one_layer_through_the_other(shift):
    """A 32 kg cube at 5 m/s, 1/60 s (8 cm a step against layers 2.5 cm apart), the layers
    aligned or nearly: the step closes the fold, so the cloth's own pairs in contact at the step's
    start are not enough; those in contact at the end of a solve join the contact set and the solve
    is done again (collision/pair_lists/own_pairs.py). With the start's pairs alone the cloth
    crossed itself (20 and 17 crossings)."""
    dt = 1.0 / 60.0
    simulation = cube_onto_folded_cloth(dt, 5.0, shift=shift, particle_mass=0.5)
    assert_the_cloth_never_crosses_itself(simulation, dt)


@pytest.mark.parametrize("dt, shift", [(1.0 / 60.0, 0.007), (1.0 / 60.0, 0.031),
                                       (1.0 / 30.0, 0.0), (1.0 / 30.0, 0.015)])
def test_a_heavy_cube_dropped_fast_onto_a_folded_cloth_never_pushes_it_through_itself(dt, shift):
    """A 128 kg cube at 5 m/s presses harder than the solve's penalty contacts hold within one
    step: with them alone the cloth crossed itself in each of these runs (1246, 1479, 3 and 807
    crossings). A step that carries a point through a triangle or an edge past an edge is taken
    again in halves (integrators/implicit_euler.implicit_euler_step): no edge of the cloth ever
    crosses one of its triangles or one of the cube's, and some steps were halved."""
    simulation = cube_onto_folded_cloth(dt, 5.0, shift=shift)
    triangles = simulation.model.arrays.surface_triangles
    of_cloth = simulation.model.arrays.particle_body[triangles[:, 0]] == 0
    for _ in range(round(1.0 / dt)):
        simulation.step(1)
        assert count_crossings(simulation.positions, triangles[of_cloth]) == 0, simulation.time
        assert len(crossing_pairs(simulation.positions, triangles[of_cloth],
                                  triangles[~of_cloth])) == 0, simulation.time
    assert simulation.integrator.statistics.halvings[0] > 0


def test_a_step_taken_in_halves_is_the_same_one_step_a_call_and_resumed():
    """The halving lives inside a step (integrators/implicit_euler.implicit_euler_step): the heavy drop stepped one step a
    call ends bit for bit where one call of 8 steps ends, and a fresh Simulation given the state
    just before a halved step takes that step as the run did."""
    dt = 1.0 / 30.0
    run = cube_onto_folded_cloth(dt, 5.0, shift=0.015)
    resumed = False
    for _ in range(8):
        halvings, before = run.integrator.statistics.halvings[0], run.state.copy()
        run.step(1)
        if run.integrator.statistics.halvings[0] > halvings and not resumed:
            fresh = cube_onto_folded_cloth(dt, 5.0, shift=0.015)
            fresh.state = before
            fresh.step(1)
            assert np.array_equal(fresh.positions, run.positions)
            resumed = True
    assert resumed
    whole = cube_onto_folded_cloth(dt, 5.0, shift=0.015)
    whole.step(8)
    assert np.array_equal(whole.positions, run.positions)


def test_a_copy_of_a_pressed_folded_cloth_steps_as_the_run_it_came_from():
    """Resuming: a fresh Simulation given the state of the run above at a step (its pair list
    found anew by a search, not the one the run kept) steps bit for bit as the run does: the
    solve takes only the own pairs in contact, which every list holds."""
    dt = 1.0 / 30.0
    run = cube_onto_folded_cloth(dt, 5.0)
    for _ in range(4):
        run.step(1)
    copy = cube_onto_folded_cloth(dt, 5.0)
    copy.state = run.state.copy()
    run.step(3)
    copy.step(3)
    assert np.array_equal(run.positions, copy.positions)


def test_a_state_set_on_a_running_simulation_steps_as_the_run_it_came_from():
    """The same for a Simulation that has stepped a state of its own first (the cloth lying
    flat: its pair list empty, and kept while nothing moves apart): given the pressed folded
    state, its first step must not take the cloth's own pairs from that list."""
    dt = 1.0 / 30.0
    run = cube_onto_folded_cloth(dt, 5.0)
    for _ in range(4):
        run.step(1)
    other = cube_onto_folded_cloth(dt, 5.0, folded=False)
    other.step(1)
    other.state = run.state.copy()
    run.step(3)
    other.step(3)
    assert np.array_equal(run.positions, other.positions)
