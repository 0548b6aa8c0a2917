"""Deforming mesh terrains and pins driven by point caches (terrains/deforming_mesh.py,
animation.py, bodies/pins.py): oracles are the rigid motion a cache can also describe, the exact
distance to the surface where the cache has it, and the cache itself for hard pins."""
import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import springsim
from springsim.animation import Animation, interpolated_points
from springsim.errors import SceneError
from springsim.export.mdd import encode as encode_mdd
from springsim.export.pc2 import encode as encode_pc2
from springsim.scenefile import load_scene
from springsim.terrains.deforming_mesh import LAST_TIME
from springsim.terrains.deforming_surface import surface_at

FPS = 24.0


def write_pc2(path, frames, fps=FPS):
    with open(path, "wb") as file:
        encode_pc2(file, np.asarray(frames), np.arange(len(frames)) / fps, fps, 0)
    return path


def write_obj(path, vertices, triangles):
    path.write_text("".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in vertices)
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in triangles))
    return path


def plate(n=9, size=3.0):
    """A square of n x n vertices in the y = 0 plane, its normals up."""
    xs = np.linspace(-size / 2, size / 2, n)
    vertices = np.array([[x, 0.0, z] for z in xs for x in xs])
    triangles = []
    for i in range(n - 1):
        for j in range(n - 1):
            a = i * n + j
            triangles += [(a, a + n, a + 1), (a + 1, a + n, a + n + 1)]
    return vertices, np.array(triangles)


def platform_path(times):
    """Still for 0.25 s, then up at 0.6 m/s and sideways at 0.5 m/s."""
    moving = np.clip(times - 0.25, 0.0, None)
    return np.stack([0.5 * moving, 0.6 * moving, 0.0 * moving], axis=1)


CUBE = """
dt = {dt}
integrator = "{integrator}"
[[bodies]]
type = "cube"
particles_per_edge = 4
edge_length = 0.5
position = [0.0, 0.4, 0.0]
"""


@pytest.fixture(scope="module")
def platform_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("platform")
    vertices, triangles = plate()
    write_obj(folder / "plate.obj", vertices, triangles)
    times = np.arange(25) / FPS
    moved = platform_path(times)
    write_pc2(folder / "plate.pc2", vertices[None] + moved[:, None])
    # the cache's float32 numbers, keyframed exactly, so that the two describe the same motion
    keys = np.asarray(moved, np.float32).astype(float)
    return folder, times, keys


@pytest.mark.parametrize("integrator, dt", [("symplectic_euler", 1e-3), ("rk4", 2e-3),
                                            ("implicit_euler", 1 / 60)])
def test_a_cached_rigid_motion_moves_the_cube_as_the_keyframed_motion(platform_files, integrator,
                                                                      dt):
    """A plate that a point cache lifts and slides is the same terrain as the plate moved by
    linear keyframes through the same positions: the cube riding on it (static friction relative
    to the moving surface) ends where it ends on the keyframed one."""
    folder, times, keys = platform_files
    head = CUBE.format(dt=dt, integrator=integrator)
    deforming = head + '[[terrains]]\ntype = "mesh"\nfile = "plate.obj"\n' \
                       '[terrains.animation]\nfile = "plate.pc2"\n'
    frames = ", ".join(f"{{time = {t:.17g}, position = [{x:.17g}, {y:.17g}, {z:.17g}]}}"
                       for t, (x, y, z) in zip(times, keys))
    rigid = head + f'[[terrains]]\ntype = "mesh"\nfile = "plate.obj"\n' \
                   f'[terrains.motion]\nkeyframes = [{frames}]\n'
    ends = []
    for name, text in (("deforming", deforming), ("rigid", rigid)):
        (folder / f"{name}.toml").write_text(text)
        simulation = springsim.Simulation(load_scene(str(folder / f"{name}.toml")))
        start = simulation.state.positions.copy()
        simulation.advance(1.0)
        ends.append(simulation.state.positions.copy())
    assert np.abs(ends[0] - ends[1]).max() < 1e-6
    # it rode up with the plate (0.45 m by 1 s) and along it (0.375 m), friction (0.3 g)
    # bringing it up to the plate's sideways speed within 0.2 s of the plate's start
    assert ends[0][:, 1].min() == pytest.approx(0.45, abs=0.02)
    assert 0.3 < (ends[0] - start)[:, 0].mean() < 0.375


