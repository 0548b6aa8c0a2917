"""The penetration a run reports (the recording's ``penetration``, the summary, the stability
tools) is measured against each terrain where it is at the frame's time: a terrain moving by a
motion, or deforming by a point cache, is no longer measured where it started.

Oracles: a sphere moving at a constant velocity and a plane turning at a constant rate, with
points placed at known depths below them where they are at time t (analytic); pinned points that
a moving sphere runs into, depth max(0, R - min |x - c(t)|) at every frame; the cape's
figure, against libigl's exact signed distance to the surface the point cache has at each frame.
"""
import math

import numpy as np
import pytest

import springsim
from springsim.bodies.cloth import Cloth
from springsim.model import build_model
from springsim.motion import Motion
from springsim.recording import deepest_penetration, record
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.stability import deepest_penetration as depth_beyond_band
from springsim.terrains import Plane, Sphere
from springsim.terrains.deforming_surface import surface_at

SPEED = 2.0                 # m/s, the sphere's, along x
TURN = math.pi / 2          # rad/s, the plane's, about z
NO_SPRINGS = SpringParameters(0.0, 0.0)


def pinned_points(position=(0.0, 5.0, 0.0), width=0.4):
    """Four pinned points (a spring-less 2 x 2 cloth with its corners pinned)."""
    return Cloth(particles_per_edge=2, width=width, height=width, position=position,
                 pinned="corners", drag=0.0, structural=NO_SPRINGS, shear=NO_SPRINGS,
                 bend=NO_SPRINGS)


def moving_sphere(position=(0.0, 5.0, 0.0)):
    sphere = Sphere(center=(0.0, 0.0, 0.0), radius=1.0, motion=Motion(velocity=(SPEED, 0.0, 0.0)))
    return Scene(bodies=[pinned_points(position)], terrains=[sphere], gravity=(0.0, 0.0, 0.0))


@pytest.mark.parametrize("t", [0.0, 0.25, 0.5, 1.5])
def test_a_point_inside_a_moving_sphere_is_as_deep_as_it_is_where_the_sphere_is_then(t):
    model = build_model(moving_sphere())
    x = model.initial_positions.copy()   # the points 5 m above the sphere's path: free
    assert deepest_penetration(model, x, t) == 0.0
    x[2] = (SPEED * t + 0.7, 0.0, 0.0)   # 0.3 m inside the sphere centred at (2t, 0, 0)
    assert deepest_penetration(model, x, t) == pytest.approx(0.3, abs=1e-12)


@pytest.mark.parametrize("t", [0.0, 0.3, 1.0])
def test_a_point_below_a_turning_plane_is_as_deep_as_it_is_below_the_plane_then(t):
    plane = Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0),
                  motion=Motion(angular_velocity=(0.0, 0.0, TURN)))
    model = build_model(Scene(bodies=[pinned_points()], terrains=[plane]))
    angle = TURN * t
    normal = np.array([-math.sin(angle), math.cos(angle), 0.0])   # (0, 1, 0) turned about z
    along = np.array([math.cos(angle), math.sin(angle), 0.0])
    x = np.tile(4.0 * normal, (model.particle_count, 1))   # 4 m above it: free
    assert deepest_penetration(model, x, t) == 0.0
    x[1] = 0.5 * along - 0.2 * normal   # 0.2 m below the plane as it has turned by t
    assert deepest_penetration(model, x, t) == pytest.approx(0.2, abs=1e-12)


def test_the_recording_and_the_stability_check_measure_a_moving_sphere_where_it_is():
    """Pinned points in the moving sphere's path (contact moves no pinned particle): it reaches
    them at 0.41 s and has them 0.72 m deep at 1 s, where measured at its start it would never
    reach them."""
    scene = moving_sphere(position=(2.0, 0.0, 0.0))
    simulation = springsim.Simulation(scene, integrator="implicit_euler", dt=1 / 60)
    recording = record(simulation, duration=1.0, fps=10.0)
    x = recording.positions[0]
    assert np.array_equal(recording.positions[-1], x)   # pinned: they stay
    centres = np.outer(recording.time, [SPEED, 0.0, 0.0])
    nearest = np.linalg.norm(x[None] - centres[:, None], axis=2).min(axis=1)
    expected = np.maximum(0.0, 1.0 - nearest)
    assert expected[0] == 0.0 and expected[-1] > 0.7
    np.testing.assert_allclose(recording.penetration, expected, rtol=0, atol=1e-12)
    # the stability tools: the depth beyond the contact band, at the simulation's own time
    assert depth_beyond_band(simulation) == pytest.approx(1.0 - nearest[-1] - 0.01, abs=1e-12)


def test_the_cape_penetration_is_the_exact_distance_to_the_figure_where_the_cache_has_it():
    """The cape (a coarser cloth: 20 x 20) over its walking figure for 0.2 s: at every frame
    the recorded penetration is the deepest of libigl's exact signed distances to the figure
    where the point cache has it then, and of the depths below the floor y = 0. Measured where
    the figure started, this run reported 1.8 mm from t = 1/15 s (the full cape 0.197 m at
    t = 1/3 s) with no particle inside."""
    import igl

    scene = springsim.load_scene("cape", ["bodies.0.particles_per_edge=20"])
    surface = scene.terrains[1].deforming_surface()
    recording = record(springsim.Simulation(scene), duration=0.2, fps=30.0)
    for frame, t in enumerate(recording.time):
        x = recording.positions[frame]
        inside = -igl.signed_distance(x, surface_at(surface, t), surface.triangles,
                                      sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0]
        exact = max(0.0, float(inside.max()), float(-x[:, 1].min()))
        assert recording.penetration[frame] == pytest.approx(exact, abs=1e-9), f"t = {t:.4f} s"
