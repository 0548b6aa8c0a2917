"""The viewer's panel logic, driven with no window.

Oracles: the mouse spring on a free particle follows the closed form of a critically damped
oscillator, with first-order convergence in dt; the figures are the exact rates of a synthetic
clock; each control changes exactly the model arrays the kernels read (and keeps or resets the
state as documented); a cube's new height and rotation put its lattice where geometry says; a
diverging setting stops the run with the course's message and a reset recovers.
"""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.springs import SpringKind, SpringParameters
from springsim.terrains import Bowl
from springsim.viewer.controls import UNSTABLE_MESSAGE, Controls, real_time_steps
from springsim.viewer.frame_stats import FrameStats
from springsim.viewer.mouse_spring import nearest_particle, point_on_drag_plane

NO_SPRINGS = SpringParameters(0.0, 0.0)


def free_particles(dt: float) -> Scene:
    """Eight unconnected particles with no gravity and no terrain: only the mouse acts."""
    cube = Cube(particles_per_edge=2, structural=NO_SPRINGS, shear=NO_SPRINGS, bend=NO_SPRINGS)
    return Scene(name="free", bodies=[cube], terrains=[], gravity=(0.0, 0.0, 0.0), dt=dt)


def pulled_error(dt: float, seconds: float = 0.5, omega: float = 10.0) -> float:
    controls = Controls(free_particles(dt))
    controls.mouse.stiffness_per_mass = omega ** 2
    start = controls.sim.positions[3].copy()
    pull = np.array([0.6, -0.3, 0.2])
    controls.grab(3, start + pull)
    controls.set_steps_per_frame(round(seconds / dt))
    controls.resume()
    controls.advance_frame(now=0.0)
    t = controls.sim.time
    # x'' = w^2 (T - x) - 2 w x', x(0) = T - d, x'(0) = 0  =>  x = T - d (1 + w t) e^(-w t)
    exact = start + pull - pull * (1 + omega * t) * math.exp(-omega * t)
    others = np.delete(controls.sim.positions, 3, axis=0)
    assert np.array_equal(others, np.delete(controls.sim.model.initial_positions, 3, axis=0))
    return float(np.linalg.norm(controls.sim.positions[3] - exact))


def test_mouse_spring_is_a_critically_damped_spring_of_first_order_in_dt():
    coarse, fine = pulled_error(2e-3), pulled_error(1e-3)
    assert fine < 5e-3                    # metres, for a pull of 0.7 m
    assert 1.7 < coarse / fine < 2.3      # the impulse is applied explicitly: order 1


def test_mouse_spring_is_capped_to_stay_stable_for_large_steps():
    controls = Controls(free_particles(0.05))
    controls.mouse.stiffness_per_mass = 1e6          # w h = 50 uncapped: it would explode
    controls.grab(0, controls.sim.positions[0] + 1.0)
    controls.set_steps_per_frame(200)
    controls.resume()
    controls.advance_frame(now=0.0)
    assert not controls.unstable
    assert np.allclose(controls.sim.positions[0], controls.mouse.target, atol=1e-6)


def test_picking_geometry():
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    assert nearest_particle(positions, (0.9, 0.1, 0.0), within=0.2) == 1
    assert nearest_particle(positions, (5.0, 5.0, 5.0), within=0.2) == -1
    # a ray from (0, 0, 10) towards -z meets the plane z = 1 at (0, 0, 1)
    point = point_on_drag_plane(np.array([0.0, 0.0, 10.0]), np.array([0.0, 0.0, -1.0]),
                                (3.0, 4.0, 1.0), (0.0, 0.0, 1.0))
    assert np.allclose(point, (0.0, 0.0, 1.0))
    assert point_on_drag_plane(np.zeros(3), np.array([1.0, 0.0, 0.0]), (0, 0, 1), (0, 0, 1)) is None


