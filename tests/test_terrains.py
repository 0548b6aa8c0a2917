"""Terrain contact: exact contact accelerations for a particle at rest, restitution, Coulomb
friction on the 45-degree plane, and the default cube dropped on every built-in terrain with every
integrator (no NaN, no penetration, at rest or sliding as the physics says)."""
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import springsim
from springsim.terrains import pack_terrains, terrain_distance
from springsim.forces import accelerations, force_columns
from springsim.terrains import Bowl, Plane, Sphere, tilted_plane

INTEGRATORS = ["explicit_euler", "symplectic_euler", "midpoint", "rk4"]
G = 9.8
EARTH_GRAVITY = (0.0, -G, 0.0)
SLOPE_NORMAL = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)   # the tilted plane's, normalized
DOWN_SLOPE = np.array([1.0, -1.0, 0.0]) / math.sqrt(2.0)
SLOPE = math.radians(45.0)
# The bar is "at most epsilon"; the impact pass promises more: no penetration at all after a step.
NO_PENETRATION = -1e-9  # m, round-off


def centre_of_mass(simulation):
    return simulation.model.mass @ simulation.positions / simulation.model.mass.sum()


def centre_of_mass_velocity(simulation):
    return simulation.model.mass @ simulation.velocities / simulation.model.mass.sum()


def step_checking_contact(simulation, seconds, every=None):
    """Advance ``seconds`` one step at a time; return the smallest signed distance to any terrain
    seen after any step (negative = penetration), and the centre of mass every ``every`` steps."""
    model = simulation.model
    closest, history = np.inf, []
    for step in range(int(round(seconds / simulation.dt))):
        simulation.step(1)
        for terrain in model.terrains:
            closest = min(closest, float(terrain.signed_distance(simulation.positions,
                                                                 model.arrays.radius).min()))
        if every and (step + 1) % every == 0:
            history.append((simulation.time, centre_of_mass(simulation)))
    assert np.all(np.isfinite(simulation.positions)) and np.all(np.isfinite(simulation.velocities))
    return closest, history


# --- the contact kernels on single particles --------------------------------------------------

def free_particles(cube_simulation, terrain, **options):
    """Eight unconnected 1 kg particles (a 2 x 2 x 2 cube with no springs) under gravity."""
    return cube_simulation("rk4", 1e-3, gravity=EARTH_GRAVITY, terrains=[terrain], ks=0.0, kd=0.0,
                           particles_per_edge=2, position=(0.0, 5.0, 0.0), **options)


def contact_acceleration(simulation, x, v, h=1e-3):
    a = np.full_like(x, np.nan)
    accelerations(simulation.model.arrays, x, v, h, a, force_columns(a))
    return a


def points_on_plane(normal, count=8, spread=3.0, seed=0):
    """Points exactly on the plane through the origin with this normal."""
    rng = np.random.default_rng(seed)
    p = spread * rng.standard_normal((count, 3))
    return p - np.outer(p @ normal, normal)


def test_a_particle_at_rest_on_the_plane_feels_no_net_force(cube_simulation):
    simulation = free_particles(cube_simulation, Plane(point=(0.0, 0.0, 0.0), friction=0.0))
    x = points_on_plane(np.array([0.0, 1.0, 0.0]))
    a = contact_acceleration(simulation, x, np.zeros_like(x))
    assert np.all(a == 0.0)  # no NaN from a zero sliding speed, and the weight fully supported


@pytest.mark.parametrize("friction", [1.2, 1.0001, 5.0])
def test_static_friction_holds_a_particle_on_the_45_degree_plane(cube_simulation, friction):
    simulation = free_particles(cube_simulation, tilted_plane(friction=friction))
    x = points_on_plane(SLOPE_NORMAL)
    a = contact_acceleration(simulation, x, np.zeros_like(x))
    np.testing.assert_allclose(a, 0.0, atol=1e-14)


