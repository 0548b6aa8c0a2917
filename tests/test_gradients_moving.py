"""Gradients through contact with terrains that move rigidly (gradients/terrain_shapes.Moving)
under every integrator with an adjoint, against central finite differences of the forward run:
a cube resting on a platform that slides and turns under it (friction on the velocity relative
to the surface, the turn carrying the normal), one on a plane that tilts up under it (each
particle held at the surface's normal velocity, which changes along the plane), a ball dropped
onto the shoulder of a sphere that rises and spins (the surface's velocity w x r depends on
where the ball touches, and the normal turns with it), and the same ball onto a plane that
tilts as it rises, on a keyed path; a small sphere fast enough that each step is taken in
parts; and the platform far below the cube, where rk4's adjoint takes its kernels."""
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


def lifting_plane():
    """The small cube resting in a plane's band, the plane turning at 0.5 rad/s about a
    horizontal axis through (-1, 0, 0): its surface lifts the cube at about 0.5 m/s, faster
    under the far side, so that each particle's floor is the surface's normal velocity where
    it rests."""
    scene = platform()
    scene.terrains[0].motion = Motion(angular_velocity=(0.0, 0.0, 0.5), pivot=(-1.0, 0.0, 0.0))
    return scene


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


def fast_sphere():
    """A small sphere rising at 40 m/s into the resting cube's bottom face: 8 cm a step of
    2 ms, past its 0.4 of its 16 cm thickness, so each step is taken in two parts
    (substeps.py)."""
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 0.6, 0.0), pinned=())
    return Scene(bodies=[cube], drag=0.1, terrains=[
        Sphere(center=(0.05, -0.2, 0.03), radius=0.08, friction=0.3, restitution=0.5,
               motion=Motion(velocity=(0.0, 40.0, 0.0)))])


def far_platform():
    """The sliding, turning platform 1.5 m below the small cube, which it never reaches: rk4's
    steps take the kernels (contact.far_from_terrains)."""
    scene = platform()
    scene.bodies[0].position = (0.0, 2.0, 0.0)
    return scene


SCENES = {"far-platform": (far_platform, ["bodies.0.structural.ks", "gravity"]),
          "platform": (platform, ["terrains.0.friction", "bodies.0.structural.ks", "gravity",
                                  "bodies.0.velocity"]),
          "lifting-plane": (lifting_plane, ["terrains.0.friction", "bodies.0.structural.ks",
                                            "gravity", "bodies.0.velocity"]),
          "spinning-sphere": (spinning_sphere, BALL_KEYS),
          "tilting-plane": (tilting_plane, BALL_KEYS),
          "fast-sphere": (fast_sphere, ["bodies.0.structural.ks", "gravity",
                                        "terrains.0.restitution"])}


@pytest.mark.parametrize("case", list(SCENES))
@pytest.mark.parametrize("integrator", EXPLICIT + ["implicit_euler"])
def test_moving_terrain_gradients_match_finite_differences(integrator, case):
    scene_of, names = SCENES[case]
    if case == "fast-sphere":   # steps taken in two parts are the run of steps half as long
        from springsim import Simulation
        whole = Simulation(scene_of(), integrator=integrator, dt=0.002)
        halves = Simulation(scene_of(), integrator=integrator, dt=0.001)
        assert whole.substeps().count == 2 and halves.substeps().count == 1
        whole.step(10)
        halves.step(20)
        assert np.array_equal(whole.positions, halves.positions)
    assert_gradients_match(scene_of, integrator, names)


def deforming_terrain(folder, vertices, triangles, path, frames=3, fps=10.0, **settings):
    """A mesh terrain whose point cache has the vertices at ``path(t, vertices)`` for each
    frame's time t."""
    from springsim.animation import Animation
    from springsim.terrains import MeshTerrain
    from test_deforming_terrains import write_obj, write_pc2

    name = f"deforming{len(list(folder.glob('*.obj')))}"
    write_obj(folder / f"{name}.obj", vertices, triangles)
    samples = np.stack([path(k / fps, vertices) for k in range(frames)])
    write_pc2(folder / f"{name}.pc2", samples, fps=fps)
    return MeshTerrain(file=str(folder / f"{name}.obj"),
                       animation=Animation(str(folder / f"{name}.pc2"), fps=fps), **settings)