def test_frame_stats_are_the_rates_of_the_clock():
    stats = FrameStats(window=0.5)
    dt, steps, interval = 1e-3, 10, 0.02
    for frame in range(60):
        stats.frame(now=frame * interval, steps=steps, sim_seconds=steps * dt)
    assert stats.fps == pytest.approx(1 / interval)
    assert stats.steps_per_second == pytest.approx(steps / interval)
    assert stats.real_time_factor == pytest.approx(steps * dt / interval)


def test_start_resets_step_advances_one_frame_and_time_follows_dt():
    controls = Controls("jelly-plane")
    assert controls.steps_per_frame == real_time_steps(1e-3) == 17
    assert controls.step_frame() == 17 and controls.sim.time == pytest.approx(0.017)
    controls.set_dt(5e-4)
    controls.set_steps_per_frame(4)
    controls.resume()
    controls.advance_frame(now=0.0)
    assert controls.sim.time == pytest.approx(0.017 + 4 * 5e-4)   # state kept across set_dt
    controls.start()
    assert controls.sim.time == 0.0 and controls.running


def test_physics_settings_change_the_kernel_arrays_and_keep_the_state():
    controls = Controls("jelly-plane")
    controls.step_frame()
    before = controls.sim.positions.copy()
    assert controls.set_spring(SpringKind.SHEAR, ks=3000.0, kd=40.0)
    assert controls.set_restitution(0.25) and controls.set_friction(0.7)
    assert controls.set_drag(0.5)
    assert controls.set_integrator("midpoint")
    sim = controls.sim
    arrays = sim.model.arrays
    shear = sim.model.spring_kind == SpringKind.SHEAR
    assert np.all(arrays.group_ks[arrays.spring_group[shear]] == 3000.0)
    assert np.all(arrays.group_kd[arrays.spring_group[shear]] == 40.0)
    assert np.all(arrays.group_ks[arrays.spring_group[~shear]] == 2000.0)
    assert arrays.terrain_restitution[0] == 0.25 and arrays.terrain_friction[0] == 0.7
    assert np.all(arrays.drag == 0.5) and sim.integrator.name == "midpoint"
    assert np.array_equal(sim.positions, before) and sim.time == pytest.approx(0.017)
    assert controls.spring(SpringKind.SHEAR) == SpringParameters(3000.0, 40.0)


def test_body_settings_rebuild_the_cube_where_geometry_puts_it():
    controls = Controls("jelly-plane")
    controls.step_frame()
    assert controls.set_particles_per_edge(4)
    assert controls.sim.model.particle_count == 64 and controls.sim.time == 0.0
    assert controls.set_cube_height(12.0)
    x = controls.sim.positions
    spacing = 4.0 / 3
    # lattice offsets (i - N//2) spacing, i = 0..3: their mean is -0.5 spacing
    assert x.mean(axis=0)[1] == pytest.approx(12.0 - 0.5 * spacing)
    assert controls.set_cube_rotation(90.0)
    rotated = controls.sim.positions
    lattice = (np.indices((4, 4, 4)).reshape(3, -1).T - 2) * spacing
    axis = np.array([1.0, 0.0, 1.0]) / math.sqrt(2)
    expected = Rotation.from_rotvec(math.pi / 2 * axis).apply(lattice) + (0.0, 12.0, 0.0)
    assert np.allclose(rotated, expected)