# steps after which the last step's start plus h rounds differently from steps x h (24 x 1/60,
# 176 x 2e-3), where a step's end taken as its start plus h would need a refit of its own
@pytest.mark.parametrize("integrator, dt, steps", [("rk4", 2e-3, 176),
                                                   ("implicit_euler", 1 / 60, 24)])
def test_one_refit_serves_a_steps_end_and_the_next_start_and_a_resumed_run_is_bit_identical(
        platform_files, integrator, dt, steps):
    """The surface refitted for a step's end is at the next step's start time to the last bit
    (world.step_end), so the next step does not refit it again; and a run resumed from a copy of
    its state mid-motion, with a fresh model that refits there, ends where the run that never
    stopped ends, bit for bit."""
    folder, _, _ = platform_files
    text = CUBE.format(dt=dt, integrator=integrator) + '[[terrains]]\ntype = "mesh"\n' \
        'file = "plate.obj"\n[terrains.animation]\nfile = "plate.pc2"\n'
    (folder / f"resume-{integrator}.toml").write_text(text)

    def simulation():
        return springsim.Simulation(load_scene(str(folder / f"resume-{integrator}.toml")))

    first = simulation()
    first.step(steps)   # the plate moving since 0.25 s, the cube riding it
    assert (steps - 1) * dt + dt != steps * dt
    arrays = first.model.arrays
    block = int(arrays.terrain_deforming[0])
    assert arrays.terrain_data[block + LAST_TIME] == first.state.time
    resumed = simulation()
    resumed.state = first.state.copy()
    for run in (first, resumed):
        run.advance(0.2)
    assert np.array_equal(resumed.state.positions, first.state.positions)
    assert np.array_equal(resumed.state.velocities, first.state.velocities)


def sphere_files(folder, radii):
    """An icosphere whose radius takes ``radii`` at the cache's samples."""
    ball = trimesh.creation.icosphere(subdivisions=3)
    write_obj(folder / "ball.obj", ball.vertices, ball.faces)
    write_pc2(folder / "ball.pc2", [radius * ball.vertices for radius in radii])
    return ball


@pytest.mark.parametrize("integrator, dt, every", [("implicit_euler", 1 / 60, 1),
                                                   ("symplectic_euler", 1e-4, 100)])
def test_an_inflating_ball_lifts_the_cloth_and_no_particle_enters_it(tmp_path, integrator, dt,
                                                                     every):
    """A ball under a cloth grows from 0.3 m to 0.5 m in 0.5 s: the cloth rides up on it, and
    at every step checked no particle is inside the surface where the cache has it then (the
    exact distance to the interpolated triangles, libigl)."""
    import igl

    radii = np.interp(np.arange(25) / FPS, [0.3, 0.8], [0.3, 0.5])
    sphere_files(tmp_path, radii)
    (tmp_path / "inflate.toml").write_text(f"""
dt = {dt}
integrator = "{integrator}"
[[bodies]]
type = "cloth"
particles_per_edge = 15
width = 1.2
height = 1.2
position = [0.0, 0.36, 0.0]
pinned = "none"
[[terrains]]
type = "mesh"
file = "ball.obj"
friction = 0.5
[terrains.animation]
file = "ball.pc2"
""")
    scene = load_scene(str(tmp_path / "inflate.toml"))
    surface = scene.terrains[0].deforming_surface()
    simulation = springsim.Simulation(scene)
    deepest = np.inf
    while simulation.time < 1.2 - 1e-9:
        simulation.step(every)
        distance = igl.signed_distance(simulation.state.positions,
                                       surface_at(surface, simulation.time), surface.triangles,
                                       sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0]
        deepest = min(deepest, distance.min())
    top = simulation.state.positions[:, 1].max()
    assert deepest > -2e-3, f"a particle was {-deepest:.4f} m inside the ball"
    assert top == pytest.approx(0.5, abs=0.02)   # it rests on the grown ball


