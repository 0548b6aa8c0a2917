"""The built-in scenes of a world that moves (presets.py), simulated as a user runs them: each
does what its description says, checked against the physics it shows.

Oracles: the cape never enters the walking figure (libigl's exact signed distance to the
figure's surface where its point cache has it); each jelly cube on the conveyor moves with the
platform's surface under it, c' + w x r (static friction, relative to the moving surface); the
flag's free edge streams downwind of where the same flag hangs in still air; no particle of the
curtain is ever inside the sphere sweeping through it.
"""
import numpy as np
import pytest

import springsim
from springsim.terrains.deforming_surface import surface_at


pytestmark = pytest.mark.slow   # the built-in moving scenes run for seconds of simulated time

def test_the_cape_lies_on_the_walking_figure_without_entering_it():
    """Laid over the shoulders, the cape falls onto them and down the back and rides there: from
    half a second on, hundreds of its particles lie within the contact band of the figure, none
    ever inside it, and the pinned ones keep to the neck as the figure walks on."""
    import igl

    scene = springsim.load_scene("cape")
    surface = scene.terrains[1].deforming_surface()
    simulation = springsim.Simulation(scene)
    pinned = simulation.model.pinned

    def distance_to_figure():
        vertices = surface_at(surface, simulation.time)
        return igl.signed_distance(simulation.positions, vertices, surface.triangles,
                                   sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0]

    deepest, touching, start = np.inf, [], simulation.positions[pinned].copy()
    gap, drift = distance_to_figure()[pinned], 0.0
    while simulation.time < 1.0 - 1e-9:
        simulation.step(3)
        distance = distance_to_figure()
        deepest = min(deepest, float(distance.min()))
        drift = max(drift, float(np.abs(distance[pinned] - gap).max()))
        if simulation.time > 0.5:
            touching.append(int(np.sum(distance < scene.terrains[1].epsilon)))
    assert deepest > -1e-6, f"a cape particle was {-deepest * 1e3:.2f} mm inside the figure"
    assert min(touching) > 100
    assert drift < 2e-3      # riveted: each pinned particle keeps its gap to the figure
    carried = np.linalg.norm(simulation.positions[pinned] - start, axis=1)
    assert carried.min() > 0.5 * 0.8   # the neck walked on at 0.8 m/s, the pins with it


def test_the_conveyors_cubes_ride_the_moving_turning_platform():
    scene = springsim.load_scene("jelly-conveyor")
    platform = scene.terrains[0]
    simulation = springsim.Simulation(scene)
    simulation.advance(2.0)
    model = simulation.model
    for body in model.bodies:
        x = simulation.positions[body.start:body.stop]
        v = simulation.velocities[body.start:body.stop]
        centre = x.mean(axis=0)
        rotation, carried, pivot = platform.pose_at(simulation.time)
        w = np.asarray(platform.motion.angular_velocity, float)
        surface = np.asarray(platform.motion.velocity, float) + np.cross(w, centre - carried)
        assert np.linalg.norm(v.mean(axis=0) - surface) < 0.02, body.name
        assert centre[1] > 0.0                                # on it, not fallen off


def test_the_flag_streams_downwind_of_where_it_hangs_in_still_air():
    windy = springsim.Simulation(springsim.load_scene("flag"))
    still_scene = springsim.load_scene("flag")
    still_scene.wind = None
    still = springsim.Simulation(still_scene)
    for simulation in (windy, still):
        simulation.advance(2.0)
    free = ~windy.model.pinned
    downwind = windy.positions[free, 0].mean() - still.positions[free, 0].mean()
    assert downwind > 0.3
    assert windy.positions[free, 1].mean() > still.positions[free, 1].mean() + 0.1   # held up


@pytest.mark.parametrize("integrator, dt", [("implicit_euler", None), ("rk4", 1e-4)])
def test_no_particle_of_the_swept_curtain_is_ever_inside_the_sphere(integrator, dt):
    scene = springsim.load_scene("cloth-sweep")
    sphere = scene.terrains[1]
    simulation = springsim.Simulation(scene, integrator=integrator, dt=dt or scene.dt)
    deepest, pushed = np.inf, 0.0
    every = 1 if dt is None else 100
    while simulation.time < 1.0 - 1e-9:
        simulation.step(every)
        centre = sphere.place_at([sphere.center], simulation.time)[0]
        distance = np.linalg.norm(simulation.positions - centre, axis=1) - sphere.radius
        deepest = min(deepest, float(distance.min()))
        pushed = max(pushed, float(simulation.positions[:, 2].max()))
    assert deepest > -1e-9
    assert pushed > 0.5   # the sphere carried the curtain along
