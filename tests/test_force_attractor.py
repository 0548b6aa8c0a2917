"""The worked example of a force added as one file (terms/attractor.py, docs/architecture.md):
a particle pulled to a point moves as the harmonic oscillator does, under the explicit methods
(x(t) = p + A cos(w t), w = sqrt(k/m)) and under backward Euler, step by step, as its linear
recursion; the gradients through it match finite differences; bad values are one line; a
scene file names it in ``[[forces]]``."""
import numpy as np
import pytest

from springsim.bodies.balls import Ball, Balls
from springsim.errors import SceneError
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.terms.attractor import Attractor
from test_gradients import assert_gradients_match, small_scene

POINT = np.array([0.5, 1.0, -0.25])
K, MASS, AMPLITUDE = 8.0, 0.5, 0.3


def lone_ball(damping=0.0):
    ball = Ball(position=tuple(POINT + (AMPLITUDE, 0.0, 0.0)), velocity=(0.0, 0.0, 0.0),
                radius=0.05, mass=MASS)
    return Scene(bodies=[Balls(balls=[ball], drag=0.0)], terrains=[], gravity=(0.0, 0.0, 0.0),
                 forces=[Attractor(point=tuple(POINT), stiffness=K, damping=damping)])


def test_the_explicit_methods_oscillate_harmonically():
    sim = Simulation(lone_ball(), integrator="rk4", dt=1e-3)
    sim.step(1000)
    omega = np.sqrt(K / MASS)
    expected = POINT + (AMPLITUDE * np.cos(omega * 1.0), 0.0, 0.0)
    np.testing.assert_allclose(sim.positions[0], expected, atol=1e-9)
    np.testing.assert_allclose(sim.velocities[0], (-AMPLITUDE * omega * np.sin(omega), 0.0, 0.0),
                               atol=1e-8)


def test_backward_euler_follows_its_recursion():
    """(m + h d + h^2 k) v' = m v + h (k (p - x) - d v) + ... : for one particle the linear
    solve is exact, so 30 steps of h = 1/30 s follow the recursion to round-off."""
    h, damping = 1 / 30, 0.2
    sim = Simulation(lone_ball(damping), integrator="implicit_euler", dt=h)
    sim.step(30)
    x, v = POINT + (AMPLITUDE, 0.0, 0.0), np.zeros(3)
    for _ in range(30):
        v = (MASS * v + h * K * (POINT - x)) / (MASS + h * damping + h * h * K)
        x = x + h * v
    np.testing.assert_allclose(sim.positions[0], x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.velocities[0], v, rtol=0, atol=1e-12)
    assert np.linalg.norm(x - POINT) < 0.5 * AMPLITUDE   # and it damps, as backward Euler does


def attracted_cube():
    scene = small_scene()
    scene.forces = [Attractor(point=(0.5, 1.0, 0.0), stiffness=50.0, damping=0.5)]
    return scene


@pytest.mark.parametrize("integrator", ["rk4", "implicit_euler"])
def test_gradients_through_it_match_finite_differences(integrator):
    assert_gradients_match(attracted_cube, integrator,
                           ["bodies.0.structural.ks", "bodies.0.velocity", "drag"])


@pytest.mark.parametrize("change, message", [
    ({"stiffness": -1.0}, "forces.0.stiffness = -1.0: must be >= 0 N/m"),
    ({"point": (0.0, 1.0)}, "forces.0.point"),
    ({"bodies": [3]}, "forces.0.bodies = 3: must be body numbers from 0 to 0"),
])
def test_bad_values_are_one_line(change, message):
    scene = lone_ball()
    for key, value in change.items():
        setattr(scene.forces[0], key, value)
    with pytest.raises(SceneError) as caught:
        scene.validate()
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_a_scene_file_names_it(tmp_path):
    from springsim.scenefile import load_scene, scene_to_toml

    path = tmp_path / "pulled.toml"
    path.write_text('gravity = [0.0, 0.0, 0.0]\nintegrator = "rk4"\ndt = 0.001\n\n[[bodies]]\ntype = "cube"\n'
                    '\n[[forces]]\ntype = "attractor"\npoint = [0.0, 2.0, 0.0]\nstiffness = 3.0\n')
    scene = load_scene(str(path), ["forces.0.damping=0.25"])
    assert scene.forces == [Attractor(point=(0.0, 2.0, 0.0), stiffness=3.0, damping=0.25)]
    assert 'type = "attractor"' in scene_to_toml(scene)
    with pytest.raises(SceneError) as caught:
        load_scene(str(path), ["forces.0.type=magnet"])
    assert "attractor" in str(caught.value)