@pytest.mark.parametrize("integrator, dt", [("symplectic_euler", 1e-3), ("rk4", 1e-3),
                                          ("implicit_euler", 1 / 60)])
def test_a_ball_larger_than_the_lookup_reach_falls_freely_and_lands_on_the_surface(
        tmp_path, integrator, dt):
    """A ball of radius 0.2 m (over twice the plate's band-made reach) dropped from 1.5 m above
    a slowly rising plate: while far from the plate it falls as it does with no terrain, past
    4 epsilon / h = 2.4 m/s under implicit_euler (a lookup beyond reach answered ``reach``,
    which the ball's radius turned into contact, so it was pushed up at every step, and which
    backward Euler's look-ahead read as a floor that held it to 2.4 m/s), then lands and rests
    on the plate, its centre a radius above it within the contact band, rising with it."""
    from springsim.bodies.balls import Ball, Balls
    from springsim.scene import Scene
    from springsim.terrains import MeshTerrain

    vertices, triangles = plate()
    write_obj(tmp_path / "plate.obj", vertices, triangles)
    frames = vertices[None] + (np.arange(3) * 0.01)[:, None, None] * np.array([0.0, 1.0, 0.0])
    write_pc2(tmp_path / "plate.pc2", frames, fps=1.0)   # up 1 cm/s for 2 s
    ball = Ball(position=(0.1, 1.5, 0.07), velocity=(0.0, 0.0, 0.0), radius=0.2, mass=1.0)
    scene = Scene(bodies=[Balls(balls=[ball])], drag=0.0, terrains=[MeshTerrain(
        file=str(tmp_path / "plate.obj"), restitution=0.0, friction=0.5,
        animation=Animation(str(tmp_path / "plate.pc2"), fps=1.0))])
    simulation = springsim.Simulation(scene, integrator=integrator, dt=dt)
    simulation.advance(0.3)
    alone = springsim.Simulation(Scene(bodies=scene.bodies, drag=0.0), integrator=integrator,
                                 dt=dt)
    alone.advance(0.3)
    np.testing.assert_allclose(simulation.state.positions, alone.state.positions, atol=1e-12)
    assert alone.state.positions[0, 1] == pytest.approx(1.5 - 9.81 * 0.3 ** 2 / 2, abs=0.03)
    simulation.advance(1.6)   # to 1.9 s, the plate still rising
    gap = simulation.state.positions[0, 1] - 0.2 - 0.01 * simulation.time
    assert -1e-3 < gap < scene.terrains[0].epsilon + 1e-3   # at rest in the contact band
    assert simulation.state.velocities[0, 1] == pytest.approx(0.01, abs=5e-3)


@pytest.mark.parametrize("speed, height", [(8.0, 0.2), (16.0, 0.12), (16.0, 0.33)])
def test_a_cloth_thrown_fast_at_a_deforming_plate_does_not_pass_through(tmp_path, speed, height):
    """A 10 x 10 cloth thrown down at 8 or 16 m/s (13 and 27 cm a step at 1/60 s, the plate's
    reach 4 cm) onto a slowly rising plate under implicit_euler: at no step is a particle below
    the plate. Beyond reach the lookup answers infinity, so the solve's look-ahead asks along
    the step's path (implicit/terrain_lookups.swept_lookup); without it the cloth passed through
    from these heights."""
    from springsim.bodies.cloth import Cloth
    from springsim.scene import Scene
    from springsim.terrains import MeshTerrain

    vertices, triangles = plate()
    write_obj(tmp_path / "plate.obj", vertices, triangles)
    frames = vertices[None] + (np.arange(3) * 0.01)[:, None, None] * np.array([0.0, 1.0, 0.0])
    write_pc2(tmp_path / "plate.pc2", frames, fps=1.0)   # up 1 cm/s for 2 s
    cloth = Cloth(particles_per_edge=10, width=1.0, height=1.0, position=(0.13, height, 0.07),
                  pinned="none", velocity=(0.0, -speed, 0.0))
    scene = Scene(bodies=[cloth], terrains=[MeshTerrain(
        file=str(tmp_path / "plate.obj"), animation=Animation(str(tmp_path / "plate.pc2"),
                                                              fps=1.0))])
    simulation = springsim.Simulation(scene, integrator="implicit_euler", dt=1 / 60)
    lowest = np.inf
    for _ in range(60):
        simulation.step(1)
        lowest = min(lowest, float((simulation.positions[:, 1] - 0.01 * simulation.time).min()))
    assert lowest > -1e-3, f"a particle was {-lowest:.3f} m below the plate"


