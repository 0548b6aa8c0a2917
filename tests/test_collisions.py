"""Ball-ball and ball-particle collisions: impulse laws, conservation, and the cloth-balls scene.

Oracles: velocity swap of equal balls (e = 1); the measured restitution and the kinetic energy
lost equal their analytic values; Coulomb friction removes min(|v_T|, mu (1 + e) |v_N|) of the
sliding speed; momentum and the uniform motion of the centre of mass survive many collisions;
a pinned particle is an immovable wall; balls on the reference cloth stay on it.
"""
import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.scene import Scene
from springsim.springs import SpringParameters

NO_SPRINGS = SpringParameters(0.0, 0.0)
ZERO_G = (0.0, 0.0, 0.0)


def points_at(positions, mass=1.0, pinned="none"):
    """Free point particles (a spring-less 2 x 2 cloth): particle 0 at positions[0], the other
    three 1 km away unless given."""
    cloth = Cloth(particles_per_edge=2, width=1000.0, height=1000.0, particle_mass=mass,
                  position=tuple(np.add(positions, (500.0, 0.0, 500.0))), structural=NO_SPRINGS,
                  shear=NO_SPRINGS, bend=NO_SPRINGS, pinned=pinned, drag=0.0)
    return cloth


def simulation(*bodies, integrator="rk4", dt=1e-4, gravity=ZERO_G):
    return springsim.Simulation(Scene(bodies=list(bodies), gravity=gravity, dt=dt),
                                integrator=integrator)


def step_until_impulse(sim, particle, limit=20000):
    """Step until ``particle``'s velocity changes; return the velocities before that step."""
    for _ in range(limit):
        before = sim.velocities.copy()
        sim.step(1)
        if not np.array_equal(sim.velocities[particle], before[particle]):
            return before
    raise AssertionError("no collision happened")


def test_equal_balls_colliding_head_on_with_restitution_one_swap_velocities():
    balls = Balls(balls=[Ball(position=(-1.0, 0.0, 0.0), velocity=(3.0, 0.0, 0.0)),
                         Ball(position=(1.0, 0.0, 0.0), velocity=(-1.0, 0.0, 0.0))],
                  ball_restitution=1.0, drag=0.0)
    sim = simulation(balls)
    sim.advance(1.0)
    np.testing.assert_allclose(sim.velocities, [[-1.0, 0.0, 0.0], [3.0, 0.0, 0.0]], atol=1e-12)


@pytest.mark.parametrize("restitution", [0.0, 0.3, 0.8, 1.0])
def test_measured_ball_ball_restitution_equals_the_setting(restitution):
    masses = np.array([2.0, 5.0])
    balls = Balls(balls=[Ball(position=(0.0, 0.0, 0.0), velocity=(4.0, 0.5, 0.0), radius=0.3,
                              mass=2.0),
                         Ball(position=(2.0, 0.4, 0.1), velocity=(-1.0, 0.0, 0.2), radius=0.6,
                              mass=5.0)],
                  ball_restitution=restitution, drag=0.0)
    sim = simulation(balls)
    v0 = step_until_impulse(sim, 0)
    v1 = sim.velocities
    normal = sim.positions[0] - sim.positions[1]   # corrections move along it: still the normal
    normal /= np.linalg.norm(normal)
    approach, separation = (v0[0] - v0[1]) @ normal, (v1[0] - v1[1]) @ normal
    assert approach < -1.0
    assert separation == pytest.approx(-restitution * approach, abs=1e-12)
    tangential = lambda v: (v[0] - v[1]) - ((v[0] - v[1]) @ normal) * normal  # noqa: E731
    np.testing.assert_allclose(tangential(v1), tangential(v0), atol=1e-12)  # no friction
    np.testing.assert_allclose(masses @ v1, masses @ v0, rtol=0, atol=1e-12)
    reduced = masses.prod() / masses.sum()
    kinetic = lambda v: 0.5 * masses @ np.sum(v * v, axis=1)  # noqa: E731
    lost = 0.5 * reduced * (1 - restitution ** 2) * approach ** 2
    assert kinetic(v0) - kinetic(v1) == pytest.approx(lost, abs=1e-11)


