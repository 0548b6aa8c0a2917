"""Integrators: measured orders of accuracy against SciPy's DOP853, energy behaviour over many
periods, and free fall, where each method's result is known in closed form."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from springsim import Simulation, integrator_names
from springsim.reference import reference_forces
from springsim.springs import SpringParameters

NO_GRAVITY, EARTH_GRAVITY = (0.0, 0.0, 0.0), (0.0, -9.8, 0.0)

# A small contact-free problem: a 3 x 3 x 3 cube, squeezed, spinning and jittered, each spring kind
# with its own stiffness and damping, with drag, and no gravity. Its fastest mode has a period of
# about 0.4 s, so every step below resolves it and the errors are in the asymptotic range.
SMOOTH_PROBLEM = {"ks": 50.0, "kd": 0.5, "drag": 0.2, "shear": SpringParameters(25.0, 0.5),
                  "bend": SpringParameters(12.0, 0.25), "perturb_seed": 1}
END_TIME = 1.0  # s
STEPS = {  # dt (s) for each method, halving: errors from about 1e-2 down to 1e-6
    "explicit_euler": [2e-3, 1e-3, 5e-4, 2.5e-4],
    "symplectic_euler": [2e-3, 1e-3, 5e-4, 2.5e-4],
    "midpoint": [8e-3, 4e-3, 2e-3, 1e-3],
    "rk4": [4e-2, 2e-2, 1e-2, 5e-3],
}
ORDERS = {"explicit_euler": 1, "symplectic_euler": 1, "midpoint": 2, "rk4": 4}


def flat_state(simulation):
    return np.concatenate([simulation.positions.ravel(), simulation.velocities.ravel()])


@pytest.fixture(scope="module")
def smooth_reference(cube_simulation):
    """The smooth problem's state at END_TIME from DOP853 at rtol 1e-12, on the NumPy forces."""
    simulation = cube_simulation(**SMOOTH_PROBLEM)
    model, mass = simulation.model, simulation.model.mass[:, None]

    def derivative(_, y):
        x, v = y[:y.size // 2].reshape(-1, 3), y[y.size // 2:].reshape(-1, 3)
        return np.concatenate([v.ravel(), (reference_forces(model, x, v) / mass).ravel()])

    solution = solve_ivp(derivative, (0.0, END_TIME), flat_state(simulation), method="DOP853",
                         rtol=1e-12, atol=1e-12)
    assert solution.success
    return solution.y[:, -1]


@pytest.mark.parametrize("integrator", ORDERS)
def test_measured_order_of_accuracy(cube_simulation, smooth_reference, integrator):
    errors = []
    for dt in STEPS[integrator]:
        simulation = cube_simulation(integrator, dt, **SMOOTH_PROBLEM)
        simulation.step(int(round(END_TIME / dt)))
        errors.append(np.abs(flat_state(simulation) - smooth_reference).max())
    slope = np.polyfit(np.log(STEPS[integrator]), np.log(errors), 1)[0]
    assert slope == pytest.approx(ORDERS[integrator], abs=0.3), errors


def undamped_simulation(cube_simulation, integrator):
    """No dampers, drag, gravity or terrain: the total energy is a constant of the motion."""
    return cube_simulation(integrator, 1e-3, ks=50.0, kd=0.0, perturb_seed=1)


def energy_history(simulation, seconds, samples):
    history = [simulation.energy()["total"]]
    for _ in range(samples):
        simulation.advance(seconds / samples)
        history.append(simulation.energy()["total"])
    return np.array(history) / history[0] - 1.0  # relative change


# 10 s is about 25 periods of the fastest mode and 5 of the slowest
ENERGY_SECONDS, ENERGY_SAMPLES = 10.0, 100


def test_rk4_conserves_energy_to_a_tiny_drift(cube_simulation):
    drift = energy_history(undamped_simulation(cube_simulation, "rk4"), ENERGY_SECONDS,
                           ENERGY_SAMPLES)
    assert np.abs(drift).max() < 1e-6


def test_explicit_euler_gains_energy_every_sample(cube_simulation):
    """For a linear oscillator explicit Euler multiplies the energy by 1 + (omega h)^2 each step."""
    drift = energy_history(undamped_simulation(cube_simulation, "explicit_euler"),
                           ENERGY_SECONDS, ENERGY_SAMPLES)
    assert np.all(np.diff(drift) > 0)
    assert drift[-1] > 1.0  # more than doubled


def test_symplectic_euler_energy_stays_bounded(cube_simulation):
    """It oscillates by O(omega h) around the true energy, with no drift from start to end."""
    drift = energy_history(undamped_simulation(cube_simulation, "symplectic_euler"),
                           ENERGY_SECONDS, ENERGY_SAMPLES)
    assert np.abs(drift).max() < 0.02
    quarter = len(drift) // 4
    assert abs(drift[-quarter:].mean() - drift[:quarter].mean()) < 1e-3


# Free fall with every spring at rest: the acceleration is g, constant. After n steps of h:
#   exact (midpoint and rk4 integrate a quadratic exactly):  x0 + v0 t + g t^2 / 2,  v0 + g t
#   explicit Euler, x_{k+1} = x_k + h v_k:   x0 + v0 t + g h^2 n (n - 1) / 2  (sum of k, k < n)
#   symplectic Euler, x_{k+1} = x_k + h v_{k+1}: x0 + v0 t + g h^2 n (n + 1) / 2  (k = 1 .. n)
# and in every case v0 + g t, because v_{k+1} = v_k + h g.
FREE_FALL_SUM = {"midpoint": lambda n: n * n / 2, "rk4": lambda n: n * n / 2,
                 "explicit_euler": lambda n: n * (n - 1) / 2,
                 "symplectic_euler": lambda n: n * (n + 1) / 2}


@pytest.mark.parametrize("integrator", FREE_FALL_SUM)
def test_free_fall_matches_the_closed_form(cube_simulation, integrator):
    h, n = 0.004, 250
    v0 = np.array([1.0, 2.0, -0.5])
    simulation = cube_simulation(integrator, h, gravity=EARTH_GRAVITY, ks=50.0, kd=0.5,
                                 velocity=tuple(v0), position=(0.3, 5.0, -1.0))
    x0 = simulation.positions.copy()
    simulation.step(n)
    g, t = np.asarray(EARTH_GRAVITY), n * h
    expected_x = x0 + v0 * t + g * h * h * FREE_FALL_SUM[integrator](n)
    np.testing.assert_allclose(simulation.velocities, np.broadcast_to(v0 + g * t, x0.shape),
                               rtol=0, atol=1e-11)
    np.testing.assert_allclose(simulation.positions, expected_x, rtol=0, atol=1e-11)
    assert simulation.time == pytest.approx(t, rel=1e-15)


@pytest.mark.parametrize("integrator", integrator_names())
def test_reset_then_rerun_repeats_the_run_exactly(integrator):
    """Determinism: after reset() the same steps give bit-identical states (an implicit
    integrator's contact memory is reset too)."""
    from springsim import load_scene

    dt = 1 / 60 if integrator == "implicit_euler" else 1e-3
    steps = 30 if integrator == "implicit_euler" else 600
    overrides = ["bodies.0.particles_per_edge=4", "bodies.0.position=[0, 1.6667, 0]",
                 "bodies.0.velocity=[2, 0, 0]"]
    simulation = Simulation(load_scene("jelly-plane", overrides), integrator=integrator, dt=dt)
    simulation.step(steps)
    first = simulation.positions.copy()
    simulation.reset()
    assert simulation.time == 0.0
    simulation.step(steps)
    assert np.array_equal(simulation.positions, first)