def test_hard_pins_follow_their_cached_points_to_round_off(tmp_path):
    """Two corners of a cloth pinned to a cache of the cloth's particles that carries it
    sideways and turns it: at every step each pinned particle is where the cache, linear between
    samples, has it then."""
    scene_text = """
dt = {dt}
integrator = "{integrator}"
[[bodies]]
type = "cloth"
particles_per_edge = 6
width = 1.0
height = 1.0
position = [0.0, 1.0, 0.0]
pinned = "none"
[[bodies.pins]]
particles = [0, 5]
[bodies.pins.animation]
file = "cloth.pc2"
start = 0.1
"""
    start = springsim.Simulation(springsim.load_scene(
        _scene_file(tmp_path, scene_text, "symplectic_euler", 1e-3, cache=False))).state.positions
    angles = np.radians(np.linspace(0.0, 40.0, 13))
    frames = []
    for k, angle in enumerate(angles):
        c, s = np.cos(angle), np.sin(angle)
        turn = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
        frames.append(start @ turn.T + [0.1 * k, 0.0, 0.0])
    write_pc2(tmp_path / "cloth.pc2", frames)
    cache = Animation(str(tmp_path / "cloth.pc2"), start=0.1).cache()
    for integrator, dt in (("symplectic_euler", 1e-4), ("rk4", 1e-4), ("implicit_euler", 1 / 60)):
        simulation = springsim.Simulation(springsim.load_scene(
            _scene_file(tmp_path, scene_text, integrator, dt)))
        worst = 0.0
        for _ in range(40):
            simulation.step(1 if integrator == "implicit_euler" else 100)
            expected, _ = interpolated_points(cache, simulation.time)
            worst = max(worst, np.abs(simulation.state.positions[[0, 5]] - expected[[0, 5]]).max())
        assert worst < 1e-12, integrator


@pytest.mark.parametrize("integrator, dt, every", [
    ("symplectic_euler", 1e-4, 50), ("rk4", 1e-4, 50), ("implicit_euler", 1 / 60, 1)])
def test_pins_following_a_deforming_terrain_ride_riveted_to_its_triangles(tmp_path, integrator,
                                                                          dt, every):
    """A plate that a cache turns and lifts rigidly, and a cloth above it whose two corners
    follow it (0.3 m off the surface): riveted to their nearest triangles, they move as the
    plate's own points would, rigidly at every sample (offset, side and all), and linearly
    between samples as the surface does."""
    vertices, triangles = plate()
    write_obj(tmp_path / "plate.obj", vertices, triangles)
    times = np.arange(25) / FPS
    axis = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
    turns = [Rotation.from_rotvec(1.2 * t * axis).as_matrix() for t in times]
    shifts = np.stack([0.4 * times, 0.5 * times, 0.0 * times], axis=1)
    frames = np.asarray([vertices @ turn.T + shift for turn, shift in zip(turns, shifts)],
                        np.float32)
    write_pc2(tmp_path / "plate.pc2", frames)
    (tmp_path / "rivets.toml").write_text(f"""
dt = {dt}
integrator = "{integrator}"
[[terrains]]
type = "mesh"
file = "plate.obj"
[terrains.animation]
file = "plate.pc2"
[[bodies]]
type = "cloth"
particles_per_edge = 5
width = 1.0
height = 1.0
position = [0.2, 0.3, 0.1]
pinned = "none"
[[bodies.pins]]
particles = [0, 4]
follow = "terrains.0"
""")
    simulation = springsim.Simulation(load_scene(str(tmp_path / "rivets.toml")))
    start = simulation.state.positions[[0, 4]].copy()
    places = np.array([start @ turn.T + shift for turn, shift in zip(turns, shifts)])
    worst = 0.0
    while simulation.time < 1.1:
        simulation.step(every)
        expected = np.array([[np.interp(simulation.time, times, places[:, j, c])
                              for c in range(3)] for j in range(2)])
        worst = max(worst, np.abs(simulation.state.positions[[0, 4]] - expected).max())
    assert worst < 1e-5                                   # the cache's float32 corners
    assert np.linalg.norm(places[-1] - start, axis=1).min() > 0.5   # they were carried


