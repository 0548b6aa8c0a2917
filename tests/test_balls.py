"""Balls: particles with a radius and a mass, advanced by the ordinary integrators; drag; specs;
scenes that mix several cubes, cloths and balls."""
import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.errors import SceneError
from springsim.model import build_model
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.terrains import Plane


def test_a_ball_in_free_fall_follows_the_parabola():
    start, velocity, g = np.array([0.0, 5.0, 1.0]), np.array([2.0, 3.0, -1.0]), -9.8
    balls = Balls(balls=[Ball(position=tuple(start), velocity=tuple(velocity))], drag=0.0)
    sim = springsim.Simulation(Scene(bodies=[balls], dt=1e-3), integrator="rk4")
    sim.advance(1.5)
    t = sim.time
    np.testing.assert_allclose(sim.positions[0], start + velocity * t + [0, g * t * t / 2, 0],
                               atol=1e-10)


def test_drag_is_the_balls_own_plus_the_scenes_and_slows_a_ball_exponentially():
    # a = g - v c / m with c = 10 (scene) + 40 (balls): v(t) = v_end + (v0 - v_end) e^(-c t / m)
    mass, c = 125.0, 50.0
    v0 = np.array([3.0, 0.0, 0.0])
    balls = Balls(balls=[Ball(velocity=tuple(v0), mass=mass)], drag=40.0)
    sim = springsim.Simulation(Scene(bodies=[balls], dt=1e-3, drag=10.0), integrator="rk4")
    assert sim.model.arrays.drag[0] == c
    sim.advance(2.0)
    terminal = np.array([0.0, -9.8 * mass / c, 0.0])
    expected = terminal + (v0 - terminal) * np.exp(-c * sim.time / mass)
    np.testing.assert_allclose(sim.velocities[0], expected, rtol=1e-9, atol=1e-12)


def test_a_ball_comes_to_rest_on_a_plane_one_radius_above_it():
    plane = Plane()  # y = -1, restitution 0.8
    balls = Balls(balls=[Ball(position=(0.0, 1.0, 0.0), radius=0.3, mass=2.0)])
    sim = springsim.Simulation(Scene(bodies=[balls], terrains=[plane], dt=1e-3))
    lowest = np.inf
    for _ in range(60):
        sim.advance(0.1)
        lowest = min(lowest, sim.positions[0, 1])
    assert lowest > -1.0 + 0.3 - 1e-9  # the ball's surface never went below the plane
    assert abs(sim.positions[0, 1] - (-0.7)) < plane.epsilon
    assert np.linalg.norm(sim.velocities[0]) < 1e-2


def test_balls_from_tables_build_the_same_particles_as_ball_objects():
    objects = Balls(balls=[Ball(position=(1.0, 2.0, 3.0), radius=0.2, mass=4.0), Ball()])
    tables = Balls(balls=[{"position": [1.0, 2.0, 3.0], "radius": 0.2, "mass": 4.0}, {}])
    built_objects, built_tables = objects.build(), tables.build()
    for name in ("positions", "velocities", "masses", "radii"):
        np.testing.assert_array_equal(getattr(built_tables, name), getattr(built_objects, name))
    np.testing.assert_array_equal(built_objects.radii, [0.2, 0.5])
    np.testing.assert_array_equal(built_objects.masses, [4.0, 125.0])
    assert len(built_objects.springs) == 0


@pytest.mark.parametrize("change, key", [
    ({"balls": []}, "bodies.0.balls"),
    ({"balls": [Ball(radius=0.0)]}, "bodies.0.balls.0.radius"),
    ({"balls": [Ball(), Ball(mass=-1.0)]}, "bodies.0.balls.1.mass"),
    ({"balls": [Ball(position=(0.0, 1.0))]}, "bodies.0.balls.0.position"),
    ({"balls": [{"colour": "red"}]}, "bodies.0.balls.0.colour"),
    ({"ball_restitution": 1.5}, "bodies.0.ball_restitution"),
    ({"particle_restitution": -0.1}, "bodies.0.particle_restitution"),
    ({"particle_friction": -0.1}, "bodies.0.particle_friction"),
    ({"position_correction": 2.0}, "bodies.0.position_correction"),
    ({"drag": float("nan")}, "bodies.0.drag"),
])
def test_bad_ball_settings_are_scene_errors_naming_the_key(change, key):
    with pytest.raises(SceneError) as error:
        Scene(bodies=[Balls(**change)]).validate()
    assert error.value.key == key


