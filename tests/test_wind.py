"""Wind (wind.py): the flat-plate terminal speed, gusts that are deterministic, bad input."""
import math

import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.bodies.cloth_material import ClothMaterial
from springsim.errors import SceneError
from springsim.scene import Scene
from springsim.wind import Gusts, Wind

# the reference cloth's springs want 0.1 ms steps of the explicit methods (cloth-balls' dt)
STEPS = {"symplectic_euler": 1e-4, "rk4": 1e-4, "implicit_euler": 1 / 60}


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_flat_cloth_falls_face_down_at_the_flat_plate_terminal_speed(integrator):
    """A free 1 m x 1 m sheet of 4 kg in still air (rho = 1.2, C_d = 1.2): v = sqrt(2 m g /
    (rho C_d A)), 7.4 m/s. Its mass is spread by area (a material), as the air's force is, so
    that it falls flat."""
    cloth = Cloth(particles_per_edge=5, width=1.0, height=1.0, pinned="none", drag=0.0,
                  material=ClothMaterial(density=4.0))
    scene = Scene(bodies=[cloth], wind=Wind(density=1.2, drag=1.2), integrator=integrator,
                  dt=STEPS[integrator])
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    sim.advance(4.0)
    terminal = math.sqrt(2 * 4.0 * 9.8 / (1.2 * 1.2 * 1.0))
    assert -sim.velocities[:, 1].mean() == pytest.approx(terminal, rel=2e-3)


@pytest.mark.parametrize("integrator", ["rk4", "implicit_euler"])
def test_a_ball_in_wind_reaches_the_wind_speed_and_gusts_are_deterministic(integrator):
    ball = Balls(balls=[Ball(position=(0.0, 0.0, 0.0), radius=0.1, mass=0.05)], drag=0.0)
    runs = []
    for seed in (1, 1, 2):
        scene = Scene(bodies=[ball], gravity=(0.0, 0.0, 0.0), integrator=integrator,
                      dt=STEPS[integrator],
                      wind=Wind(velocity=(3.0, 0.0, 0.0), gusts=Gusts(0.3, 1.0, seed)))
        scene.validate()
        sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
        sim.advance(3.0)
        runs.append(sim.velocities.copy())
    assert np.array_equal(runs[0], runs[1]) and not np.array_equal(runs[0], runs[2])
    assert runs[0][0, 0] == pytest.approx(3.0, abs=1.0)   # carried along, gusting about 3 m/s


@pytest.mark.parametrize("table, key", [
    ({"density": -1.0}, "wind.density"),
    ({"keyframes": [{"time": 1.0}, {"time": 1.0}]}, "wind.keyframes.1.time"),
    ({"gusts": {"length": 0.0}}, "wind.gusts.length"),
])
def test_bad_wind_is_one_line_naming_the_key(table, key):
    from springsim.scenefile import scene_from_table

    with pytest.raises(SceneError) as raised:
        scene_from_table({"bodies": [{"type": "balls"}], "wind": table}).validate()
    assert raised.value.key == key