def plate(n=9, size=3.0):
    from test_deforming_terrains import plate as square
    return square(n, size)


def tent():
    """Two slopes rising 0.5 m to a ridge along z: the ridge is the closest feature of a
    point above it (its edge region), whose normal turns with the point."""
    vertices = np.array([[-1.0, 0.0, -1.0], [-1.0, 0.0, 1.0], [0.0, 0.5, -1.0], [0.0, 0.5, 1.0],
                         [1.0, 0.0, -1.0], [1.0, 0.0, 1.0]])
    return vertices, np.array([[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5]])


def rising_tilting(t, vertices):
    """Up at 0.5 m/s, sideways at 0.4 m/s, and tilting: each vertex rises 0.3 m/s more per m
    of x, so the surface's velocity differs across every triangle."""
    return vertices + t * np.column_stack([np.full(len(vertices), 0.4),
                                           0.5 + 0.3 * vertices[:, 0],
                                           np.zeros(len(vertices))])


def twisting_ridge(t, vertices):
    """Up at 0.2 to 0.8 m/s along z (the far end faster), so the ridge's velocity varies along
    it."""
    return vertices + t * np.column_stack([np.zeros(len(vertices)), 0.5 + 0.3 * vertices[:, 2],
                                           0.1 * vertices[:, 2]])


def cube_on_deforming_plate(folder):
    """The small cube resting in the band of a plate that rises, slides and tilts under it,
    placed off the plate's vertices and edges (where the closest feature changes)."""
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.1, 0.503, 0.07),
                velocity=(0.0, -0.1, 0.0), pinned=())
    return Scene(bodies=[cube], drag=0.1, terrains=[deforming_terrain(
        folder, *plate(), rising_tilting, friction=0.6, restitution=0.3)])


def ball_on_deforming_ridge(folder):
    """A ball 5 mm above the tent's ridge, which rises faster at one end."""
    ball = Ball(position=(0.05, 0.705, 0.1), velocity=(0.3, -1.5, 0.2), radius=0.2, mass=2.0)
    return Scene(bodies=[Balls(balls=[ball])], drag=0.1, terrains=[deforming_terrain(
        folder, *tent(), twisting_ridge, friction=0.4, restitution=0.6)])


def cube_thrown_onto_deforming_plate(folder):
    """The small cube 15 cm above a plate that its point cache holds still, thrown down at
    10 m/s: under implicit_euler at 10 ms a step its bottom reaches the plate from beyond the
    grid's reach (4 cm), found by the forward's swept lookup (gradients/implicit_lookup.py)."""
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.1, 0.65, 0.07),
                velocity=(0.5, -10.0, 0.2), pinned=())
    return Scene(bodies=[cube], drag=0.1, terrains=[deforming_terrain(
        folder, *plate(), lambda t, p: p, friction=0.6, restitution=0.3)])


def ball_thrown_onto_deforming_ridge(folder):
    """A ball 9 cm above the rising tent's ridge thrown down at 10 m/s: under implicit_euler
    it reaches the ridge (an edge, where the normal turns) from beyond the grid's reach (8 cm:
    the ridge's fastest vertex moves that far between frames)."""
    scene = ball_on_deforming_ridge(folder)
    scene.bodies[0].balls[0].position = (0.05, 0.79, 0.1)
    scene.bodies[0].balls[0].velocity = (0.3, -10.0, 0.2)
    return scene


