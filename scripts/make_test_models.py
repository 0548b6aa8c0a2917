"""Make the test models for mesh bodies: the kinds of file an artist has (closed, UV-seamed, open
scans, several shells, thin limbs, inside out, a CAD part with a hole, millimetres), all made
here (same licence as springsim) with trimesh.creation, plain NumPy and, for the monkey head,
cone and cylinder with UVs, Blender as a module (bpy).

    .venv/bin/python scripts/make_test_models.py            # the small ones, into tests/data/
    .venv/bin/python scripts/make_test_models.py --all DIR  # every model, for benchmarks/

The small ones (tests/data/) are kept in the repository; the benchmark
(benchmarks/mesh_bodies.py) makes the rest in a temporary folder. Every file is written the
same way each time (deterministic).
"""
import argparse
from pathlib import Path

import numpy as np
import trimesh

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"


def write_obj(path: Path, vertices, faces, uvs=None, uv_faces=None) -> None:
    """An OBJ as exporters write it: ``v`` lines in order, faces of any size (1-based), with
    ``vt`` corners where given."""
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in np.asarray(vertices, float)]
    if uvs is not None:
        lines += [f"vt {u:.6f} {v:.6f}" for u, v in np.asarray(uvs, float)]
        lines += ["f " + " ".join(f"{a + 1}/{b + 1}" for a, b in zip(face, uv_face))
                  for face, uv_face in zip(faces, uv_faces)]
    else:
        lines += ["f " + " ".join(str(a + 1) for a in face) for face in faces]
    path.write_text("\n".join(lines) + "\n")


def unwelded() -> tuple[np.ndarray, np.ndarray]:
    """A UV sphere as a game exporter writes it: a vertex per (position, UV) pair, so positions
    repeat along the UV seam and at the poles."""
    rows, columns = 12, 24
    vertices, uvs, faces = [], [], []
    for i in range(rows + 1):
        theta = np.pi * i / rows
        for j in range(columns + 1):          # column `columns` repeats column 0 (the seam)
            phi = 2 * np.pi * j / columns
            vertices.append((np.sin(theta) * np.cos(phi), np.cos(theta),
                             -np.sin(theta) * np.sin(phi)))
            uvs.append((j / columns, 1 - i / rows))
    for i in range(rows):
        for j in range(columns):
            a, b = i * (columns + 1) + j, (i + 1) * (columns + 1) + j
            if i > 0:
                faces.append((a, b, a + 1))
            if i < rows - 1:
                faces.append((a + 1, b, b + 1))
    # the seam copy of each pole is on no face: leave it out, as exporters do (Blender's OBJ
    # importer drops a vertex on no face, and its Mesh Cache then counts one fewer)
    faces = np.array(faces)
    used = np.unique(faces)
    renumber = np.full(len(vertices), -1)
    renumber[used] = np.arange(len(used))
    return np.array(vertices)[used], renumber[faces]


def open_scan() -> trimesh.Trimesh:
    """A scanned pebble: an ellipsoid whose underside (faces below y = -0.6) was never scanned."""
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    sphere.apply_scale((1.3, 0.8, 1.0))
    keep = sphere.triangles_center[:, 1] > -0.6 * 0.8
    return trimesh.Trimesh(sphere.vertices, sphere.faces[keep], process=False)


def animal() -> trimesh.Trimesh:
    """A thin-limbed animal: a box body, four thin capsule legs, two thin ears and a tail, each its
    own closed shell overlapping the body (as modellers build them)."""
    parts = [trimesh.creation.box(extents=(1.2, 0.5, 0.5))]
    parts[0].apply_translation((0.0, 0.9, 0.0))
    for x in (-0.45, 0.45):
        for z in (-0.17, 0.17):
            leg = trimesh.creation.capsule(height=0.75, radius=0.04, count=(8, 8))
            leg.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
            leg.apply_translation((x, 0.42, z))
            parts.append(leg)
    for z in (-0.12, 0.12):
        ear = trimesh.creation.box(extents=(0.03, 0.3, 0.12))
        ear.apply_translation((0.55, 1.25, z))
        parts.append(ear)
    tail = trimesh.creation.capsule(height=0.6, radius=0.03, count=(8, 8))
    tail.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2.5, (0, 0, 1)))
    tail.apply_translation((-0.85, 1.15, 0.0))
    parts.append(tail)
    return trimesh.util.concatenate(parts)


