"""Gradients through contact with terrains that move rigidly (gradients/terrain_shapes.Moving)
under the explicit methods, against central finite differences of the forward run: a cube
resting on a platform that slides and turns under it (friction on the velocity relative to the
surface, the turn carrying the normal), a ball dropped onto the shoulder of a sphere that rises
and spins (the surface's velocity w x r depends on where the ball touches, and the normal
turns with it), and the same ball onto a plane that tilts as it rises, on a keyed path; and the
platform far below the cube, where rk4's adjoint takes its kernels."""
import numpy as np
import pytest

from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cube import Cube
from springsim.motion import Keyframe, Motion
from springsim.scene import Scene
from springsim.terrains.plane import Plane
from springsim.terrains.sphere import Sphere
from test_gradients import assert_gradients_match

EXPLICIT = ["symplectic_euler", "rk4"]
BALL_KEYS = ["terrains.0.restitution", "terrains.0.friction", "gravity",
             "bodies.0.balls.0.velocity", "drag"]


def platform():
    """The small cube resting in a plane's band, the plane sliding at 1 m/s and turning at
    2 rad/s about a vertical axis through (0.3, 0, 0.2)."""
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 0.503, 0.0),
                velocity=(0.0, -0.1, 0.0), pinned=())
    motion = Motion(velocity=(1.0, 0.0, 0.0), angular_velocity=(0.0, 2.0, 0.0),
                    pivot=(0.3, 0.0, 0.2))
    return Scene(bodies=[cube], drag=0.1, terrains=[
        Plane(point=(0.0, 0.0, 0.0), friction=0.6, restitution=0.3, motion=motion)])


def spinning_sphere():
    """A ball 5 mm above a sphere's shoulder, the sphere rising at 0.5 m/s and spinning at
    4 rad/s about its centre's z axis."""
    ball = Ball(position=(0.5, 0.8714, 0.0), velocity=(0.3, -1.5, 0.2), radius=0.2, mass=2.0)
    motion = Motion(velocity=(0.0, 0.5, 0.0), angular_velocity=(0.0, 0.0, 4.0))
    return Scene(bodies=[Balls(balls=[ball])], drag=0.1, terrains=[
        Sphere(center=(0.0, 0.0, 0.0), radius=0.8, friction=0.4, restitution=0.6,
               motion=motion)])


def tilting_plane():
    """A ball 5 mm above a plane that rises and tilts on a smooth keyed path."""
    ball = Ball(position=(0.1, 0.205, -0.1), velocity=(0.5, -1.0, 0.0), radius=0.2, mass=2.0)
    motion = Motion(interpolation="smooth", keyframes=[
        Keyframe(time=0.0, position=(0.0, 0.0, 0.0)),
        Keyframe(time=0.05, position=(0.0, 0.03, 0.01), rotation_degrees=4.0,
                 rotation_axis=(1.0, 0.0, 0.2))])
    return Scene(bodies=[Balls(balls=[ball])], drag=0.1, terrains=[
        Plane(point=(0.0, 0.0, 0.0), friction=0.4, restitution=0.6, motion=motion)])


def far_platform():
    """The sliding, turning platform 1.5 m below the small cube, which it never reaches: rk4's
    steps take the kernels (contact.far_from_terrains)."""
    scene = platform()
    scene.bodies[0].position = (0.0, 2.0, 0.0)
    return scene


SCENES = {"far-platform": (far_platform, ["bodies.0.structural.ks", "gravity"]),
          "platform": (platform, ["terrains.0.friction", "bodies.0.structural.ks", "gravity",
                                  "bodies.0.velocity"]),
          "spinning-sphere": (spinning_sphere, BALL_KEYS),
          "tilting-plane": (tilting_plane, BALL_KEYS)}


@pytest.mark.parametrize("case", list(SCENES))
@pytest.mark.parametrize("integrator", EXPLICIT)
def test_moving_terrain_gradients_match_finite_differences(integrator, case):
    scene_of, names = SCENES[case]
    assert_gradients_match(scene_of, integrator, names)


def test_a_deforming_terrain_is_refused_where_it_is(tmp_path):
    """A plate that a point cache lifts 1.5 m into the small cube within the run is refused: the
    check looks it up where its animation has it (where the scene placed it, it stays clear)."""
    from springsim.animation import Animation
    from springsim.errors import SceneError
    from springsim.gradients import gradient
    from springsim.terrains import MeshTerrain
    from test_deforming_terrains import plate, write_obj, write_pc2
    from test_gradients import small_scene, weighted_squares

    vertices, triangles = plate()
    write_obj(tmp_path / "plate.obj", vertices, triangles)
    frames = vertices[None] + (np.arange(4) * 1.0)[:, None, None] * np.array([0.0, 1.0, 0.0])
    write_pc2(tmp_path / "plate.pc2", frames, fps=10.0)
    scene = small_scene()
    scene.bodies[0].pinned = ()
    scene.terrains = [MeshTerrain(file=str(tmp_path / "plate.obj"),
                                  animation=Animation(str(tmp_path / "plate.pc2"), fps=10.0))]
    with pytest.raises(SceneError, match="terrains.0 = 'MeshTerrain': is touched at step"):
        gradient(scene, weighted_squares, ["gravity"], duration=0.2, integrator="rk4",
                 dt=0.002)