def test_ball_hitting_a_free_particle_with_restitution_zero_moves_on_with_it():
    ball = Balls(balls=[Ball(position=(0.0, 1.0, 0.0), velocity=(0.0, -3.0, 0.0))], drag=0.0)
    sim = simulation(points_at((0.0, 0.0, 0.0)), ball)   # particles 0-3 points, 4 the ball
    sim.advance(0.5)
    common = -3.0 * 125.0 / 126.0   # perfectly inelastic: momentum shared by both masses
    np.testing.assert_allclose(sim.velocities[[0, 4]], [[0.0, common, 0.0]] * 2, atol=1e-12)


@pytest.mark.parametrize("friction", [0.0, 0.03, 0.2, 10.0])
def test_ball_particle_friction_removes_the_coulomb_share_of_the_sliding_speed(friction):
    ball = Balls(balls=[Ball(position=(-0.2, 0.6, 0.0), velocity=(2.0, -3.0, 0.0), mass=10.0)],
                 particle_restitution=0.5, particle_friction=friction, drag=0.0)
    sim = simulation(points_at((0.0, 0.0, 0.0), mass=2.0), ball)
    v0 = step_until_impulse(sim, 4)
    v1 = sim.velocities
    normal = sim.positions[4] - sim.positions[0]
    normal /= np.linalg.norm(normal)
    relative0, relative1 = v0[4] - v0[0], v1[4] - v1[0]
    approach = relative0 @ normal
    assert relative1 @ normal == pytest.approx(-0.5 * approach, abs=1e-12)
    sliding0 = relative0 - approach * normal
    sliding1 = relative1 - (relative1 @ normal) * normal
    removed = min(np.linalg.norm(sliding0), friction * 1.5 * abs(approach))
    np.testing.assert_allclose(sliding1, sliding0 * (1 - removed / np.linalg.norm(sliding0)),
                               atol=1e-12)
    np.testing.assert_allclose(10.0 * v1[4] + 2.0 * v1[0], 10.0 * v0[4] + 2.0 * v0[0],
                               atol=1e-12)


def test_position_correction_removes_15_percent_of_the_overlap_per_step_about_the_centre():
    ball = Balls(balls=[Ball(position=(0.0, 0.4, 0.0))], drag=0.0)  # 0.1 m into the point
    sim = simulation(points_at((0.0, 0.0, 0.0)), ball)
    mass = sim.model.mass[[0, 4]]
    centre = mass @ sim.positions[[0, 4]] / mass.sum()
    for steps in (1, 9):
        sim.step(steps)
    overlap = 0.5 - np.linalg.norm(sim.positions[4] - sim.positions[0])
    assert overlap == pytest.approx(0.1 * 0.85 ** 10, rel=1e-9)
    np.testing.assert_allclose(mass @ sim.positions[[0, 4]] / mass.sum(), centre, atol=1e-14)
    assert not sim.velocities.any()   # corrections move particles, they add no velocity


def test_a_pinned_particle_is_an_immovable_wall():
    ball = Balls(balls=[Ball(position=(0.0, 1.0, 0.0), velocity=(0.0, -2.0, 0.0))],
                 particle_restitution=0.5, drag=0.0)
    sim = simulation(points_at((0.0, 0.0, 0.0), pinned=[0]), ball)
    sim.advance(0.5)
    np.testing.assert_allclose(sim.velocities[4], (0.0, 1.0, 0.0), atol=1e-12)
    np.testing.assert_array_equal(sim.positions[0], (0.0, 0.0, 0.0))