def teapot() -> trimesh.Trimesh:
    """A teapot-like multi-shell model: a squashed sphere, a spout and a handle overlapping it, and
    a lid resting on top as a separate closed shell."""
    pot = trimesh.creation.icosphere(subdivisions=3, radius=0.6)
    pot.apply_scale((1.0, 0.75, 1.0))
    spout = trimesh.creation.cone(radius=0.12, height=0.7, sections=16)
    spout.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 3, (0, 0, 1)))
    spout.apply_translation((0.45, 0.0, 0.0))
    handle = trimesh.creation.torus(major_radius=0.28, minor_radius=0.05, major_sections=24,
                                    minor_sections=8)
    handle.apply_translation((-0.6, 0.0, 0.0))
    lid = trimesh.creation.cylinder(radius=0.3, height=0.08, sections=24)
    lid.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    lid.apply_translation((0.0, 0.47, 0.0))
    return trimesh.util.concatenate([pot, spout, handle, lid])


def washer() -> trimesh.Trimesh:
    """A CAD part with a hole: a thick washer (an annulus, closed, of genus one)."""
    return trimesh.creation.annulus(r_min=0.35, r_max=1.0, height=0.5, sections=48)


def inside_out() -> trimesh.Trimesh:
    mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
    mesh.apply_scale((1.0, 0.6, 0.8))
    mesh.invert()
    return mesh


def millimetres() -> trimesh.Trimesh:
    """A capsule 2000 mm long, in millimetres."""
    capsule = trimesh.creation.capsule(height=1500.0, radius=250.0, count=(16, 16))
    return capsule


def fine_torus() -> trimesh.Trimesh:
    """70,000 triangles: the build-time benchmark's model."""
    return trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=250,
                                  minor_sections=140)


def blender_models(folder: Path) -> None:
    """Suzanne (open: eyes are separate shells and the head has holes), a cone and a cylinder,
    exported by Blender's OBJ exporter with UVs."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    makers = {"suzanne": lambda: bpy.ops.mesh.primitive_monkey_add(calc_uvs=True),
              "cone": lambda: bpy.ops.mesh.primitive_cone_add(vertices=24, calc_uvs=True),
              "cylinder": lambda: bpy.ops.mesh.primitive_cylinder_add(vertices=24,
                                                                      calc_uvs=True)}
    for name, make in makers.items():
        for obj in list(bpy.data.objects):
            bpy.data.objects.remove(obj)
        make()
        bpy.ops.wm.obj_export(filepath=str(folder / f"{name}.obj"), export_selected_objects=True,
                              export_materials=False, export_uv=True, export_normals=True)


def small(folder: Path) -> None:
    """The few models the unit tests use."""
    folder.mkdir(parents=True, exist_ok=True)
    open_scan().export(folder / "open_scan.obj")
    animal().export(folder / "animal.obj")
    vertices, faces = unwelded()
    write_obj(folder / "uv_sphere_unwelded.obj", vertices, faces)


def everything(folder: Path) -> None:
    small(folder)
    trimesh.creation.box(extents=(1.0, 1.0, 1.0)).export(folder / "box.obj")
    teapot().export(folder / "teapot.obj")
    washer().export(folder / "washer.stl")
    inside_out().export(folder / "inside_out.ply")
    millimetres().export(folder / "capsule_mm.obj")
    fine_torus().export(folder / "torus_70k.obj")
    # a glTF file has one UV per vertex, so its vertices repeat along UV seams
    vertices, faces = unwelded()
    trimesh.Trimesh(vertices * (1.0, 0.7, 0.9), faces, process=False).export(folder / "uv_egg.glb")
    blender_models(folder)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--all", metavar="DIR", help="every model, into DIR")
    args = parser.parse_args()
    if args.all:
        everything(Path(args.all))
    else:
        small(DATA)


if __name__ == "__main__":
    main()