@pytest.mark.parametrize("friction", [0.0, 0.3, 0.9])
def test_kinetic_friction_on_the_45_degree_plane(cube_simulation, friction):
    """From rest and when sliding down, the acceleration is g (sin 45 - mu cos 45) down the slope
    (at rest the impending motion is down the slope; a slide down makes friction point up)."""
    simulation = free_particles(cube_simulation, tilted_plane(friction=friction))
    expected = G * (math.sin(SLOPE) - friction * math.cos(SLOPE)) * DOWN_SLOPE
    x = points_on_plane(SLOPE_NORMAL)
    for speed in (0.0, 0.7, 30.0):
        v = np.tile(speed * DOWN_SLOPE, (len(x), 1))
        a = contact_acceleration(simulation, x, v)
        np.testing.assert_allclose(a, np.broadcast_to(expected, a.shape), atol=1e-12)


@pytest.mark.parametrize("speed", [0.005, 0.05, 50.0])
def test_kinetic_friction_opposes_a_sideways_slide(cube_simulation, speed):
    """Sliding across the slope, friction mu g cos 45 points exactly against the velocity, slow
    or fast (any speed that friction cannot stop within the step, here above 2.1 mm/s)."""
    friction = 0.3
    simulation = free_particles(cube_simulation, tilted_plane(friction=friction))
    across = np.array([0.0, 0.0, 1.0])
    x = points_on_plane(SLOPE_NORMAL)
    a = contact_acceleration(simulation, x, np.tile(speed * across, (len(x), 1)))
    np.testing.assert_allclose(a @ SLOPE_NORMAL, 0.0, atol=1e-12)
    np.testing.assert_allclose(a @ DOWN_SLOPE, G * math.sin(SLOPE), rtol=1e-12)
    np.testing.assert_allclose(a @ across, -friction * G * math.cos(SLOPE), rtol=1e-12)


def test_friction_at_the_end_of_a_slide_is_still_bounded_by_the_cone(cube_simulation):
    """Slower than friction could stop within the step, but pulled harder than the cone holds:
    the friction has exactly the Coulomb size mu g cos 45 (and no division by |v_T| happens)."""
    friction, h = 0.3, 1e-3
    simulation = free_particles(cube_simulation, tilted_plane(friction=friction))
    x = points_on_plane(SLOPE_NORMAL)
    for speed in (0.0, 1e-4, 1e-3):
        v = np.tile(speed * np.array([0.0, 0.0, 1.0]), (len(x), 1))
        a = contact_acceleration(simulation, x, v, h)
        friction_part = a - G * math.sin(SLOPE) * DOWN_SLOPE
        np.testing.assert_allclose(np.linalg.norm(friction_part, axis=1),
                                   friction * G * math.cos(SLOPE), rtol=1e-12)


@pytest.mark.parametrize("terrain", [Plane(point=(0.3, -1.0, 2.0), normal=(0.2, 1.0, -0.4)),
                                     Sphere(), Bowl()], ids=["plane", "sphere", "bowl"])
def test_kernel_and_terrain_agree_on_the_signed_distance(terrain):
    rng = np.random.default_rng(5)
    x = rng.uniform(-8.0, 12.0, (200, 3))
    radius = rng.uniform(0.0, 0.3, 200)
    expected = terrain.signed_distance(x, radius)
    packed = pack_terrains([terrain])
    for i in range(len(x)):
        phi, nx, ny, nz = terrain_distance(packed["terrain_kind"][0],
                                           packed["terrain_parameters"][0],
                                           packed["terrain_data"], x[i, 0], x[i, 1], x[i, 2],
                                           radius[i])
        assert phi == pytest.approx(expected[i], abs=1e-12)
        assert math.hypot(nx, ny, nz) == pytest.approx(1.0, abs=1e-14)


# --- restitution ------------------------------------------------------------------------------

