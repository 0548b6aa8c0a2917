"""Mesh terrains against the analytic ones: an icosphere behaves as the sphere within a few cm, a
ramp of two triangles as the tilted plane to the millimetre (friction g (sin - mu cos) included,
in the stages of explicit methods and as constraints of implicit_euler), and a jelly torus comes
to rest on a mesh floor."""
import math

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

import springsim
from springsim.bodies.cube import Cube
from springsim.bodies.mesh import MeshBody
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.terrains import MeshTerrain, Sphere, pack_terrains, terrain_distance, tilted_plane

G = 9.8
SLOPE_NORMAL = np.array([1.0, 1.0, 0.0]) / math.sqrt(2.0)
DOWN_SLOPE = np.array([1.0, -1.0, 0.0]) / math.sqrt(2.0)


def square(path, normal, half: float, center=(0.0, 0.0, 0.0)):
    """An open square of two triangles, facing ``normal``."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.cross(n, [0.0, 0.0, 1.0] if abs(n[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(n, u)
    corners = [np.asarray(center) + half * (a * u + b * w)
               for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    if np.cross(corners[1] - corners[0], corners[2] - corners[0]) @ n < 0:
        faces = faces[:, ::-1]
    trimesh.Trimesh(np.array(corners), faces, process=False).export(path)
    return str(path)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("terrain_meshes")


def test_the_kernel_and_the_numpy_twin_agree(folder):
    path = folder / "ico.stl"
    trimesh.creation.icosphere(subdivisions=3, radius=2.0).export(path)
    terrain = MeshTerrain(file=str(path), position=(0.5, -1.0, 0.2))
    terrain.validate("terrains.0")
    rng = np.random.default_rng(3)
    x = rng.uniform(-4.0, 4.0, (300, 3))
    packed = pack_terrains([terrain])
    expected = terrain.signed_distance(x)
    for i in range(len(x)):
        phi, nx, ny, nz = terrain_distance(packed["terrain_kind"][0],
                                           packed["terrain_parameters"][0],
                                           packed["terrain_data"], *x[i], 0.0)
        assert phi == pytest.approx(expected[i], abs=1e-12)
        assert math.hypot(nx, ny, nz) == pytest.approx(1.0, abs=1e-12)
    # and near the surface it is the sphere's distance, to the faceting and the grid
    r = np.linalg.norm(x - [0.5, -1.0, 0.2], axis=1)
    near = np.abs(r - 2.0) < 0.3
    np.testing.assert_allclose(expected[near], r[near] - 2.0, atol=0.02)


def test_an_icosphere_gives_the_spheres_outcome(folder):
    """The default cube dropped on the sphere of radius 3 and on an icosphere mesh of it: the
    centre of mass agrees within a few cm through the landing and the slide off."""
    path = folder / "sphere.obj"
    trimesh.creation.icosphere(subdivisions=4, radius=3.0).export(path)
    sphere = Sphere()
    mesh = MeshTerrain(file=str(path), position=sphere.center)
    paths = []
    for terrain in (sphere, mesh):
        simulation = springsim.Simulation(Scene(bodies=[Cube()], terrains=[terrain]))
        centres = []
        for _ in range(4):
            simulation.advance(0.5)
            centres.append(simulation.model.mass @ simulation.positions / simulation.model.mass.sum())
        paths.append(np.array(centres))
    assert np.max(np.linalg.norm(paths[1] - paths[0], axis=1)) < 0.05


def cube_on_the_slope(terrain, integrator, dt):
    """The stiff 5 x 5 x 5 cube of test_terrains.py set on the 45-degree slope, corner down."""
    face_down = Rotation.from_rotvec(np.radians(-45.0) * np.array([0.0, 0.0, 1.0]))
    rotation = (Rotation.from_rotvec(np.radians(45.0) * SLOPE_NORMAL) * face_down).as_rotvec()
    springs = SpringParameters(20000.0, 120.0)
    cube = Cube(particles_per_edge=5, edge_length=2.0, position=tuple(1.001 * SLOPE_NORMAL),
                rotation_degrees=float(np.degrees(np.linalg.norm(rotation))),
                rotation_axis=tuple(rotation), structural=springs, shear=springs, bend=springs)
    return springsim.Simulation(Scene(bodies=[cube], terrains=[terrain], integrator=integrator,
                                      dt=dt, gravity=(0.0, -G, 0.0)))


@pytest.mark.parametrize("integrator, dt", [("rk4", 1e-3), ("explicit_euler", 1e-4),
                                            ("implicit_euler", 5e-3)])
def test_a_ramp_of_two_triangles_is_the_tilted_plane(folder, integrator, dt):
    friction = 0.3
    ramp = MeshTerrain(file=square(folder / "ramp.obj", SLOPE_NORMAL, 12.0,
                                   center=6.0 * DOWN_SLOPE), friction=friction)
    trajectories = []
    for terrain in (tilted_plane(friction=friction), ramp):
        simulation = cube_on_the_slope(terrain, integrator, dt)
        times, centres = [], []
        for _ in range(20):
            simulation.advance(0.1)
            times.append(simulation.time)
            centres.append(simulation.model.mass @ simulation.positions
                           / simulation.model.mass.sum())
        assert terrain.signed_distance(simulation.positions).min() >= -1e-9
        trajectories.append(np.array(centres))
    plane, mesh = trajectories
    assert np.max(np.linalg.norm(mesh - plane, axis=1)) < 1e-3
    # sliding down the mesh ramp at g (sin 45 - mu cos 45), after the springs settle
    s = mesh[5:] @ DOWN_SLOPE
    measured = 2 * np.polyfit(np.array(times[5:]), s, 2)[0]
    expected = G * (math.sin(math.pi / 4) - friction * math.cos(math.pi / 4))
    assert measured == pytest.approx(expected, rel=2e-3)


def test_a_jelly_torus_comes_to_rest_on_a_mesh_floor(folder):
    torus_path = folder / "torus.obj"
    trimesh.creation.torus(major_radius=1.0, minor_radius=0.4).export(torus_path)
    floor = MeshTerrain(file=square(folder / "floor.obj", (0.0, 1.0, 0.0), 5.0), restitution=0.3)
    spacing = 0.2
    torus = MeshBody(file=str(torus_path), spacing=spacing, rotation_degrees=90.0,
                     rotation_axis=(1.0, 0.0, 0.0), position=(0.0, 0.8, 0.0))
    simulation = springsim.Simulation(Scene(bodies=[torus], terrains=[floor]))
    simulation.advance(3.0)
    assert simulation.energy()["kinetic"] < 1e-3
    offsets = simulation.model.arrays.terrain_offset
    assert floor.signed_distance(simulation.positions, offsets).min() >= -1e-9
    assert floor.signed_distance(simulation.positions, offsets).min() < floor.epsilon   # on it
    # no vertex of the surface below the floor, and the body not floating above it
    lowest = floor.signed_distance(simulation.surfaces()[0].vertices).min()
    assert -1e-3 <= lowest < spacing / 2


CACHED_CALL = """
import numpy as np
import springsim
from springsim.collision.response.terrain import apply_contact_forces
model = springsim.Simulation(springsim.load_scene("jelly-plane")).model
x = model.initial_positions.copy()
a = np.zeros_like(x)
apply_contact_forces(model.arrays, x, np.zeros_like(x), 1e-3, a)
stats = apply_contact_forces.stats
print(sum(stats.cache_hits.values()), sum(stats.cache_misses.values()))
"""


def test_kernels_calling_the_generated_dispatcher_load_from_the_cache():
    """The dispatcher is generated at import (terrains/dispatch.py) and has no cache of its own;
    the contact kernel that calls it is cached with it inside, so a second process compiles
    nothing (the first fills the cache if no test has yet)."""
    import subprocess
    import sys

    for _ in range(2):
        output = subprocess.run([sys.executable, "-c", CACHED_CALL], check=True,
                                capture_output=True, text=True).stdout
    hits, misses = output.split()[-2:]
    assert (hits, misses) == ("1", "0")


def test_contact_looked_up_a_block_ahead_is_the_planes(folder):
    """A mesh terrain's distances are looked up a block of particles ahead of their contact
    (collision/response/terrain.py): on a flat mesh floor every particle, in every block (1000
    particles: the last block partial), gets the plane's reaction and friction to round-off, pinned
    ones none, with a second terrain after it in the list."""
    from springsim.collision.response.terrain import apply_contact_forces
    from springsim.model import build_model
    from springsim.terrains import Plane

    floor = MeshTerrain(file=square(folder / "flat.obj", (0.0, 1.0, 0.0), 10.0,
                                    center=(0.0, -1.0, 0.0)))
    far = Sphere(center=(0.0, 50.0, 0.0))   # touched by no particle
    rng = np.random.default_rng(5)
    x = np.column_stack([rng.uniform(-8, 8, 1000), -1.0 + rng.uniform(-0.02, 0.03, 1000),
                         rng.uniform(-8, 8, 1000)])
    v = rng.normal(0.0, 0.01, (1000, 3))   # some stick, some slide
    a = rng.normal(0.0, 10.0, (1000, 3)) + (0.0, -G, 0.0)
    results = []
    for terrain in (Plane(point=(0.0, -1.0, 0.0)), floor):
        model = build_model(Scene(bodies=[Cube(particles_per_edge=2)], terrains=[terrain, far]))
        inv_mass = np.ones(1000)
        inv_mass[::7] = 0.0
        arrays = model.arrays._replace(inv_mass=inv_mass, radius=np.zeros(1000),
                                       terrain_offset=np.zeros(1000))
        out = a.copy()
        apply_contact_forces(arrays, x, v, 1e-3, out)
        results.append(out)
    touched = np.any(results[0] != a, axis=1)
    assert touched.sum() > 300 and not touched[::7].any()
    np.testing.assert_allclose(results[1], results[0], rtol=0, atol=1e-9 * np.abs(a).max())


def test_the_still_dispatcher_gives_every_still_kind_the_same_bits(folder):
    """The contact loops look still terrains up with still_terrain_distance, which leaves out
    the kinds that are never still (the deforming mesh: with it, LLVM no longer keeps the
    plane's lookup fast): for every other kind it answers exactly as terrain_distance."""
    from springsim.terrains import KINDS, Bowl, Plane, still_terrain_distance

    path = folder / "ico_still.stl"
    trimesh.creation.icosphere(subdivisions=2, radius=1.5).export(path)
    terrains = [Plane(), Sphere(), Bowl(), MeshTerrain(file=str(path), position=(0.2, 0.1, 0.0))]
    for number, terrain in enumerate(terrains):
        terrain.validate(f"terrains.{number}")
    packed = pack_terrains(terrains)
    still_kinds = {number for number, cls in enumerate(KINDS)
                   if not getattr(cls, "never_still", False)}
    assert set(packed["terrain_kind"].tolist()) == still_kinds   # every still kind is tried
    x = np.random.default_rng(5).uniform(-3.0, 3.0, (200, 3))
    for t in range(len(terrains)):
        for point in x:
            arguments = (packed["terrain_kind"][t], packed["terrain_parameters"][t],
                         packed["terrain_data"], *point, 0.01)
            assert still_terrain_distance(*arguments) == terrain_distance(*arguments)