def _scene_file(folder, text, integrator, dt, cache=True):
    body = text.format(integrator=integrator, dt=dt)
    if not cache:
        body = body.split("[[bodies.pins]]")[0]
    path = folder / f"pins-{integrator}-{cache}.toml"
    path.write_text(body)
    return str(path)


def test_a_mesh_cloth_pin_follows_its_file_vertex_as_placed(tmp_path):
    """A mesh cloth's cache lists its file's vertices in the file's frame: a pinned particle
    goes where its vertex goes after the cloth's scale, rotation and position."""
    vertices, triangles = plate(n=5, size=1.0)
    write_obj(tmp_path / "sheet.obj", vertices, triangles)
    frames = [vertices + [0.0, 0.2 * k, 0.0] for k in range(5)]
    write_pc2(tmp_path / "sheet.pc2", frames)
    (tmp_path / "sheet.toml").write_text("""
dt = 0.008333333333333333
integrator = "implicit_euler"
[[bodies]]
type = "cloth"
file = "sheet.obj"
scale = 2.0
rotation_degrees = 90.0
rotation_axis = [1.0, 0.0, 0.0]
position = [0.0, 2.0, 0.0]
[[bodies.pins]]
particles = [4]
[bodies.pins.animation]
file = "sheet.pc2"
""")
    simulation = springsim.Simulation(load_scene(str(tmp_path / "sheet.toml")))
    simulation.advance(3 / FPS)
    # the file's vertex 4, (0.5, 0.6, -0.5) at 3 frames, scaled by 2, turned 90 degrees about x
    x, y, z = 2 * np.array([0.5, 0.6, -0.5])
    assert np.allclose(simulation.state.positions[4], [x, -z + 2.0, y], atol=1e-6)


def bad_scene(tmp_path, terrain_extra="", pin_extra="", body="cloth"):
    vertices, triangles = plate(n=3, size=1.0)
    write_obj(tmp_path / "plate.obj", vertices, triangles)
    box = trimesh.creation.box()
    write_obj(tmp_path / "box.obj", box.vertices, box.faces)
    write_pc2(tmp_path / "nine.pc2", [vertices, vertices])
    write_pc2(tmp_path / "four.pc2", [vertices[:4], vertices[:4]])
    text = f"""
dt = 0.001
[[bodies]]
type = "{body}"
position = [0.0, 1.0, 0.0]
{"file = 'box.obj'" if body == "mesh" else ""}
{pin_extra}
[[terrains]]
type = "mesh"
file = "plate.obj"
{terrain_extra}
"""
    (tmp_path / "bad.toml").write_text(text)
    return str(tmp_path / "bad.toml")