@pytest.mark.parametrize("integrator", ["explicit_euler", "rk4"])
def test_momentum_and_centre_of_mass_survive_many_collisions(integrator):
    rng = np.random.default_rng(4)
    centres = rng.uniform(-1.5, 1.5, (24, 3))
    balls = Balls(balls=[Ball(position=tuple(c), velocity=tuple(-2.0 * c + rng.normal(0, 1, 3)),
                              radius=0.25, mass=float(rng.uniform(1.0, 20.0)))
                         for c in centres], drag=0.0)
    cloth = Cloth(particles_per_edge=12, width=3.0, height=3.0, pinned="none", drag=0.0,
                  velocity=(0.0, 1.0, 0.0))
    sim = simulation(cloth, balls, integrator=integrator)
    mass = sim.model.mass
    total = mass.sum()
    momentum0 = mass @ sim.velocities
    centre0 = mass @ sim.positions / total
    scale = mass @ np.linalg.norm(sim.velocities, axis=1)
    ball_velocities0 = sim.velocities[sim.model.arrays.balls].copy()
    for _ in range(5):
        sim.advance(0.1)
        np.testing.assert_allclose(mass @ sim.velocities, momentum0, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(mass @ sim.positions / total,
                                   centre0 + momentum0 / total * sim.time, rtol=0, atol=1e-10)
    changed = np.linalg.norm(sim.velocities[sim.model.arrays.balls] - ball_velocities0, axis=1)
    assert np.count_nonzero(changed > 0.1) >= 20   # nearly every ball hit something


def cloth_check(sim):
    """Penetration (share of the radius) of the deepest cloth particle in a ball, and the height of
    each ball's centre above the highest cloth particle beneath it (within half a radius)."""
    arrays = sim.model.arrays
    balls, cloth = arrays.balls, np.flatnonzero(arrays.radius == 0)
    x = sim.positions
    radius = arrays.radius[balls]
    distance = np.linalg.norm(x[balls][:, None] - x[cloth][None], axis=2)
    depth = np.max((radius[:, None] - distance) / radius[:, None])
    horizontal = np.linalg.norm((x[balls][:, None] - x[cloth][None])[:, :, [0, 2]], axis=2)
    heights = [x[ball, 1] - x[cloth[horizontal[k] < radius[k] / 2], 1].max(initial=-np.inf)
               for k, ball in enumerate(balls)]
    return depth, min(heights)


@pytest.mark.parametrize("integrator", ["rk4", "explicit_euler"])
def test_the_four_balls_land_on_the_cloth_and_stay_on_it_for_3_s(integrator):
    sim = springsim.Simulation(springsim.load_scene("cloth-balls"), integrator=integrator)
    assert sim.dt == 1e-4
    balls = sim.model.arrays.balls
    landed = False
    for _ in range(150):
        sim.advance(0.02)
        depth, height = cloth_check(sim)
        assert depth < 0.05 and height > 0.3   # the cloth lies under every ball, not inside it
        assert np.all(np.abs(sim.positions[balls][:, [0, 2]]) < 2.0)
        landed |= bool(np.all(sim.positions[balls, 1] < 0.0))
    assert landed and sim.time == pytest.approx(3.0)
    assert np.all(sim.positions[balls, 1] < 0.0) and np.all(sim.positions[balls, 1] > -1.0)


# The largest stable time steps of the reference's table for cloth and balls.
STABLE_DT = {"explicit_euler": 2e-4, "symplectic_euler": 2e-4, "midpoint": 2e-4, "rk4": 3e-4,
             "predict_reevaluate": 1e-4}
# Backward Euler is stable far beyond them: ball-particle contacts are part of its solve
# (collision/response/penalty.py), so large steps must not let the ball through either.
IMPLICIT_DT = {"implicit_euler": (5e-3, 1e-2, 1.0 / 60.0)}
STEPS = ([(name, dt) for name, dt in STABLE_DT.items()]
         + [(name, dt) for name, steps in IMPLICIT_DT.items() for dt in steps])


@pytest.mark.parametrize("integrator, dt", STEPS, ids=[f"{name}-{dt:.3g}" for name, dt in STEPS])
@pytest.mark.parametrize("height, speed", [(2.5, 0.0), (1.0, 20.0)], ids=["dropped", "thrown"])
def test_a_fast_ball_never_passes_through_the_cloth(integrator, dt, height, speed):
    scene = springsim.load_scene("cloth-balls")
    scene.bodies[1].balls = [Ball(position=(0.1, height, -0.05), velocity=(0.0, -speed, 0.0))]
    sim = springsim.Simulation(scene, integrator=integrator, dt=dt)
    lowest = np.inf
    for _ in range(50):
        sim.advance(0.02)
        depth, height_above = cloth_check(sim)
        assert depth < 0.05 and height_above > 0.3
        lowest = min(lowest, sim.positions[-1, 1])
    assert lowest < -0.3   # it did hit the cloth and push it down


@pytest.mark.parametrize("height, speed", [(2.5, 0.0), (1.0, 20.0)], ids=["dropped", "thrown"])
@pytest.mark.parametrize("dt", [1.0 / 30.0, 0.05])
def test_at_frame_steps_extra_newton_iterations_keep_even_the_fast_ball_out(height, speed, dt):
    """At dt = 1/30 s the 20 m/s ball moves 0.67 m, more than its radius, in one step (1 m at
    0.05 s): the contact normal turns within the step, and backward Euler relinearizes the contact
    springs (more Newton iterations, chosen by the step itself) to hold it."""
    scene = springsim.load_scene("cloth-balls")
    scene.bodies[1].balls = [Ball(position=(0.1, height, -0.05), velocity=(0.0, -speed, 0.0))]
    sim = springsim.Simulation(scene, integrator="implicit_euler", dt=dt)
    lowest = np.inf
    for _ in range(int(1.5 / dt)):
        sim.step(1)
        depth, height_above = cloth_check(sim)
        assert depth < 0.15 and height_above > 0.3   # a 0.67 to 1 m step may overlap briefly
        lowest = min(lowest, sim.positions[-1, 1])
    assert lowest < -0.3


@pytest.mark.parametrize("dt", [1e-2, 1.0 / 60.0])
def test_backward_euler_ball_particle_contacts_conserve_momentum(dt):
    """A 20 kg ball thrown at 10 m/s into a free 10 x 10 cloth (100 kg, springs, no pins, no
    gravity, no drag): the contacts inside the solve push the ball as hard as the cloth, so the
    momentum stays what it was while the ball loses most of its speed to the cloth."""
    ball = Balls(balls=[Ball(position=(0.1, 1.0, -0.05), velocity=(1.0, -10.0, 0.5), mass=20.0)],
                 drag=0.0)
    cloth = Cloth(particles_per_edge=10, width=2.0, height=2.0, pinned="none", drag=0.0,
                  velocity=(0.0, 1.0, 0.0))
    sim = simulation(cloth, ball, integrator="implicit_euler", dt=dt)
    mass = sim.model.mass
    momentum0 = mass @ sim.velocities
    scale = mass @ np.linalg.norm(sim.velocities, axis=1)
    for _ in range(round(0.5 / dt)):
        sim.step(1)
        np.testing.assert_allclose(mass @ sim.velocities, momentum0, rtol=0, atol=1e-9 * scale)
        depth, height = cloth_check(sim)
        assert depth < 0.05 and height > 0.3
    assert sim.velocities[-1, 1] > -1.0   # from -10 m/s: it pushed the cloth, and was pushed


def test_balls_dropped_on_the_jelly_cube_land_on_top_of_it():
    sim = springsim.Simulation(springsim.load_scene("jelly-balls"))
    arrays = sim.model.arrays
    balls, cube = arrays.balls, np.flatnonzero(arrays.radius == 0)
    for _ in range(40):
        sim.advance(0.1)
        x = sim.positions
        distance = np.linalg.norm(x[balls][:, None] - x[cube][None], axis=2)
        assert distance.min() > 0.9 * 0.5   # no ball sinks into the jelly
    assert np.all(x[balls, 1] > x[cube, 1].max())   # all three are on its top