@pytest.mark.parametrize("restitution", [0.8, 0.5, 1.0])
def test_a_particle_rebounds_with_the_terrain_restitution(cube_simulation, restitution):
    """Eight free particles dropped from 2 m (the lowest four are the ones at the plane first):
    the normal speed just after the bounce over the speed of the fall, sqrt(2 g H), is the
    restitution, within what the contact band and one step leave open: the bounce happens
    somewhere in the band (up to epsilon short of the plane: g epsilon / v) and one step of
    gravity may be cancelled or not (g h)."""
    height, epsilon, dt = 2.0, 0.01, 1e-3
    plane = Plane(point=(0.0, 0.0, 0.0), restitution=restitution, epsilon=epsilon)
    simulation = free_particles(cube_simulation, plane)
    lowest = simulation.positions[:, 1] == simulation.positions[:, 1].min()
    simulation.state.positions[:, 1] += height - simulation.positions[lowest, 1][0]
    fall_speed = math.sqrt(2 * G * height)
    simulation.step(1)
    while np.all(simulation.velocities[lowest, 1] < 0.0):  # falling until the bounce
        simulation.step(1)
    rebound = simulation.velocities[lowest, 1]
    tolerance = (G * epsilon / fall_speed + 2 * G * dt) / fall_speed
    np.testing.assert_allclose(rebound / fall_speed, restitution, atol=tolerance)
    # and the rebound carries them up to e^2 H, within the band
    apex = simulation.positions[lowest, 1].copy()
    while np.all(simulation.velocities[lowest, 1] > 0.0):
        simulation.step(1)
        apex = np.maximum(apex, simulation.positions[lowest, 1])
    np.testing.assert_allclose(apex, restitution ** 2 * height, atol=2 * epsilon)


@pytest.mark.parametrize("height, bounces", [(0.015, False), (0.05, True)])
def test_an_approach_too_slow_to_rebound_out_of_the_band_is_resting_contact(cube_simulation,
                                                                            height, bounces):
    """Landing slower than sqrt(2 g epsilon) = 0.44 m/s, a rebound would stay inside the 1 cm
    band: the particle stops instead (collision/response/terrain.py). From 5 cm it lands at 0.9 m/s
    and bounces."""
    plane = Plane(point=(0.0, 0.0, 0.0), restitution=0.8)
    simulation = free_particles(cube_simulation, plane)
    lowest = simulation.positions[:, 1] == simulation.positions[:, 1].min()
    simulation.state.positions[:, 1] += height - simulation.positions[lowest, 1][0]
    fastest_up = 0.0
    for _ in range(100):  # 0.1 s: enough to land from either height
        simulation.step(1)
        fastest_up = max(fastest_up, simulation.velocities[lowest, 1].min())
    if bounces:
        assert fastest_up > 0.5
    else:
        assert fastest_up == 0.0
        assert np.all(simulation.velocities[lowest] == 0.0)
        assert np.all(plane.signed_distance(simulation.positions[lowest]) < plane.epsilon)


def test_an_inelastic_plane_stops_the_particle(cube_simulation):
    simulation = free_particles(cube_simulation, Plane(point=(0.0, 3.0, 0.0), restitution=0.0))
    closest, _ = step_checking_contact(simulation, 1.5)
    assert closest >= NO_PENETRATION
    assert np.all(simulation.velocities == 0.0)


# --- friction on the 45-degree plane ------------------------------------------------------------

