"""The Python API refuses misuse with one SceneError naming the argument, before any compiled
call: never a TypeError from inside, a Numba typing error, an OverflowError, or a write past the
end of an array.

Oracle: the error's key is the argument (or scene key) at fault, and the simulation is unchanged
by the refused call (time, steps and arrays as before), so the refusal came before any work.
"""
import math

import numpy as np
import pytest

import springsim
from springsim.bodies.cube import Cube
from springsim.collision.pair_lists import EDGES, POINTS
from springsim.errors import SceneError
from springsim.scene import Scene
from springsim.state import solve_pair_list
from springsim.motion import Motion
from springsim.substeps import collider_substeps
from springsim.terrains import Plane, Sphere

INF, NAN = math.inf, math.nan


@pytest.fixture(scope="module")
def simulation():
    return springsim.Simulation(springsim.load_scene("jelly-plane", [
        "bodies.0.particles_per_edge=3"]))


def refused(call, key):
    with pytest.raises(SceneError) as caught:
        call()
    assert caught.value.key == key, str(caught.value)
    assert "\n" not in str(caught.value)
    return str(caught.value)


@pytest.mark.parametrize("count", [1.5, "3", None, True, 2 ** 64, -1, 2 ** 53 + 1, 3.0,
                                   np.float64(2)])
def test_step_takes_only_a_whole_number_of_steps_in_range(simulation, count):
    before = simulation.state.copy()
    refused(lambda: simulation.step(count), "count")
    assert simulation.steps_taken == before.steps and simulation.time == before.time
    assert np.array_equal(simulation.positions, before.positions)


def test_step_takes_numpy_integers(simulation):
    steps = simulation.steps_taken
    simulation.step(np.int64(2))
    assert simulation.steps_taken == steps + 2


@pytest.mark.parametrize("seconds", ["1", None, INF, NAN, -0.5, 10 ** 400, 1e300])
def test_advance_takes_only_a_finite_time(simulation, seconds):
    steps = simulation.steps_taken
    refused(lambda: simulation.advance(seconds), "seconds")
    assert simulation.steps_taken == steps


def test_a_scene_name_is_not_a_scene():
    message = refused(lambda: springsim.Simulation("jelly-plane"), "scene")
    assert "springsim.load_scene('jelly-plane')" in message
    refused(lambda: springsim.Simulation({"bodies": []}), "scene")


@pytest.mark.parametrize("dt", ["0.001", NAN, INF, -1e-3, 0.0, True, 10 ** 400])
def test_dt_must_be_a_finite_positive_number(dt):
    refused(lambda: springsim.Simulation(springsim.load_scene("jelly-plane"), dt=dt), "dt")


@pytest.mark.parametrize("make, key", [
    (lambda: Cube(particle_mass=INF), "bodies.0.particle_mass"),
    (lambda: Cube(particle_mass="1"), "bodies.0.particle_mass"),
    (lambda: Cube(particle_mass=NAN), "bodies.0.particle_mass"),
    (lambda: Cube(edge_length=INF), "bodies.0.edge_length"),
    (lambda: Cube(particles_per_edge=4.0), "bodies.0.particles_per_edge"),
    (lambda: Cube(position=(0.0, "9", 0.0)), "bodies.0.position"),
])
def test_body_values_are_checked_as_a_scene_file_checks_them(make, key):
    scene = Scene(bodies=[make()], terrains=[Plane()])
    refused(lambda: springsim.Simulation(scene), key)


@pytest.mark.parametrize("name, value", [("friction", INF), ("friction", "0.3"),
                                         ("restitution", NAN), ("epsilon", INF)])
def test_terrain_values_are_checked_as_a_scene_file_checks_them(name, value):
    scene = Scene(bodies=[Cube()], terrains=[Plane(**{name: value})])
    refused(lambda: springsim.Simulation(scene), f"terrains.0.{name}")


@pytest.mark.parametrize("make, key, says", [
    (lambda: Scene(bodies=[Cube()], terrains=[Sphere(center=(3.0, 0.0, 0.0), motion=Motion(
        keyframes=[{"time": 0.0}, {"time": 1.0, "position": (1.0, 0.0, 0.0)}]))]),
     "terrains.0.motion.keyframes.0", "= {'time': 0.0}: must be a Keyframe object, not a dict"),
    (lambda: Scene(bodies=[Cube()], terrains=[Plane(motion={"velocity": [1.0, 0.0, 0.0]})]),
     "terrains.0.motion", "must be a Motion object, not a dict"),
    (lambda: Scene(bodies=[Cube()], terrains=[{"type": "plane"}]), "terrains.0",
     "must be a terrain object (Bowl, MeshTerrain, Plane, Sphere, tilted_plane), not a dict"),
    (lambda: Scene(bodies=[Cube(pins=[{"particles": [0]}])]), "bodies.0.pins.0",
     "must be a Pin object, not a dict"),
])
def test_a_dict_where_an_object_goes_is_refused_by_its_full_key(make, key, says):
    """A table in a scene file becomes an object; in Python a dict there once converted
    cleanly, then failed where its attributes were read (AttributeError)."""
    assert says in refused(lambda: springsim.Simulation(make()), key)


