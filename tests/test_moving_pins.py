"""Pins that move (bodies/pins.py, world.py): hard pins exactly on their paths under every
integrator, pins that follow a terrain, soft pins, and bad input."""
import numpy as np
import pytest

import springsim
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.bodies.pins import Pin, Region
from springsim.errors import SceneError
from springsim.motion import Keyframe, Motion
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.terrains import Sphere

# the reference cloth's springs want 0.1 ms steps of the explicit methods (cloth-balls' dt)
STEPS = {"explicit_euler": 1e-4, "symplectic_euler": 1e-4, "midpoint": 1e-4, "rk4": 1e-4,
         "predict_reevaluate": 1e-4, "implicit_euler": 1 / 60}
CORNER = Region(min=(0.9, -0.1, 0.9), max=(1.1, 0.1, 1.1))   # the cloth's (+x, +z) corner


def carried_cloth(motion):
    """A 5 x 5 cloth, 2 m wide, its (+x, +z) corner carried by ``motion``, another held."""
    return Cloth(particles_per_edge=5, width=2.0, height=2.0, pinned="none",
                 pins=[Pin(region=CORNER, motion=motion), Pin(particles=[0])])


MOTION = Motion(keyframes=[Keyframe(0.0), Keyframe(0.1, (0.0, 0.5, 0.0), 30.0, (0.0, 1.0, 0.0)),
                           Keyframe(0.25, (0.5, 0.5, -0.5), 90.0, (0.0, 1.0, 0.0))],
                interpolation="smooth", pivot=(0.0, 0.0, 0.0))


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_pinned_particle_is_on_its_keyframed_path_at_every_step(integrator):
    scene = Scene(bodies=[carried_cloth(MOTION)], integrator=integrator, dt=STEPS[integrator])
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    corner, start = 24, sim.positions[24].copy()
    steps = round(0.3 / STEPS[integrator])
    worst = 0.0
    for _ in range(min(steps, 60)):
        sim.step(steps // min(steps, 60))
        path = MOTION.place([start], sim.time)[0]
        worst = max(worst, np.abs(sim.positions[corner] - path).max())
        assert np.array_equal(sim.positions[0], [-1.0, 0.0, -1.0])   # the held one holds
    assert worst < 1e-14
    assert np.abs(sim.positions[corner] - start).max() > 0.4   # it was carried


@pytest.mark.parametrize("integrator", ["rk4", "implicit_euler"])
def test_a_pin_following_a_terrain_keeps_its_place_in_the_terrains_frame(integrator):
    ball = Sphere(center=(0.0, 1.0, 0.0), radius=0.2,
                  motion=Motion(velocity=(0.5, 0.0, 0.0), angular_velocity=(0.0, 3.0, 0.0)))
    cloth = Cloth(particles_per_edge=5, width=2.0, height=2.0, position=(0.0, 0.5, 0.0),
                  pinned="none", pins=[Pin(particles=[12, 13], follow="terrains.0")])
    scene = Scene(bodies=[cloth], terrains=[ball], integrator=integrator, dt=STEPS[integrator])
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    start = sim.positions[[12, 13]].copy()
    sim.advance(0.2)
    assert np.abs(sim.positions[[12, 13]] - ball.place_at(start, sim.time)).max() < 1e-13


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler"])
@pytest.mark.parametrize("follow", ["", "terrains.0"])
def test_a_soft_pin_holds_with_its_stiffness(integrator, follow):
    """Four particles of a free 2 x 2 cloth, each on a soft pin of k = 100 N/m, sag by m g / k;
    following a terrain that stands still is holding too."""
    cloth = Cloth(particles_per_edge=2, width=1.0, height=1.0,
                  bend=SpringParameters(0.0, 0.0), pinned="none", particle_mass=0.1,
                  pins=[Pin(particles=[0, 1, 2, 3], stiffness=100.0, damping=2.0,
                            follow=follow)])
    scene = Scene(bodies=[cloth], terrains=[Sphere(center=(0.0, -5.0, 0.0), radius=1.0)],
                  integrator=integrator, dt=STEPS[integrator])
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    sim.advance(3.0)
    assert sim.positions[:, 1] == pytest.approx(-0.1 * 9.8 / 100.0, rel=1e-4)


def test_pins_on_a_cube_carry_it():
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 1.0, 0.0),
                pins=[Pin(region=Region(min=(-1, 1.4, -1), max=(1, 1.6, 1)),
                          motion=Motion(velocity=(1.0, 0.0, 0.0)))])
    scene = Scene(bodies=[cube], integrator="implicit_euler", dt=1 / 60)
    scene.validate()
    sim = springsim.Simulation(scene, integrator="implicit_euler", dt=1 / 60)
    sim.advance(1.0)
    assert sim.positions[:, 0].mean() == pytest.approx(1.0, abs=0.05)


@pytest.mark.parametrize("pin, key, words", [
    (Pin(region=Region(min=(5, 5, 5), max=(6, 6, 6))), "bodies.0.pins.0", "no particle"),
    (Pin(particles=[0], follow="terrains.3"), "bodies.0.pins.0.follow", "names no terrain"),
    (Pin(particles=[0], follow="terrain 1"), "bodies.0.pins.0.follow", "terrains.N"),
    (Pin(particles=[0], stiffness=-1.0), "bodies.0.pins.0.stiffness", "> 0"),
    (Pin(particles=[0], motion=Motion(keyframes=[Keyframe(1.0), Keyframe(0.5)])),
     "bodies.0.pins.0.motion.keyframes.1.time", "increasing"),
])
def test_bad_pins_are_one_line_naming_the_key(pin, key, words):
    scene = Scene(bodies=[Cloth(particles_per_edge=3, pinned="none", pins=[pin])],
                  terrains=[Sphere(center=(0.0, -5.0, 0.0), radius=1.0)])
    with pytest.raises(SceneError) as raised:
        scene.validate()
    assert raised.value.key == key and words in str(raised.value)