DEFORMING = {"plate": (cube_on_deforming_plate, ["terrains.0.friction", "bodies.0.structural.ks",
                                                  "gravity", "bodies.0.velocity"]),
             "ridge": (ball_on_deforming_ridge, BALL_KEYS),
             "thrown": (cube_thrown_onto_deforming_plate, ["terrains.0.friction",
                                                           "bodies.0.structural.ks", "gravity",
                                                           "bodies.0.velocity",
                                                           "terrains.0.restitution"]),
             "thrown-ridge": (ball_thrown_onto_deforming_ridge, BALL_KEYS)}


@pytest.mark.parametrize("case", list(DEFORMING))
@pytest.mark.parametrize("integrator", EXPLICIT + ["implicit_euler"])
def test_deforming_terrain_gradients_match_finite_differences(integrator, case, tmp_path):
    """Contact with a mesh that a point cache deforms (gradients/terrain_shapes.Deforming): on
    a plate's faces, whose surface velocity varies across each triangle, and on a ridge's edge,
    whose normal turns with the ball; the terrain's friction or restitution takes part, so the
    contact happened."""
    from springsim.gradients import gradient
    from test_gradients import STEPS, weighted_squares

    make, names = DEFORMING[case]
    assert_gradients_match(lambda: make(tmp_path), integrator, names)
    dt = STEPS[integrator]
    _, grads = gradient(make(tmp_path), weighted_squares, [names[0]], duration=10 * dt,
                        integrator=integrator, dt=dt, fps=1 / (4 * dt))
    assert abs(float(np.ravel(grads[names[0]])[0])) > 1e-3


@pytest.mark.parametrize("stride_memory", [1 << 30, 1])
def test_the_adjoint_takes_each_step_at_the_forward_runs_own_time(stride_memory):
    """The backward pass sets each step's start to the time the forward run had there (its
    accumulated clock), with every state kept and with checkpoints run again: start + n h
    rounds otherwise (asserted here), and at a keyframe on a step boundary the two would take
    the surface's velocity from opposite sides of the kink."""
    from springsim.gradients.clock import STEP_START
    from springsim.gradients.physics import Physical
    from springsim.gradients.tape import backward, record
    from springsim.simulation import Simulation

    dt, steps = 1 / 600, 40
    forward = Simulation(platform(), integrator="symplectic_euler", dt=dt)
    times = []
    for _ in range(steps):
        times.append(forward.time)
        forward.step(1)
    assert any(t != n * dt for n, t in enumerate(times))

    class Spy:
        def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar, kept=None):
            seen.append(float(physical.clock[STEP_START]))
            return x_bar, v_bar

    seen = []
    simulation = Simulation(platform(), integrator="symplectic_euler", dt=dt)
    _, tape = record(simulation, steps, np.array([steps]), stride_memory)
    assert (tape.stride > 1) == (stride_memory == 1)
    physical = Physical.of(simulation.model)
    backward(simulation, Spy(), physical, tape, np.array([steps]),
             np.zeros((1, simulation.model.particle_count, 3)))
    assert seen[::-1] == times


@pytest.mark.parametrize("case, count, turning", [("thrown", 9, False),
                                                   ("thrown-ridge", 1, True)])
def test_a_swept_contact_takes_part_under_implicit_euler(tmp_path, monkeypatch, case, count,
                                                         turning):
    """The thrown cases' swept contacts reach the adjoint (implicit_lookup.swept_vjp): the
    cube's bottom layer on the plate's faces, the ball on the ridge, where the normal turns."""
    from springsim.gradients import gradient, implicit_contact
    from test_gradients import weighted_squares

    real, rows, turns = implicit_contact.swept_vjp, [], []

    def spy(shape, at, *rest):
        rows.append(len(at))
        turns.append(bool(np.any(shape.curvature(at) != 0.0)))
        return real(shape, at, *rest)

    monkeypatch.setattr(implicit_contact, "swept_vjp", spy)
    gradient(DEFORMING[case][0](tmp_path), weighted_squares, ["gravity"],
             duration=0.1, integrator="implicit_euler", dt=0.01)
    assert sum(rows) >= count and any(turns) == turning