def test_a_motion_beyond_float64_in_one_step_is_refused_by_the_substeps():
    """A motion the checks let through (each number within bounds) whose step is still beyond
    float64 (a large dt): once an OverflowError in substeps.py."""
    sphere = Sphere(center=(3.0, 0.0, 0.0), motion=Motion(velocity=(1e150, 0.0, 0.0)))
    message = refused(lambda: collider_substeps([sphere], 1e10), "terrains.0.motion.velocity")
    assert "further than float64 can measure in one step of dt = 1e+10 s" in message


def test_the_same_value_is_refused_in_a_file_and_through_the_api(tmp_path):
    """The API's message is the scene file's, word for word."""
    path = tmp_path / "s.toml"
    path.write_text('[[bodies]]\ntype = "cube"\nparticle_mass = inf\n')
    with pytest.raises(SceneError) as from_file:
        springsim.load_scene(str(path))
    with pytest.raises(SceneError) as from_api:
        springsim.Simulation(Scene(bodies=[Cube(particle_mass=INF)]))
    assert str(from_api.value) == str(from_file.value)


@pytest.mark.parametrize("name, replacement", [
    ("positions", lambda x: np.zeros((len(x) + 50, 3))),          # more particles
    ("positions", lambda x: np.zeros((len(x) - 1, 3))),           # fewer
    ("positions", lambda x: x.astype(np.float32)),
    ("positions", lambda x: np.asfortranarray(x)),
    ("velocities", lambda x: np.zeros((len(x), 2))),
    ("velocities", lambda x: x.tolist()),
    ("positions", lambda x: np.repeat(x, 2, axis=0)[::2]),       # a strided view
])
def test_a_replaced_state_array_of_another_shape_or_layout_is_refused(name, replacement):
    simulation = springsim.Simulation(springsim.load_scene("jelly-plane", [
        "bodies.0.particles_per_edge=3"]))
    setattr(simulation.state, name, replacement(getattr(simulation.state, name)))
    refused(lambda: simulation.step(10), f"state.{name}")
    assert simulation.steps_taken == 0


def test_read_only_arrays_and_a_foreign_contact_memory_are_refused():
    simulation = springsim.Simulation(springsim.load_scene("jelly-plane"),
                                      integrator="implicit_euler", dt=0.01)
    simulation.state.velocities.flags.writeable = False
    refused(lambda: simulation.step(1), "state.velocities")
    simulation.state.velocities.flags.writeable = True
    contacts = simulation.state.contacts
    simulation.state.contacts = contacts._replace(terrain=np.full(10, -1))
    refused(lambda: simulation.step(1), "state.contacts.terrain")
    simulation.state.contacts = contacts._replace(kind=contacts.kind.astype(np.int64))
    refused(lambda: simulation.step(1), "state.contacts.kind")
    simulation.state.contacts = contacts
    simulation.step(1)
    assert simulation.steps_taken == 1


def test_a_pair_list_that_numbers_shapes_the_model_lacks_is_refused():
    """The kernels trust a pair list's rows: one naming a triangle or an edge past the model's,
    or of another dtype, is refused before the step (it would be read past an array's end)."""
    simulation = springsim.Simulation(springsim.load_scene("jelly-stack"), dt=1e-3)
    simulation.step(1)
    pairs = simulation.state.pairs
    triangles = len(simulation.model.arrays.surface_triangles)
    simulation.state.pairs = pairs._replace(points=np.array([[0, triangles]], np.int64))
    refused(lambda: simulation.step(1), "state.pairs.points")
    simulation.state.pairs = pairs._replace(edges=np.zeros((1, 2), np.int32))
    refused(lambda: simulation.step(1), "state.pairs.edges")
    simulation.state.pairs = (pairs.points, pairs.edges)
    refused(lambda: simulation.step(1), "state.pairs")
    simulation.state.pairs = pairs
    simulation.step(1)
    assert simulation.steps_taken == 2


def test_a_solve_pair_list_that_numbers_shapes_the_model_lacks_is_refused():
    """Backward Euler's kept list of pairs of two bodies is read by its kernels too: one naming
    a triangle past the model's, or found for another number of particles, is refused."""
    simulation = springsim.Simulation(springsim.load_scene("jelly-stack"), dt=1 / 60,
                                      integrator="implicit_euler")
    simulation.step(1)
    kept = simulation.state.solve_pairs
    triangles = len(simulation.model.arrays.surface_triangles)
    wrong = solve_pair_list(np.array([[0, triangles]]), kept.pairs[EDGES], kept.found_at,
                            kept.reach)
    simulation.state.solve_pairs = wrong
    refused(lambda: simulation.step(1), "state.solve_pairs.points")
    simulation.state.solve_pairs = solve_pair_list(kept.pairs[POINTS], kept.pairs[EDGES],
                                                   kept.found_at[:-1], kept.reach)
    refused(lambda: simulation.step(1), "state.solve_pairs")
    simulation.state.solve_pairs = kept
    simulation.step(1)
    assert simulation.steps_taken == 2
