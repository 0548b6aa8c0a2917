"""Forces: internal forces conserve momentum and angular momentum, and the Numba kernels agree with
the plain NumPy reference to round-off."""
import numpy as np
import pytest

from springsim.forces import accelerations, force_columns, forces
from springsim.reference import reference_forces
from springsim.springs import SpringParameters

NO_GRAVITY, EARTH_GRAVITY = (0.0, 0.0, 0.0), (0.0, -9.8, 0.0)

# several models: one stiffness everywhere; each kind its own; face springs; pinned corners
MODELS = {
    "uniform": {"particles_per_edge": 3},
    "per-kind": {"particles_per_edge": 4, "structural": SpringParameters(2000.0, 60.0),
                 "shear": SpringParameters(700.0, 5.0), "bend": SpringParameters(150.0, 0.0)},
    "face-springs": {"particles_per_edge": 5, "face_springs": True,
                     "face": SpringParameters(300.0, 9.0), "edge_length": 4.0},
    "pinned": {"particles_per_edge": 4, "pinned": (0, 3, 60, 63)},
    "two": {"particles_per_edge": 2, "bend": SpringParameters(0.0, 0.0)},
}


def random_state(simulation, seed):
    """A deformed, moving state: positions jittered by about 10 % of the spacing."""
    rng = np.random.default_rng(seed)
    model = simulation.model
    x0 = model.initial_positions
    spacing = model.scene_bodies[0].edge_length / (model.scene_bodies[0].particles_per_edge - 1)
    x = x0 + 0.1 * spacing * rng.standard_normal(x0.shape)
    v = rng.standard_normal(x0.shape)
    v[simulation.model.pinned] = 0.0
    return x, v


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_internal_forces_have_zero_sum_and_zero_torque(cube_simulation, name, seed):
    simulation = cube_simulation(gravity=NO_GRAVITY, drag=0.0, ks=120.0, kd=3.0,
                                 **MODELS[name])
    x, v = random_state(simulation, seed)
    f = forces(simulation.model.arrays, x, v)
    scale = np.abs(f).max()
    assert scale > 1.0  # the state really is deformed
    np.testing.assert_allclose(f.sum(axis=0), 0.0, atol=1e-12 * scale * len(f))
    torque = np.cross(x, f).sum(axis=0)
    np.testing.assert_allclose(torque, 0.0, atol=1e-12 * scale * np.abs(x).max() * len(f))


@pytest.mark.parametrize("name", MODELS)
@pytest.mark.parametrize("gravity, drag", [(NO_GRAVITY, 0.0), (EARTH_GRAVITY, 0.7)])
def test_numba_forces_match_the_reference(cube_simulation, name, gravity, drag):
    simulation = cube_simulation(gravity=gravity, drag=drag, ks=80.0, kd=2.0, **MODELS[name])
    model = simulation.model
    for seed in range(3):
        x, v = random_state(simulation, seed)
        expected = reference_forces(model, x, v)
        scale = np.abs(expected).max()
        np.testing.assert_allclose(forces(model.arrays, x, v), expected, rtol=0,
                                   atol=1e-13 * scale)


@pytest.mark.parametrize("name", MODELS)
def test_accelerations_without_terrain_are_force_over_mass(cube_simulation, name):
    simulation = cube_simulation(gravity=EARTH_GRAVITY, drag=0.4, ks=80.0, kd=2.0,
                                 particle_mass=0.35, **MODELS[name])
    model = simulation.model
    x, v = random_state(simulation, 7)
    a = np.full_like(x, np.nan)  # every entry must be written
    accelerations(model.arrays, x, v, 1e-3, a, force_columns(a))
    expected = reference_forces(model, x, v) * model.arrays.inv_mass[:, None]
    np.testing.assert_allclose(a, expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    assert np.all(a[model.pinned] == 0.0)


def test_gravity_alone_gives_g_and_drag_alone_gives_minus_c_v_over_m(cube_simulation):
    simulation = cube_simulation(gravity=EARTH_GRAVITY, drag=0.5, ks=0.0, kd=0.0,
                                 particle_mass=2.0)
    x, v = random_state(simulation, 3)
    a = np.empty_like(x)
    accelerations(simulation.model.arrays, x, v, 1e-3, a, force_columns(a))
    np.testing.assert_allclose(a, np.asarray(EARTH_GRAVITY) - 0.5 * v / 2.0, rtol=1e-15,
                               atol=1e-15)


def test_dampers_dissipate_exactly_kd_times_closing_speed_squared(cube_simulation):
    """With dampers only, the power of the internal forces is -sum kd ((v_a - v_b) . l)^2."""
    simulation = cube_simulation(gravity=NO_GRAVITY, ks=0.0, kd=0.0, particles_per_edge=4,
                                 structural=SpringParameters(0.0, 6.0),
                                 shear=SpringParameters(0.0, 2.5), bend=SpringParameters(0.0, 1.0))
    model = simulation.model
    x, v = random_state(simulation, 11)
    power = float(np.sum(forces(model.arrays, x, v) * v))
    a, b = model.springs[:, 0], model.springs[:, 1]
    d = x[a] - x[b]
    closing = np.einsum("ij,ij->i", v[a] - v[b], d) / np.linalg.norm(d, axis=1)
    kd = model.arrays.group_kd[model.arrays.spring_group]
    dissipated = float(np.sum(kd * closing ** 2))
    assert dissipated > 1.0
    assert power == pytest.approx(-dissipated, rel=1e-12)
