"""Vertex block descent (integrators/vbd.py) against what it approximates and the laws it keeps:
free fall is backward Euler's recursion exactly; a cloth's step converges to a fully converged
backward Euler step as iterations grow (a measured curve); Coulomb friction on slopes slides at
g (sin a - mu cos a) and holds where mu > tan a; a cube falls onto the floor and comes to rest
on it without sinking or jittering; a linear term (the attractor) is backward Euler's
oscillator; threads change no bit; bad settings are one line."""
import numba
import numpy as np
import pytest

from conftest import EARTH_GRAVITY
from springsim import SceneError, Simulation
from springsim.bodies.balls import Ball, Balls
from springsim.clock import CALL_START
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.scene import Scene
from springsim.scenefile import load_scene
from springsim.springs import SpringParameters
from springsim.terms.attractor import Attractor
from springsim.terrains import Plane, tilted_plane
from test_implicit import first_bounce, sliding_cube as implicit_sliding_cube

H = 1.0 / 60.0
SQRT_HALF = np.sqrt(0.5)


def small_cloth(**options):
    cloth = Cloth(particles_per_edge=8, width=1.0, height=1.0, position=(0.0, 1.0, 0.0),
                  pinned="corners", self_collision=False)
    return Scene(name="cloth", bodies=[cloth], terrains=[], gravity=EARTH_GRAVITY, **options)


def test_free_fall_is_backward_eulers_recursion():
    """Springs at rest and every particle falling alike: from the second step on, VBD's
    adaptive first guess (the last acceleration along gravity) is the answer, which one
    iteration keeps: v' = v + h g, x' = x + h v' to round-off."""
    springs = SpringParameters(500.0, 5.0)
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 5.0, 0.0),
                velocity=(1.0, 2.0, 0.0), structural=springs, shear=springs, bend=springs)
    scene = Scene(name="fall", bodies=[cube], terrains=[], gravity=EARTH_GRAVITY)
    sim = Simulation(scene, integrator="vbd", dt=H, iterations=1)
    sim.state.velocities[:] += H * np.asarray(EARTH_GRAVITY)   # as if it had fallen a step
    sim.state.contacts.velocity_change[:] = H * np.asarray(EARTH_GRAVITY)
    x, v = sim.positions.copy(), sim.velocities.copy()
    for _ in range(30):
        v = v + H * np.asarray(EARTH_GRAVITY)
        x = x + H * v
    sim.step(30)
    np.testing.assert_allclose(sim.velocities, v, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.positions, x, rtol=0, atol=1e-12)


def test_a_cloth_step_converges_to_backward_euler_as_iterations_grow():
    """Five steps of an 8 x 8 cloth hanging by its corners, against backward Euler solved to
    convergence (40 Newton iterations, each solve to 1e-13): the largest difference falls with
    the iterations, from 0.7 mm at one iteration to round-off at 256 (measured: 7.0e-4, 1.1e-4,
    3.7e-5, 1.5e-5, 5.7e-6, 1.5e-6, 2.2e-7, 5.8e-9, 4.2e-12 m)."""
    reference = Simulation(small_cloth(), integrator="implicit_euler", dt=H, newton_iterations=40,
                           cg_tolerance=1e-13, cg_max_iterations=5000)
    reference.step(5)
    errors = []
    for iterations in (1, 4, 16, 64, 256):
        sim = Simulation(small_cloth(), integrator="vbd", dt=H, iterations=iterations)
        sim.step(5)
        errors.append(np.abs(sim.positions - reference.positions).max())
    assert all(later < 0.5 * earlier for earlier, later in zip(errors, errors[1:]))
    assert errors[0] > 1e-4 and errors[-1] < 1e-10


def sliding_cube(degrees, friction, iterations):
    """test_implicit.py's cube on a slope, under vbd at 1/60 s; and the slope's normal."""
    sim, downhill = implicit_sliding_cube(degrees, friction, "vbd", H, iterations=iterations)
    angle = np.radians(degrees)
    return sim, downhill, np.array([np.sin(angle), np.cos(angle), 0.0])


def mean_velocity(sim):
    mass = sim.model.mass[:, None]
    return (mass * sim.velocities).sum(axis=0) / mass.sum()


@pytest.mark.parametrize("degrees, friction", [(45, 0.3), (30, 0.3), (30, 0.1)])
def test_a_cube_slides_at_the_coulomb_acceleration(degrees, friction):
    """mu < tan a: the centre of mass accelerates at g (sin a - mu cos a) (converged: 100
    iterations; measured within 0.05%), never below the plane."""
    sim, downhill, normal = sliding_cube(degrees, friction, 100)
    sim.advance(1.0)
    speed = mean_velocity(sim) @ downhill
    sim.advance(1.0)
    angle = np.radians(degrees)
    expected = 9.8 * (np.sin(angle) - friction * np.cos(angle))
    assert mean_velocity(sim) @ downhill - speed == pytest.approx(expected, rel=0.002)
    assert (sim.positions @ normal).min() > 0.0


