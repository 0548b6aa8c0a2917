"""Defaults a new user met (issue 56, item 7): a cloth from a file weighs what a fabric of its
area weighs, a mesh body made of a box rests on the floor rather than a part of a cell above it,
and the plane's default place is said where the key is documented.

Oracles: the mesh's area times the documented density, the lumped share of each vertex (a
square grid's inner vertex carries one cell), the box's own faces, and the contact band (a
resting particle lies within ``epsilon`` of the surface, never more)."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import springsim
from springsim import load_scene
from springsim.bodies.cloth import Cloth
from springsim.bodies.cloth_material import ClothMaterial
from springsim.bodies.mesh import MeshBody
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.terrains.mesh import MeshTerrain
from springsim.terrains.plane import Plane, tilted_plane

ROOT = Path(__file__).resolve().parents[1]


def napkin_obj(path: Path, size: float = 1.5, n: int = 30) -> Path:
    """An n x n vertex grid of quads, size x size m, flat in x-z (what a user models)."""
    fraction = np.linspace(-size / 2, size / 2, n).tolist()
    lines = [f"v {x!r} 0.0 {z!r}" for z in fraction for x in fraction]
    index = np.arange(n * n).reshape(n, n) + 1
    for i in range(n - 1):
        for j in range(n - 1):
            lines.append(f"f {index[i, j]} {index[i + 1, j]} {index[i + 1, j + 1]} "
                         f"{index[i, j + 1]}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_cloth_from_a_file_weighs_a_fabric_of_its_area_shared_by_vertex_area(tmp_path):
    napkin = napkin_obj(tmp_path / "napkin.obj")
    built = Cloth(file=str(napkin), pinned="none").build()
    density = ClothMaterial().density                   # 0.3 kg/m², documented
    assert built.masses.sum() == pytest.approx(density * 1.5 ** 2, rel=1e-12)   # not 900 kg
    cell = (1.5 / 29) ** 2
    grid = built.masses.reshape(30, 30)
    assert grid[1:-1, 1:-1] == pytest.approx(np.full((28, 28), density * cell), rel=1e-9)
    assert grid[0, 0] == pytest.approx(density * cell / 4, rel=1e-9)            # a corner
    assert grid[0, 5] == pytest.approx(density * cell / 2, rel=1e-9)            # an edge
    # and the default material's springs with it, not the course's 25000 N/m per spring
    assert built.spring_constants is not None


def test_a_vertex_in_no_face_of_a_fabric_weighs_as_its_vertices_do_on_average(tmp_path):
    napkin = napkin_obj(tmp_path / "napkin.obj")
    with napkin.open("a") as file:
        file.write("v 5.0 5.0 5.0\n")                 # a stray vertex, in no face
    built = Cloth(file=str(napkin), pinned="none").build()
    assert built.pinned[-1]
    assert built.masses[-1] == pytest.approx(built.masses[:-1].mean(), rel=1e-12)   # not 1 kg


def test_a_cloth_from_a_file_with_particle_mass_is_the_courses_cloth(tmp_path):
    built = Cloth(file=str(napkin_obj(tmp_path / "napkin.obj")), pinned="none",
                  particle_mass=0.01).build()
    assert np.all(built.masses == 0.01) and built.spring_constants is None


def test_the_grid_cloths_mass_is_a_number_that_gradients_take():
    from springsim.gradients.parameters import SceneValue

    assert SceneValue.named(load_scene("cloth-hang"), "bodies.0.particle_mass").value == 1.0


def test_the_grid_cloth_keeps_the_courses_kilogram_a_particle():
    built = Cloth(particles_per_edge=5).build()
    assert np.all(built.masses == 1.0) and built.spring_constants is None


def box_obj(path: Path, size=(1.0, 1.0, 1.0)) -> Path:
    """A box of ``size`` m standing on y = 0 (Blender's cube, scaled, in springsim's Y-up)."""
    sx, sy, sz = np.asarray(size) / 2
    corners = [(-sx, 0, -sz), (sx, 0, -sz), (sx, 0, sz), (-sx, 0, sz),
               (-sx, 2 * sy, -sz), (sx, 2 * sy, -sz), (sx, 2 * sy, sz), (-sx, 2 * sy, sz)]
    faces = ["1 2 3 4", "5 8 7 6", "1 5 6 2", "2 6 7 3", "3 7 8 4", "4 8 5 1"]
    path.write_text("\n".join([f"v {x} {y} {z}" for x, y, z in corners]
                              + [f"f {face}" for face in faces]) + "\n")
    return path


@pytest.mark.parametrize("particles", [300, 2000, 5000])
def test_an_auto_lattice_puts_a_cubes_faces_on_lattice_planes(tmp_path, particles):
    """Before, the spacing had three significant digits (0.0901 m for a 1 m cube at 2000
    particles: 12 cells of 1.081 m, 4 cm out at each face)."""
    lattice = MeshBody(file=str(box_obj(tmp_path / "cube.obj")), particles=particles).lattice()
    assert np.abs(lattice.positions.min(axis=0) - (-0.5, 0.0, -0.5)).max() < 1e-12
    assert np.abs(lattice.positions.max(axis=0) - (0.5, 1.0, 0.5)).max() < 1e-12
    assert abs(len(lattice.positions) / particles - 1) <= 0.5


def test_an_auto_lattice_fits_a_boxs_longest_side(tmp_path):
    lattice = MeshBody(file=str(box_obj(tmp_path / "box.obj", (0.7, 1.3, 0.5))),
                       particles=800).lattice()
    assert lattice.positions[:, 1].min() == pytest.approx(0.0, abs=1e-12)
    assert lattice.positions[:, 1].max() == pytest.approx(1.3, abs=1e-12)


def plane_obj(path: Path) -> Path:
    """Blender's default plane (2 m, one quad), facing up, as the extension exports it."""
    path.write_text("v -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nf 1 2 3 4\n")
    return path