def mixed_scene() -> Scene:
    soft = SpringParameters(ks=500.0, kd=5.0)
    return Scene(bodies=[
        Cube(particles_per_edge=3, position=(-4.0, 3.0, 0.0)),
        Balls(balls=[Ball(position=(0.0, 5.0, 0.0)), Ball(position=(2.0, 5.0, 0.0), radius=0.2)],
              ball_restitution=0.3, particle_friction=0.1),
        Cloth(particles_per_edge=4, position=(0.0, 2.0, 0.0), structural=soft, drag=0.5),
        Cube(particles_per_edge=4, position=(5.0, 3.0, 0.0)),
        Cloth(particles_per_edge=5, position=(0.0, 0.0, 6.0), pinned="none"),
        Balls(balls=[Ball(position=(0.0, 3.0, 6.0), mass=7.0)], ball_restitution=0.9),
    ], terrains=[Plane()], drag=0.25)


def test_a_scene_mixing_cubes_cloths_and_balls_builds_one_consistent_model():
    model = build_model(mixed_scene())
    sizes = [27, 2, 16, 64, 25, 1]
    assert [body.stop - body.start for body in model.bodies] == sizes
    assert model.particle_count == sum(sizes)
    balls = model.arrays.balls
    np.testing.assert_array_equal(balls, [27, 28, 27 + 2 + 16 + 64 + 25])
    np.testing.assert_array_equal(model.arrays.radius[balls], [0.5, 0.2, 0.5])
    assert np.count_nonzero(model.arrays.radius) == 3
    np.testing.assert_array_equal(model.arrays.ball_slot[balls], [0, 1, 2])
    assert np.all(np.delete(model.arrays.ball_slot, balls) == -1)
    # each ball collides with its own body's settings
    np.testing.assert_array_equal(model.arrays.ball_restitution, [0.3, 0.3, 0.9])
    np.testing.assert_array_equal(model.arrays.particle_friction, [0.1, 0.1, 0.03])
    # drag: the scene's 0.25 plus each body's own (cubes have none)
    expected_drag = np.repeat([0.25, 0.25 + 3.4e-4, 0.75, 0.25, 0.25 + 3.4e-4, 0.25 + 3.4e-4],
                              sizes)
    np.testing.assert_allclose(model.arrays.drag, expected_drag)
    # springs stay inside their bodies, with their body's stiffness
    body_of = np.repeat(np.arange(len(sizes)), sizes)
    a, b = model.springs[:, 0], model.springs[:, 1]
    assert np.array_equal(body_of[a], body_of[b])
    ks = model.arrays.group_ks[model.arrays.spring_group]
    first_cloth = body_of[a] == 2
    structural = model.spring_kind == 0
    assert np.all(ks[first_cloth & structural] == 500.0)
    assert np.all(ks[first_cloth & ~structural] == 25000.0)
    np.testing.assert_array_equal(model.pinned[29:45], Cloth(particles_per_edge=4).pinned_mask())


def test_a_scene_file_mixing_cubes_cloths_and_balls_loads(tmp_path):
    path = tmp_path / "mixed.toml"
    path.write_text("""
dt = 1e-4
[[bodies]]
type = "cube"
particles_per_edge = 3
position = [-4, 3, 0]
[[bodies]]
type = "cloth"
particles_per_edge = 5
pinned = "edge"
[[bodies]]
type = "cube"
particles_per_edge = 3
position = [4, 3, 0]
[[bodies]]
type = "cloth"
particles_per_edge = 4
position = [0, 0, 6]
pinned = [0, 3]
[[bodies]]
type = "balls"
ball_restitution = 0.5
[[bodies.balls]]
position = [0, 2, 0]
radius = 0.25
mass = 3
[[bodies.balls]]
position = [0, 2, 6]
[[terrains]]
type = "plane"
""")
    scene = springsim.load_scene(path)
    model = build_model(scene)
    assert [type(body).__name__ for body in scene.bodies] == ["Cube", "Cloth", "Cube", "Cloth",
                                                              "Balls"]
    assert model.particle_count == 27 + 25 + 27 + 16 + 2
    np.testing.assert_array_equal(model.arrays.radius[model.arrays.balls], [0.25, 0.5])
    np.testing.assert_array_equal(model.mass[model.arrays.balls], [3.0, 125.0])
    np.testing.assert_array_equal(model.arrays.ball_restitution, [0.5, 0.5])
    assert np.count_nonzero(model.pinned) == 5 + 2