@pytest.mark.parametrize("iterations", [10, 100])
def test_a_cube_that_friction_holds_on_a_slope_stays_put(iterations):
    """mu = 0.8 > tan 30: after its first step in contact (friction is lagged a step:
    vbd/contact.py) the face on the slope creeps slower than friction_velocity (1 mm/s; measured
    0.55-0.61 mm in the second second), and no particle moves faster."""
    sim, _, normal = sliding_cube(30, 0.8, iterations)
    sim.advance(0.5)
    start = sim.positions.copy()
    on_slope = start @ normal < 0.01
    sim.advance(1.0)
    assert np.abs(sim.velocities).max() < 1e-3
    assert np.abs(sim.positions - start)[on_slope].max() < 1e-3 * 1.0


@pytest.mark.parametrize("friction", [0.3, 1.2])
def test_a_ball_on_a_slope_slides_or_holds(friction):
    """A lone particle (no springs: every block step is the whole problem) at 10 iterations:
    g sin 45 (1 - mu) to its drag's share where mu < 1, at rest where mu > 1."""
    plane, radius = tilted_plane(friction=friction), 0.1
    offset = radius * SQRT_HALF + 1e-4
    ball = Ball(position=(offset, offset, 0.0), radius=radius, mass=1.0)
    scene = Scene(name="ball", bodies=[Balls(balls=[ball])], terrains=[plane],
                  gravity=EARTH_GRAVITY)
    sim = Simulation(scene, integrator="vbd", dt=H)
    downhill = np.array([1.0, -1.0, 0.0]) * SQRT_HALF
    sim.step(30)
    speed = sim.velocities[0] @ downhill
    sim.step(60)
    expected = max(0.0, 9.8 * SQRT_HALF * (1.0 - friction))
    assert sim.velocities[0] @ downhill - speed == pytest.approx(expected, rel=1e-3, abs=1e-9)
    assert plane.signed_distance(sim.positions, radius).min() > 0.0


@pytest.mark.parametrize("dt", [1 / 60, 1 / 30])
def test_a_cube_falls_onto_the_floor_and_rests_there(dt):
    """The course's cube (10 per edge) dropped on the floor: no particle ever below it, and it
    comes to rest where it landed, without jitter: from 5 s on, no particle faster than 5 mm/s
    nor moving 5 mm in a second (measured: 1-3 mm/s, the creep the smoothed static friction
    allows)."""
    scene = load_scene("jelly-plane")
    sim = Simulation(scene, integrator="vbd", dt=dt)
    floor = scene.terrains[0]
    lowest = np.inf
    while sim.time < 5.0 - 1e-9:
        sim.step(1)
        lowest = min(lowest, floor.signed_distance(sim.positions).min())
    rested = sim.positions.copy()
    sim.advance(1.0)
    assert lowest >= 0.0
    assert np.abs(sim.velocities).max() < 0.005
    assert np.abs(sim.positions - rested).max() < 0.005


def test_a_linear_term_is_backward_eulers_oscillator():
    """The attractor (terms/attractor.py) is linearized once an iteration: for one particle that
    is exact, so each step follows backward Euler's linear recursion to round-off."""
    point, k, d, mass = np.array([0.5, 1.0, -0.25]), 8.0, 0.2, 0.5
    ball = Ball(position=tuple(point + (0.3, 0.0, 0.0)), radius=0.05, mass=mass)
    scene = Scene(bodies=[Balls(balls=[ball], drag=0.0)], terrains=[], gravity=(0.0, 0.0, 0.0),
                  forces=[Attractor(point=tuple(point), stiffness=k, damping=d)])
    sim = Simulation(scene, integrator="vbd", dt=H, iterations=1)
    sim.step(30)
    x, v = point + (0.3, 0.0, 0.0), np.zeros(3)
    for _ in range(30):
        v = (mass * v + H * k * (point - x)) / (mass + H * d + H * H * k)
        x = x + H * v
    np.testing.assert_allclose(sim.positions[0], x, rtol=0, atol=1e-12)


