"""Substeps for fast colliders (substeps.py): a moving terrain never passes through a particle.

Oracles: a sphere of 5 cm radius crossing a hanging curtain at 10 m/s (17 cm in a 1/60 s step,
more than its diameter) carries the particles in its path along with it (without substeps they
stay within 5 cm of where they hung: it passes through them); the substep count is the analytic
ceil(v dt / (SHARE 2 r)); a keyframed motion's fastest stretch, however short, sets it; a run
resumed from a saved state equals the run that went on, bit for bit; a half-space needs none.
"""
import math

import numpy as np
import pytest

import springsim
from springsim.bodies.cloth import Cloth
from springsim.errors import SceneError
from springsim.motion import Keyframe, Motion
from springsim.scene import Scene
from springsim.substeps import SHARE, collider_substeps
from springsim.terrains.plane import Plane
from springsim.terrains.sphere import Sphere

RADIUS, SPEED = 0.05, 10.0


def curtain_scene(dt, speed=SPEED):
    """A 2 m curtain of 41 x 41 particles in the z = 0 plane, held along its top edge, and a
    sphere that starts 1 m in front of its middle and crosses it along +z at ``speed``."""
    sphere = Sphere(center=(0.0, 1.0, -1.0), radius=RADIUS,
                    motion=Motion(velocity=(0.0, 0.0, speed)))
    cloth = Cloth(particles_per_edge=41, width=2.0, height=2.0, position=(0.0, 1.0, 0.0),
                  rotation_degrees=90.0, rotation_axis=(1.0, 0.0, 0.0), pinned="edge+z")
    return Scene(bodies=[cloth], terrains=[sphere], integrator="implicit_euler", dt=dt,
                 gravity=(0.0, 0.0, 0.0))


@pytest.mark.parametrize("dt", [1 / 60, 1 / 30])
def test_a_fast_sphere_carries_the_curtain_instead_of_passing_through_it(dt):
    simulation = springsim.Simulation(curtain_scene(dt))
    substeps = simulation.substeps()
    assert substeps.count == math.ceil(SPEED * dt / (SHARE * 2 * RADIUS)) > 1
    start = simulation.positions.copy()
    in_path = np.linalg.norm(start[:, :2] - [0.0, 1.0], axis=1) < 0.6 * RADIUS
    assert in_path.sum() >= 1
    simulation.advance(0.3)   # the sphere ends 2 m past the curtain
    # carried along (2 m at most, less what the cloth's pull lets it slip)
    assert np.all(simulation.positions[in_path, 2] - start[in_path, 2] > 1.0)


def test_the_substeps_take_the_fastest_stretch_of_a_keyframed_motion():
    """Still for a second, then 1 m in 0.02 s (50 m/s), then still: the 20 ms stretch sets the
    travel of a 1/60 s step, 50 m/s x 1/60 s."""
    dt = 1 / 60
    keys = [Keyframe(0.0, (0.0, 0.0, 0.0)), Keyframe(1.0, (0.0, 0.0, 0.0)),
            Keyframe(1.02, (0.0, 0.0, 1.0)), Keyframe(3.0, (0.0, 0.0, 1.0))]
    sphere = Sphere(center=(0.0, 1.0, 0.0), radius=0.2, motion=Motion(keyframes=keys))
    found = collider_substeps([Plane(), sphere], dt)
    assert found.terrain == 1 and found.travel == pytest.approx(50.0 * dt, rel=1e-9)
    assert found.count == math.ceil(50.0 * dt / (SHARE * 0.4))


def test_still_terrains_and_half_spaces_need_no_substeps():
    fast_plane = Plane(motion=Motion(velocity=(0.0, 100.0, 0.0)))
    assert collider_substeps([fast_plane, Sphere()], 1 / 60).count == 1


def test_a_run_resumed_from_a_saved_state_is_the_run_that_went_on(tmp_path):
    """The substeps are chosen from the scene and dt alone, so a run saved after two steps and
    resumed in a new Simulation ends where the run that went on ends, to the last bit."""
    going_on = springsim.Simulation(curtain_scene(1 / 30))
    going_on.step(2)
    going_on.save_state(tmp_path / "state.npz")
    going_on.step(2)
    going_on.step(2)
    resumed = springsim.Simulation(curtain_scene(1 / 30))
    resumed.load_state(tmp_path / "state.npz")
    resumed.step(2)
    resumed.step(2)
    assert np.array_equal(going_on.positions, resumed.positions)
    assert going_on.steps_taken == resumed.steps_taken == 6
    assert going_on.time == pytest.approx(6 / 30, rel=1e-12)


def test_a_motion_too_fast_for_any_substeps_is_one_line_before_the_run():
    with pytest.raises(SceneError) as raised:
        springsim.Simulation(curtain_scene(1 / 60, speed=1e6))
    assert raised.value.key == "terrains.0.motion.velocity" and "smaller dt" in str(raised.value)
    assert "\n" not in str(raised.value)


def test_a_closed_mesh_is_as_thick_as_its_smallest_side_and_an_open_one_is_a_half_space(
        tmp_path):
    import trimesh

    from springsim.terrains import MeshTerrain

    trimesh.creation.box((2.0, 0.3, 1.0)).export(tmp_path / "slab.obj")
    floor = trimesh.Trimesh([[-1, 0, -1], [1, 0, -1], [1, 0, 1], [-1, 0, 1]],
                            [[0, 2, 1], [0, 3, 2]], process=False)
    floor.export(tmp_path / "floor.obj")
    assert MeshTerrain(file=str(tmp_path / "slab.obj")).thickness() == pytest.approx(0.3)
    assert MeshTerrain(file=str(tmp_path / "floor.obj")).thickness() == math.inf