def test_body_contact_settings_change_the_kernel_arrays_and_keep_the_state():
    """A cloth of 5 x 5 particles 1 m apart over a cube: thickness and self-collision reach
    the arrays the contact kernels read; a self-colliding thickness of half the spacing or more,
    or beyond 1 m, is refused with SceneError's one line and the old simulation kept."""
    scene = Scene(name="cloth over cube", bodies=[
        Cube(particles_per_edge=3, position=(0.0, 1.0, 0.0)),
        Cloth(particles_per_edge=5, position=(0.0, 6.0, 0.0))], dt=1e-4)
    controls = Controls(scene)
    assert [(n, name) for n, name, _ in controls.contact_bodies()] == [(0, "cube0"), (1, "cloth1")]
    controls.step_frame()
    before, time = controls.sim.positions.copy(), controls.sim.time
    assert controls.set_thickness(1, 0.3) and controls.set_self_collision(0, True)
    arrays = controls.sim.model.arrays
    assert arrays.body_thickness.tolist() == [0.05, 0.3]
    assert arrays.body_self_collision.tolist() == [True, True]
    assert np.array_equal(controls.sim.positions, before) and controls.sim.time == time
    sim = controls.sim
    assert not controls.set_thickness(1, 0.5)            # half of the 1 m spacing
    assert controls.sim is sim and controls.message.startswith("bodies.1.thickness = 0.5")
    assert "\n" not in controls.message
    assert controls.set_self_collision(1, False) and controls.set_thickness(1, 0.5)
    assert controls.message == "" and controls.sim.model.arrays.body_thickness[1] == 0.5
    assert not controls.set_thickness(0, 1.5) and "bodies.0.thickness" in controls.message


def test_an_edit_that_keeps_the_motion_finds_its_own_pair_lists():
    """The state's pair lists were found for the old model: its surfaces, numbered its way,
    and its thicknesses, which decide how far a list reaches. An edit that keeps the motion
    (a thicker cube on the pile) keeps positions and velocities but not the lists: the new
    model finds its own at its next step, as a fresh run does."""
    controls = Controls("jelly-stack")
    controls.sim.advance(1.2)   # the cubes lie on each other: pairs in the list
    assert len(controls.sim.state.pairs.points) > 0
    before = controls.sim.positions.copy()
    assert controls.set_thickness(1, 0.2)
    sim = controls.sim
    assert np.array_equal(sim.positions, before)
    assert len(sim.state.pairs.points) == 0 and len(sim.state.pairs.found_at) == 0
    fresh = Simulation(sim.scene, threads=1)
    fresh.state = sim.state.copy()
    sim.step(1)
    fresh.step(1)
    assert np.array_equal(sim.positions, fresh.positions)
    assert len(sim.state.pairs.found_at) == sim.model.particle_count


def test_terrain_buttons_and_a_bad_setting_keep_the_old_simulation():
    controls = Controls("jelly-plane")
    assert controls.choose_terrain("bowl")
    assert isinstance(controls.sim.model.terrains[0], Bowl) and controls.terrain_name() == "bowl"
    assert controls.choose_terrain("tilted plane") and controls.terrain_name() == "tilted plane"
    assert controls.choose_terrain("none") and controls.sim.model.terrains == ()
    assert controls.choose_terrain("plane")
    sim = controls.sim
    assert not controls.set_cube_height(0.0)          # the cube would start inside the plane
    assert controls.sim is sim and "bodies.0.position" in controls.message
    assert not controls.set_dt(-1.0) and controls.sim is sim and "dt" in controls.message
    assert not controls.choose_scene("no-such-scene") and controls.sim is sim


def test_divergence_stops_the_run_with_the_message_and_reset_recovers():
    controls = Controls("jelly-plane")
    controls.set_particles_per_edge(4)
    controls.set_cube_height(3.0)
    controls.set_integrator("explicit_euler")
    controls.set_dt(0.01)                              # far past explicit Euler's limit
    controls.start()
    for frame in range(100):
        controls.advance_frame(now=frame / 60)
        if controls.unstable:
            break
    assert controls.unstable and not controls.running
    assert controls.message.startswith(UNSTABLE_MESSAGE)
    frozen = controls.sim.time
    controls.advance_frame(now=2.0)
    assert controls.step_frame() == 0 and controls.sim.time == frozen
    controls.resume()
    assert not controls.running                        # no running on from a diverged state
    assert controls.set_dt(1e-3)                       # change a setting, then reset
    controls.reset()
    assert not controls.unstable and controls.message == "" and controls.sim.time == 0.0
    controls.start()
    controls.advance_frame(now=3.0)
    assert controls.sim.time == pytest.approx(controls.steps_per_frame * 1e-3)