def test_threads_change_no_bit():
    """The threaded kernel with one thread and with two, and the serial one: a colour's
    particles share nothing they write, so the results are the same bits."""
    runs = []
    for threaded, threads in ((False, 1), (True, 1), (True, 2)):
        sim = Simulation(load_scene("cloth-drape"), integrator="vbd", dt=H)
        integrator, model = sim.integrator, sim.model
        call = integrator.kernel_call(model, sim.state, H, 20, threaded=threaded)
        numba.set_num_threads(threads)
        model.arrays.clock[CALL_START] = 0.0
        call.kernel(*call.arguments)
        runs.append(sim.state.positions.copy())
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[1], runs[2])


def test_the_graph_lists_each_particles_springs_in_sweep_order():
    """vbd/graph.py: the free particles by colour, no spring within a colour, and the n-th one's
    entries (start[n]:start[n + 1]) its springs, each with its other end, rest length, ks and
    kd; pinned particles have none."""
    from springsim.vbd.graph import vertex_graph

    sim = Simulation(load_scene("cloth-hang"), integrator="vbd", dt=H)
    arrays = sim.model.arrays
    graph = vertex_graph(arrays)
    springs = arrays.springs.astype(np.int64)
    colour = np.full(len(arrays.inv_mass), -1)
    for c in range(len(graph.colour_start) - 1):
        colour[graph.particles[graph.colour_start[c]:graph.colour_start[c + 1]]] = c
    assert np.array_equal(np.sort(graph.particles), np.flatnonzero(arrays.inv_mass > 0.0))
    both_free = (colour[springs[:, 0]] >= 0) & (colour[springs[:, 1]] >= 0)
    assert not (colour[springs[:, 0]] == colour[springs[:, 1]])[both_free].any()
    assert graph.start[0] == 0 and graph.start[-1] == len(graph.other)
    for n, i in enumerate(graph.particles):
        entries = slice(graph.start[n], graph.start[n + 1])
        mine = np.flatnonzero((springs == i).any(axis=1))
        others = springs[mine].sum(axis=1) - i
        expected = sorted(zip(others, arrays.rest_length[mine],
                              arrays.group_ks[arrays.spring_group[mine]],
                              arrays.group_kd[arrays.spring_group[mine]]))
        listed = sorted(zip(graph.other[entries], graph.rest_length[entries],
                            graph.ks[entries], graph.kd[entries]))
        assert listed == expected


@pytest.mark.parametrize("key, value, allowed", [
    ("iterations", 0, "whole number from 1 to 10000"),
    ("contact_stiffness_ratio", -1.0, "number > 0"),
    ("friction_velocity", float("nan"), "speed > 0 m/s"),
])
def test_bad_settings_are_one_line(key, value, allowed):
    with pytest.raises(SceneError, match=rf"vbd\.{key}.*{allowed}"):
        Simulation(small_cloth(), integrator="vbd", dt=H, **{key: value})
    scene = small_cloth()
    setattr(scene.vbd, key, value)
    with pytest.raises(SceneError, match=rf"vbd\.{key}"):
        scene.validate()


def test_a_scene_file_sets_the_iterations(tmp_path):
    path = tmp_path / "cloth.toml"
    path.write_text('integrator = "vbd"\ndt = 0.016667\n[vbd]\niterations = 3\n'
                    '[[bodies]]\ntype = "cloth"\nparticles_per_edge = 5\n')
    sim = Simulation(load_scene(path))
    assert sim.integrator.name == "vbd" and sim.integrator.settings.iterations == 3


def test_gradients_refuse_it_in_one_line():
    """No adjoint yet (issue 57, part 4): springsim.gradient says so before any work."""
    import springsim

    with pytest.raises(SceneError, match="integrator = 'vbd': has no adjoint yet"):
        springsim.gradient(small_cloth(), loss=lambda take: 0.0,
                           wrt=["bodies.0.structural.ks"], integrator="vbd", dt=H, duration=H)


@pytest.mark.parametrize("dt", [1 / 60, 1 / 240])
def test_a_ball_bounces_off_the_floor_with_its_restitution(dt):
    """The minimization stops an approach dead; the approach speed is restored for the impact
    pass, which reflects it: the first bounce leaves at e times the speed it arrived with."""
    ball = Ball(position=(0.0, 1.0, 0.0), radius=0.1, mass=1.0)
    scene = Scene(bodies=[Balls(balls=[ball], drag=0.0)],
                  terrains=[Plane(restitution=0.5, friction=0.0)], gravity=EARTH_GRAVITY)
    sim = Simulation(scene, integrator="vbd", dt=dt)
    arriving = first_bounce(sim)
    assert arriving < -5.0
    assert sim.velocities[0, 1] == pytest.approx(-0.5 * arriving, rel=1e-12)
    assert Plane().signed_distance(sim.positions, 0.1).min() >= 0.0