@pytest.mark.parametrize("terrain, pin, body, key, says", [
    ('[terrains.animation]\nfile = "four.pc2"', "", "cloth", "terrains.0.animation.file",
     "moves 4 points, but the mesh file"),
    ('[terrains.animation]\nfile = "missing.pc2"', "", "cloth", "terrains.0.animation.file",
     "no such file"),
    ('[terrains.animation]\nfile = "plate.obj"', "", "cloth", "terrains.0.animation.file",
     "an OBJ animation is a numbered sequence"),
    ('[terrains.animation]\nfile = "walk_####.obj"', "", "cloth", "terrains.0.animation.file",
     "no file walk_<number>.obj found"),
    ('[terrains.animation]\nfile = "step_0001.obj"', "", "cloth", "terrains.0.animation.file",
     "has 8 vertices, but the sequence's first file step_0001.obj has 9"),
    ('[terrains.animation]\nfile = "plate.txt"', "", "cloth", "terrains.0.animation.file",
     "must be a point cache"),
    ('[terrains.animation]\nfile = "truncated.pc2"', "", "cloth", "terrains.0.animation.file",
     "is truncated"),
    ('[terrains.animation]\nfile = "nine.pc2"\nfps = 0.0', "", "cloth",
     "terrains.0.animation.fps", "must be > 0"),
    ('[terrains.motion]\nvelocity = [1.0, 0.0, 0.0]\n[terrains.animation]\nfile = "nine.pc2"',
     "", "cloth", "terrains.0.animation", "not both"),
    ("", '[[bodies.pins]]\nparticles = [0]\n[bodies.pins.animation]\nfile = "nine.pc2"',
     "cloth", "bodies.0.pins.0.animation.file",
     "moves 9 points, but the body has 625 particles"),
    ("", '[[bodies.pins]]\nparticles = [0]\nfollow = "terrains.0"\n'
         '[bodies.pins.animation]\nfile = "nine.pc2"', "cloth", "bodies.0.pins.0.animation",
     "one of motion, follow and animation"),
    ("", '[[bodies.pins]]\nparticles = [0]\n[bodies.pins.animation]\nfile = "nine.pc2"',
     "mesh", "bodies.0.pins.0.animation",
     "a mesh body's particles are not its file's vertices"),
])
def test_bad_caches_are_refused_in_one_line(tmp_path, terrain, pin, body, key, says):
    path = bad_scene(tmp_path, terrain, pin, body)
    (tmp_path / "truncated.pc2").write_bytes((tmp_path / "nine.pc2").read_bytes()[:-5])
    vertices, triangles = plate(n=3, size=1.0)
    write_obj(tmp_path / "step_0001.obj", vertices, triangles)
    write_obj(tmp_path / "step_0002.obj", vertices[:8], triangles[:4])
    with pytest.raises(SceneError) as caught:
        springsim.Simulation(load_scene(path))
    assert caught.value.key == key and says in str(caught.value)
    assert "\n" not in str(caught.value)


def test_mdd_and_pc2_of_the_same_samples_read_the_same(tmp_path):
    vertices, _ = plate(n=3)
    frames = np.array([vertices + [0.0, 0.1 * k, 0.0] for k in range(4)])
    write_pc2(tmp_path / "a.pc2", frames, fps=30.0)
    with open(tmp_path / "a.mdd", "wb") as file:
        encode_mdd(file, frames, np.arange(4) / 30.0 + 2.0, 30.0)
    pc2 = Animation(str(tmp_path / "a.pc2"), fps=30.0, start=0.5).cache()
    mdd = Animation(str(tmp_path / "a.mdd"), start=0.5).cache()
    assert np.allclose(pc2.times, mdd.times, atol=1e-6) and np.array_equal(pc2.points, mdd.points)
    assert pc2.times[0] == 0.5 and pc2.times[-1] == pytest.approx(0.6)


def test_an_obj_sequence_is_the_point_cache_of_the_same_vertices(platform_files, tmp_path):
    """A numbered OBJ sequence holding the PC2's samples, exported every other frame (numbers
    1, 3, 5, ... at 48 frames/s: the PC2's 24 samples a second), moves the plate as the PC2
    does: the cube riding it ends where it ends on the PC2's plate, to the last bit, whether
    the sequence is named by its pattern or by one of its files."""
    folder, _, _ = platform_files
    samples = Animation(str(folder / "plate.pc2"), fps=FPS).cache()
    _, triangles = plate()
    for k, points in enumerate(samples.points):
        write_obj(tmp_path / f"plate.{2 * k + 1:04d}.obj", points, triangles)
    write_obj(tmp_path / "plate.obj", samples.points[0], triangles)
    (tmp_path / "plate.pc2").write_bytes((folder / "plate.pc2").read_bytes())
    head = CUBE.format(dt=1e-3, integrator="symplectic_euler")
    ends = []
    for animation in ('file = "plate.pc2"', 'file = "plate.####.obj"\nfps = 48.0',
                      'file = "plate.0007.obj"\nfps = 48.0'):
        (tmp_path / "scene.toml").write_text(
            head + f'[[terrains]]\ntype = "mesh"\nfile = "plate.obj"\n'
                   f'[terrains.animation]\n{animation}\n')
        simulation = springsim.Simulation(load_scene(str(tmp_path / "scene.toml")))
        simulation.advance(0.6)
        ends.append(simulation.state.positions.copy())
    assert np.array_equal(ends[0], ends[1]) and np.array_equal(ends[0], ends[2])
    assert ends[0][:, 1].min() > 0.15   # the plate lifted it (0.21 m by 0.6 s)
    sequence = Animation(str(tmp_path / "plate.####.obj"), fps=48.0).cache()
    assert np.array_equal(sequence.times, samples.times)