def cube_on_the_slope(cube_simulation, integrator, friction):
    """A 5 x 5 x 5 cube (2 m, 125 kg) set on the 45-degree plane, 1 mm above it, at rest, with a
    corner pointing down the slope.

    Why this cube: on a 45-degree slope the friction force at the base tilts the cube forward,
    and the normal forces must push their centre tan(45) h = 1 m down-slope of the centre of the
    base. With a face down-slope the base ends there (the cube is exactly at its tipping angle);
    with a corner down-slope it reaches 1.41 m, so a stiff enough cube stands. The default springs
    (2000 N/m) squash under that load and the cube topples and rolls, which is physics too; the
    stiffer springs here (20000 N/m, damping 120 N s/m) keep it standing.
    """
    face_down = Rotation.from_rotvec(np.radians(-45.0) * np.array([0.0, 0.0, 1.0]))
    corner_down = Rotation.from_rotvec(np.radians(45.0) * SLOPE_NORMAL) * face_down
    rotation = corner_down.as_rotvec()
    edge = 2.0
    return cube_simulation(
        integrator, 1e-3, gravity=EARTH_GRAVITY, terrains=[tilted_plane(friction=friction)],
        ks=20000.0, kd=120.0, particles_per_edge=5, edge_length=edge,
        position=tuple((edge / 2 + 1e-3) * SLOPE_NORMAL),
        rotation_degrees=float(np.degrees(np.linalg.norm(rotation))),
        rotation_axis=tuple(rotation))


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_friction_above_tan_45_holds_the_cube_without_creep_or_jitter(cube_simulation,
                                                                     integrator):
    simulation = cube_on_the_slope(cube_simulation, integrator, friction=1.2)
    closest, history = step_checking_contact(simulation, 3.0, every=500)
    assert closest >= NO_PENETRATION
    down_slope = [com @ DOWN_SLOPE for _, com in history]
    assert abs(down_slope[-1] - down_slope[-3]) < 1e-3  # no creep over the last second
    assert abs(down_slope[-1] - down_slope[0]) < 0.05   # it settled where it was put
    assert simulation.energy()["kinetic"] < 1e-6         # no jitter


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_friction_below_tan_45_lets_the_cube_slide_at_g_sin_minus_mu_cos(cube_simulation,
                                                                       integrator):
    friction = 0.3
    simulation = cube_on_the_slope(cube_simulation, integrator, friction)
    simulation.advance(0.5)  # the springs settle under the sudden load
    closest, history = step_checking_contact(simulation, 1.5, every=50)
    assert closest >= NO_PENETRATION
    t = np.array([time for time, _ in history])
    s = np.array([com @ DOWN_SLOPE for _, com in history])
    measured = 2 * np.polyfit(t, s, 2)[0]
    expected = G * (math.sin(SLOPE) - friction * math.cos(SLOPE))
    assert measured == pytest.approx(expected, rel=1e-3)


# --- the default cube on the four built-in terrains ---------------------------------------------

def preset_simulation(name, integrator):
    return springsim.Simulation(springsim.load_scene(name), integrator=integrator, dt=1e-3)


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_cube_comes_to_rest_on_the_plane(integrator):
    """Dropped 5.8 m, it lands at 10.6 m/s (48 kJ), bounces, and rests within 4.5 s."""
    simulation = preset_simulation("jelly-plane", integrator)
    closest, history = step_checking_contact(simulation, 4.5, every=250)
    assert closest >= NO_PENETRATION
    assert np.linalg.norm(history[-1][1] - history[-3][1]) < 1e-3  # still over the last 0.5 s
    assert np.linalg.norm(centre_of_mass_velocity(simulation)) < 1e-3
    assert simulation.energy()["kinetic"] < 1e-3
    lowest = simulation.model.terrains[0].signed_distance(simulation.positions).min()
    assert NO_PENETRATION <= lowest < simulation.model.terrains[0].epsilon  # on it, not above


