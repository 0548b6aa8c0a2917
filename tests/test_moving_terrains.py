"""Terrains that move (motion.py, world.py): contact relative to the surface's velocity, under
every integrator; no tunnelling at frame-size steps; resumed runs equal uninterrupted ones."""
import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.motion import Keyframe, Motion
from springsim.scene import Scene
from springsim.terrains import Plane, Sphere

STEPS = {"explicit_euler": 1e-3, "symplectic_euler": 1e-3, "midpoint": 1e-3, "rk4": 1e-3,
         "predict_reevaluate": 1e-3, "implicit_euler": 1 / 60}


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_ball_leaves_a_wall_moving_into_it_by_the_relative_restitution_formula(integrator):
    """A wall moving at u = 2 m/s hits a ball at rest (e = 0.8, no gravity): the ball leaves at
    v' = u + e (u - v) = 3.6 m/s."""
    scene = Scene(bodies=[Balls(balls=[Ball(position=(1.0, 0.0, 0.0), radius=0.1, mass=1.0)],
                                drag=0.0)],
                  terrains=[Plane(point=(0.0, 0.0, 0.0), normal=(1.0, 0.0, 0.0), restitution=0.8,
                                  friction=0.0, motion=Motion(velocity=(2.0, 0.0, 0.0)))],
                  gravity=(0.0, 0.0, 0.0))
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    sim.advance(0.8)
    assert sim.velocities[0] == pytest.approx([3.6, 0.0, 0.0], abs=1e-9)


def platform_scene(integrator):
    """A 3 x 3 x 3 jelly cube resting on a floor that speeds up to 1 m/s along x (in steps of
    0.25 to 0.5 m/s, each taken up by friction within 0.2 s), rides at 1 m/s, and stops half a
    step after 2 s: a step that ends at 2 s sees it moving whichever way its end time rounds
    (at a step's end of exactly 2 s it would already be at rest)."""
    stop = 2.0 + STEPS[integrator] / 2
    keys = [Keyframe(0.0), Keyframe(0.5, (0.125, 0.0, 0.0)), Keyframe(1.0, (0.5, 0.0, 0.0)),
            Keyframe(stop, (stop - 0.5, 0.0, 0.0))]
    floor = Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0), restitution=0.0, friction=0.5,
                  motion=Motion(keyframes=keys))
    cube = Cube(particles_per_edge=3, edge_length=0.5, particle_mass=1.0, position=(0.0, 0.26, 0.0),
                rotation_degrees=0.0)
    return Scene(bodies=[cube], terrains=[floor], integrator=integrator, dt=STEPS[integrator])


@pytest.mark.parametrize("integrator", ["symplectic_euler", "midpoint", "rk4", "predict_reevaluate",
                                        "implicit_euler"])
def test_a_cube_rides_a_moving_platform_then_slides_with_g_mu_deceleration(integrator):
    scene = platform_scene(integrator)
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    sim.advance(1.9)
    riding = sim.velocities.mean(axis=0)
    assert riding[0] == pytest.approx(1.0, abs=0.01)   # static friction: carried along
    sim.advance(0.1)   # the platform stops within the next step
    start, stopped_at = sim.velocities.mean(axis=0)[0], sim.positions.mean(axis=0)[0]
    sim.advance(0.1)
    decelerated = start - sim.velocities.mean(axis=0)[0]
    assert decelerated / 0.1 == pytest.approx(0.5 * 9.8, rel=0.05)   # kinetic friction, g mu
    sim.advance(0.4)   # it stops (the jelly rocks a little), having slid v^2 / (2 g mu)
    slid = sim.positions.mean(axis=0)[0] - stopped_at
    # less what a first-order method loses of it: backward Euler moves each step at the step's
    # end velocity, h v / 2 short in all (0.008 m at 1/60 s, 0.0005 m at 1 ms)
    expected = 1.0 / (2 * 0.5 * 9.8) - STEPS[integrator] * 1.0 / 2
    assert slid == pytest.approx(expected, rel=0.06)
    assert abs(sim.velocities.mean(axis=0)[0]) < 0.01


def curtain_scene(speed):
    """A 2 m curtain (10 x 10, pinned along its top edge) and a sphere of radius 0.3 passing
    through its middle along z at ``speed`` m/s."""
    curtain = Cloth(particles_per_edge=10, width=2.0, height=2.0, position=(0.0, 1.0, 0.0),
                    rotation_degrees=-90.0, rotation_axis=(1.0, 0.0, 0.0), pinned="edge")
    travel = 2.0
    ball = Sphere(center=(0.0, 1.0, -1.0), radius=0.3, friction=0.3, restitution=0.0,
                  motion=Motion(keyframes=[Keyframe(0.0), Keyframe(travel / speed,
                                                                    (0.0, 0.0, travel))]))
    return Scene(bodies=[curtain], terrains=[ball], integrator="implicit_euler", dt=1 / 60)


# backward Euler at a frame's step; the explicit methods at the reference cloth's 0.1 ms
CURTAIN_STEPS = [("implicit_euler", 1 / 60), ("symplectic_euler", 1e-4), ("rk4", 1e-4)]


@pytest.mark.parametrize("integrator, dt", CURTAIN_STEPS)
@pytest.mark.parametrize("speed", [5.0, 10.0])
def test_no_curtain_particle_ends_inside_a_sphere_sweeping_through_it(speed, integrator, dt):
    scene = curtain_scene(speed)
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=dt)
    sphere = scene.terrains[0]
    deepest = 0.0
    pushed = 0.0
    for _ in range(round(0.4 / dt)):
        sim.step(1)
        centre = sphere.place_at([sphere.center], sim.time)[0]
        distance = np.linalg.norm(sim.positions - centre, axis=1) - sphere.radius
        deepest = min(deepest, distance.min())
        pushed = max(pushed, sim.positions[:, 2].max())
    assert deepest > -1e-9
    assert pushed > 0.5   # the sphere carried the curtain along: it did not pass through


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_run_resumed_mid_motion_equals_the_uninterrupted_run_bit_for_bit(integrator, tmp_path):
    scene = platform_scene(integrator)
    scene.terrains[0].motion.interpolation = "smooth"
    steps = 120 if integrator == "implicit_euler" else 1200
    whole = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    whole.step(steps // 2)
    whole.save_state(tmp_path / "half.npz")
    whole.step(steps // 2)
    resumed = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    resumed.load_state(tmp_path / "half.npz")
    resumed.step(steps // 2)
    assert np.array_equal(resumed.positions, whole.positions)
    assert np.array_equal(resumed.velocities, whole.velocities)
