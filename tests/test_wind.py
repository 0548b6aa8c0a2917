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


def reference_wind_forces(arrays, x, v, t):
    """wind.add_wind_forces in NumPy, from the module's formulas: the keyed mean wind plus the
    mean of the gusts at a triangle's corners, relative to the mean of its corners' velocities;
    1/2 rho C_d A |w_n| w_n n + 1/2 rho C_f A |w_t| w_t, a third to each corner, times its
    weight; balls 1/2 rho C_d pi r^2 |w| w."""
    from springsim.render.drawing import mean_wind
    from springsim.wind import DENSITY, DRAG, FRICTION, STRENGTH

    settings, modes = arrays.wind_settings, arrays.wind_modes
    mean = mean_wind(arrays.wind_keys, t)
    speed = np.linalg.norm(mean)
    size = settings[STRENGTH] * (speed if speed > 0 else 1.0) / math.sqrt(max(len(modes), 1) / 2)

    def air(points):
        waves = np.sin(points @ modes[:, 3:6].T - modes[:, 6] * t + modes[:, 7])
        return mean + size * waves @ modes[:, 0:3]

    rho = settings[DENSITY]
    out = np.zeros_like(x)
    triangles = arrays.wind_triangles
    a, b, c = (triangles[:, k] for k in range(3))
    normal = np.cross(x[b] - x[a], x[c] - x[a])
    area = 0.5 * np.linalg.norm(normal, axis=1)
    normal /= 2 * area[:, None]
    gusted = (air(x[a]) + air(x[b]) + air(x[c])) / 3
    w = gusted - (v[a] + v[b] + v[c]) / 3
    w_n = np.sum(w * normal, axis=1)
    w_t = w - w_n[:, None] * normal
    force = (0.5 * rho * settings[DRAG] * (area * np.abs(w_n) * w_n)[:, None] * normal
             + 0.5 * rho * settings[FRICTION] * (area * np.linalg.norm(w_t, axis=1))[:, None] * w_t)
    for corner in (a, b, c):
        np.add.at(out, corner, force * arrays.wind_weights[:, None] / 3)
    for i in arrays.balls:
        w = air(x[i][None])[0] - v[i]
        size = 0.5 * rho * settings[DRAG] * math.pi * arrays.radius[i] ** 2
        out[i] += size * np.linalg.norm(w) * w
    return out


@pytest.mark.parametrize("gusts", [None, Gusts(0.3, 1.0, 4)])
def test_the_wind_kernel_is_its_formula(gusts):
    """add_wind_forces against its NumPy reference on a blown, crumpled cloth and a ball, in a
    wind keyed from +x to +z at a time between the keys, with and without gusts."""
    from springsim.wind import WindKey, add_wind_forces

    wind = Wind(keyframes=[WindKey(0.0, (5.0, 0.0, 0.0)), WindKey(1.0, (0.0, 1.0, 4.0))],
                friction=0.05, gusts=gusts)
    balls = Balls(balls=[Ball(position=(0.0, 1.0, 0.0), radius=0.1, mass=0.05)])
    scene = Scene(bodies=[Cloth(particles_per_edge=6, width=1.0, height=1.0), balls], wind=wind,
                  integrator="symplectic_euler", dt=1e-4)
    sim = springsim.Simulation(scene)
    rng = np.random.default_rng(3)
    x = sim.positions + 0.05 * rng.standard_normal(sim.positions.shape)
    v = rng.standard_normal(x.shape)
    arrays = sim.model.arrays
    arrays.clock[2] = 0.37   # the world's time, as move_world sets it
    out = np.zeros_like(x)
    add_wind_forces(arrays, x, v, np.ones(1), out)
    np.testing.assert_allclose(out, reference_wind_forces(arrays, x, v, 0.37), rtol=1e-11,
                               atol=1e-13)


def test_the_gusts_sine_is_the_c_library_sine():
    """wind.sine, the SIMD-friendly sine of the gusts, against NumPy's within an ulp or two,
    over a wave's first turns and over the range where its reduction is exact."""
    from numba import njit

    from springsim.wind import sine

    @njit
    def sines(angles):
        return np.array([sine(angle) for angle in angles])

    rng = np.random.default_rng(5)
    for angles in (np.linspace(-10.0, 10.0, 20001), rng.uniform(-1.6e6, 1.6e6, 20000)):
        np.testing.assert_allclose(sines(angles), np.sin(angles), rtol=0, atol=4e-16)


def test_the_wind_derivative_is_its_formula():
    """Backward Euler's wind pass: the same impulse h F as add_wind_forces, and each particle's
    diagonal block -h dF_i/dv_i equal to central differences of its force in its own velocity
    (exact here: with no friction along the surface, the force is quadratic in the velocity
    between sign changes), gusts and a ball included."""
    from springsim.wind import add_wind_forces, add_wind_with_jacobian

    wind = Wind(velocity=(5.0, 0.0, 1.0), friction=0.0, gusts=Gusts(0.3, 1.0, 4))
    balls = Balls(balls=[Ball(position=(0.0, 1.0, 0.0), radius=0.1, mass=0.05)])
    scene = Scene(bodies=[Cloth(particles_per_edge=5, width=1.0, height=1.0), balls], wind=wind,
                  integrator="implicit_euler", dt=1 / 60)
    sim = springsim.Simulation(scene)
    rng = np.random.default_rng(7)
    x = sim.positions + 0.05 * rng.standard_normal(sim.positions.shape)
    v = rng.standard_normal(x.shape)
    arrays = sim.model.arrays
    arrays.clock[2] = 0.37
    h, count = 1 / 60, len(x)
    impulse, blocks = np.zeros_like(x), np.zeros((count, 3, 3))
    add_wind_with_jacobian(arrays, np.arange(count), x, v, h, impulse, blocks)
    force = np.zeros_like(x)
    add_wind_forces(arrays, x, v, np.full(1, h), force)
    assert np.array_equal(impulse, force)
    eps = 1e-6
    for i in range(count):
        for c in range(3):
            plus, minus = v.copy(), v.copy()
            plus[i, c] += eps
            minus[i, c] -= eps
            f_plus, f_minus = np.zeros_like(x), np.zeros_like(x)
            add_wind_forces(arrays, x, plus, np.ones(1), f_plus)
            add_wind_forces(arrays, x, minus, np.ones(1), f_minus)
            derivative = (f_plus[i] - f_minus[i]) / (2 * eps)
            np.testing.assert_allclose(blocks[i, :, c], -h * derivative, rtol=1e-6, atol=1e-9)