def test_a_cube_dropped_on_a_plane_collider_rests_on_it_as_blender_exports_them(tmp_path):
    """The extension's export of Blender's 1 m cube (a jelly body, its default springs,
    thickness and friction) and plane (a mesh collider, restitution 0, resolution 64), at one
    step a frame: the drawn cube's bottom rests within the contact band (1 cm) of the plane. It
    stood 3.4 cm above it in Blender: the lattice stuck out of the cube."""
    springs = {kind: SpringParameters(ks=2000.0, kd=60.0) for kind in ("structural", "shear",
                                                                       "bend")}
    body = MeshBody(file=str(box_obj(tmp_path / "cube.obj")), particles=300, particle_mass=1.0,
                    position=(0.0, 0.2, 0.0), thickness=0.01, friction=0.4, **springs)
    floor = MeshTerrain(file=str(plane_obj(tmp_path / "plane.obj")), friction=0.4,
                        restitution=0.0, resolution=64)
    simulation = springsim.Simulation(Scene(bodies=[body], terrains=[floor],
                                            integrator="implicit_euler", dt=1 / 24))
    simulation.advance(2.0)
    bottom = simulation.surfaces()[0].vertices[:, 1].min()
    assert -1e-3 <= bottom <= floor.epsilon + 1e-3


def point_rows() -> dict:
    """{terrain type: its `terrains.N.point` row} of the generated scene-file reference."""
    spec = importlib.util.spec_from_file_location("docs_reference_hook",
                                                  ROOT / "docs" / "hooks" / "reference.py")
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    rows, kind = {}, None
    for line in hook.scene_reference_markdown().splitlines():
        if line.startswith("## [[terrains]] with `type = "):
            kind = line.split('"')[1]
        elif line.startswith("| `terrains.N.point`"):
            rows[kind] = line
    return rows


def test_the_scene_reference_says_where_a_plane_without_a_point_lies():
    assert Plane().point == (0.0, -1.0, 0.0)
    rows = point_rows()
    assert set(rows) == {"plane", "tilted_plane"}, rows
    assert "`[0.0, -1.0, 0.0]`" in rows["plane"] and "y = -1" in rows["plane"], rows["plane"]


def test_the_tilted_planes_point_row_says_the_origin_its_default():
    """Each kind's row says its own default: the tilted plane's point is the origin (its row
    said y = -1, the level plane's)."""
    assert tilted_plane().point == (0.0, 0.0, 0.0)
    row = point_rows()["tilted_plane"]
    assert "`[0.0, 0.0, 0.0]`" in row and "the origin" in row and "y = -1" not in row, row