@pytest.mark.parametrize("integrator", ["predict_reevaluate", "rk4"])
def test_a_cube_at_rest_on_the_plane_has_no_phantom_sliding_velocity(integrator):
    """At rest on the plane, the particles touching it have no tangential velocity, and the
    velocities are those the positions show: x(t + T) - x(t) = integral of v over T. (The
    predict_reevaluate step once kept up to 28 mm/s of sliding on particles that did not move.)"""
    simulation = preset_simulation("jelly-plane", integrator)
    simulation.advance(4.5)
    plane = simulation.model.terrains[0]
    touching = plane.signed_distance(simulation.positions) < plane.epsilon
    assert touching.sum() == 100    # the bottom face
    start, travelled = simulation.positions.copy(), np.zeros_like(simulation.positions)
    for _ in range(100):
        velocity_before = simulation.velocities.copy()
        simulation.step(1)
        travelled += simulation.dt * (velocity_before + simulation.velocities) / 2
    normal = plane.unit_normal()
    v = simulation.velocities[touching]
    moved = (simulation.positions - start)[touching]
    assert np.abs(v - np.outer(v @ normal, normal)).max() < 1e-9             # m/s, sliding
    assert np.abs(moved - travelled[touching]).max() < 1e-9                  # m, over 0.1 s
    assert np.abs(simulation.velocities).max() < 1e-4                       # m/s, settled


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_cube_goes_down_the_tilted_plane(integrator):
    """Friction 0.3 < tan 45: the cube cannot stick. It lands on an edge (the slope is 45 degrees
    to its faces), tumbles, bounces (restitution 0.8) and slides down the slope, gaining speed,
    but never faster than g sin 45, the rate with no friction at all (in flight it is exactly
    that). Tumbling loses energy at every face impact, so the sliding law g (sin - mu cos) is no
    bound here; the cube set down flat on the slope checks it above."""
    simulation = preset_simulation("jelly-tilted", integrator)
    closest, _ = step_checking_contact(simulation, 1.0)
    speed_after_landing = centre_of_mass_velocity(simulation) @ DOWN_SLOPE
    start = centre_of_mass(simulation) @ DOWN_SLOPE
    closest_later, _ = step_checking_contact(simulation, 2.0)
    assert min(closest, closest_later) >= NO_PENETRATION
    gained = centre_of_mass_velocity(simulation) @ DOWN_SLOPE - speed_after_landing
    assert 3.0 < gained <= 2.0 * G * math.sin(SLOPE) * (1 + 1e-9)
    assert centre_of_mass(simulation) @ DOWN_SLOPE - start > 10.0


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_cube_slides_off_the_sphere(integrator):
    """The cube cannot balance on the sphere, and the physics says why. Its centre of mass starts
    d = 0.31 m off the sphere's axis (the framework's off-centre lattice). A rigid block of half
    height b = 2 m on a sphere of radius R = 3 m balances only once it has rolled until its centre
    is above the contact: (R - b) theta = d, theta = 0.31 rad = 18 degrees, where the contact
    normal is steeper than the friction angle atan(0.3) = 16.7 degrees, so the contact slips; the
    landing at 10 m/s only adds to it. It slides off along the diagonal x = z of its offset (the
    scene is symmetric under swapping x and z) and falls past the sphere."""
    simulation = preset_simulation("jelly-sphere", integrator)
    sphere = simulation.model.terrains[0]
    closest, history = step_checking_contact(simulation, 3.0, every=100)
    assert closest >= NO_PENETRATION
    com = centre_of_mass(simulation)
    assert com[0] == pytest.approx(com[2], abs=1e-9) and com[0] < 0
    assert math.hypot(com[0] - sphere.center[0], com[2] - sphere.center[2]) > sphere.radius
    assert sphere.signed_distance(simulation.positions).min() > sphere.epsilon  # it left
    landed = min(sphere.signed_distance(com[None, :])[0] for _, com in history)
    assert landed < 2.5  # the centre came within half an edge of the surface: it did land


# Explicit Euler leaves a few loaded corner particles chattering (about 5 J in all, 1e-4 of the
# landing energy, while the body stands still): a particle pressed on the bowl with acceleration a
# and bouncing (restitution 0.8) gains m a^2 h / 2 per second of flight from explicit Euler's
# lagging positions, which balances the (1 - e^2) m v^2 / 2 lost per bounce near v ~ a h/(1 - e^2).
# The other methods do not gain energy in flight, and their chatter dies out.
RESTING_KINETIC_ENERGY = {"explicit_euler": 50.0, "symplectic_euler": 1.0, "midpoint": 1.0,
                          "rk4": 1.0}  # J, against 46 kJ at landing


@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_cube_comes_to_rest_in_the_bowl(integrator):
    """Dropped on the bowl's side, it slides and rocks across it; friction and the springs'
    damping stop it near the bottom within 20 s."""
    simulation = preset_simulation("jelly-bowl", integrator)
    closest, history = step_checking_contact(simulation, 20.0, every=500)
    assert closest >= NO_PENETRATION
    assert np.linalg.norm(history[-1][1] - history[-3][1]) < 5e-3  # still over the last second
    assert np.linalg.norm(centre_of_mass_velocity(simulation)) < 1e-2
    assert simulation.energy()["kinetic"] < RESTING_KINETIC_ENERGY[integrator]