def test_usd_export_moves_the_terrains_with_the_take(platform_files, tmp_path):
    """A take exported to USD has each moving terrain's points at every frame where its motion
    (a sphere) or its cache (the plate, linear between samples) has them at that frame's time."""
    from pxr import Usd, UsdGeom

    from springsim.cli import main

    folder, _, _ = platform_files
    (folder / "both.toml").write_text(CUBE.format(dt=1 / 60, integrator="implicit_euler") + """
[[terrains]]
type = "mesh"
file = "plate.obj"
[terrains.animation]
file = "plate.pc2"
[[terrains]]
type = "sphere"
center = [3.0, 0.0, 0.0]
radius = 0.5
[terrains.motion]
velocity = [0.0, 1.0, 0.0]
""")
    take, usd = tmp_path / "both.npz", tmp_path / "both.usda"
    assert main(["run", str(folder / "both.toml"), "--quiet", "--duration", "0.5", "--fps", "20",
                 "--out", str(take)]) == 0
    assert main(["export", "--quiet", str(take), str(usd)]) == 0
    stage = Usd.Stage.Open(str(usd))
    plate_points = UsdGeom.Mesh(stage.GetPrimAtPath("/take/terrains/terrain_0_meshterrain"))
    sphere = UsdGeom.Mesh(stage.GetPrimAtPath("/take/terrains/terrain_1_sphere"))
    cache = Animation(str(folder / "plate.pc2")).cache()
    for frame, t in enumerate(np.arange(11) / 20):
        points = np.asarray(plate_points.GetPointsAttr().Get(frame + 1), float)
        np.testing.assert_allclose(points, interpolated_points(cache, t)[0], atol=1e-6)
        centre = np.asarray(sphere.GetPointsAttr().Get(frame + 1), float).mean(axis=0)
        np.testing.assert_allclose(centre, [3.0, t, 0.0], atol=1e-5)


def test_the_lookup_finds_the_exact_closest_point_on_the_walking_figure():
    """The cape's figure (a fast-moving point cache: reach 9.5 cm, dozens of triangles per cell)
    at three times: every point within reach gets libigl's exact signed distance to the
    interpolated surface, whatever triangles the bounding spheres let the lookup skip."""
    import igl

    from springsim.terrains.deforming_mesh import REACH, deform, deformed_distance

    scene = springsim.load_scene("cape")
    figure = scene.terrains[1]
    surface = figure.deforming_surface()
    model = springsim.Simulation(scene).model.arrays
    row, data = model.terrain_parameters[1], model.terrain_data
    block = int(model.terrain_deforming[1])
    reach = data[block + REACH]
    rng = np.random.default_rng(1)
    for t in (0.3, 1.1, 2.45):
        deform(data, block, t)
        vertices = surface_at(surface, t)
        points = vertices[rng.integers(len(vertices), size=400)] \
            + rng.uniform(-reach, reach, (400, 3))
        exact = igl.signed_distance(points, vertices, surface.triangles,
                                    sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0]
        found = np.array([deformed_distance(row, data, *p)[0] for p in points])
        near = np.abs(exact) < reach
        assert near.sum() > 300
        np.testing.assert_allclose(found[near], exact[near], rtol=0, atol=1e-12)
