"""Triangle mesh files: read with trimesh, checked, and placed in the scene.

Shared by mesh bodies (bodies/mesh.py) and mesh terrains (terrains/mesh.py). trimesh reads OBJ,
STL, PLY, OFF and GLB/GLTF (a file holding several meshes, as a GLTF scene does, becomes their
union). Every problem is one SceneError naming the key, the value and what would do.
"""
import functools
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from .errors import SceneError, is_finite, require

SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")


class TriangleMesh(NamedTuple):
    vertices: np.ndarray   # (V, 3) float64, m
    triangles: np.ndarray  # (T, 3) int64 rows of vertices, wound counter-clockwise seen from
                           # the side the normals point to


def read_mesh(file: str, key: str) -> TriangleMesh:
    """The mesh in ``file``; ``key`` names the setting in errors."""
    require(isinstance(file, str) and file != "", key, file,
            "must name a mesh file (" + ", ".join(SUFFIXES) + ")")
    path = Path(file).expanduser()
    require(path.is_file(), key, file, "no such file" + (
        "" if path.is_absolute() else f" (relative to {Path.cwd()}; in a scene file a "
        "relative path is relative to the scene file's folder)"))
    stat = path.stat()
    return _read(str(path.resolve()), stat.st_mtime_ns, stat.st_size, key)


@functools.lru_cache(maxsize=16)
def _read(path: str, mtime_ns: int, size: int, key: str) -> TriangleMesh:
    try:
        import trimesh
    except ImportError:   # pragma: no cover - the mesh extra is part of every set-up
        raise SceneError(key, path, "needs trimesh: pip install 'springsim[mesh]'") from None
    try:
        loaded = trimesh.load(path, force="mesh", process=True)
    except Exception as error:   # trimesh raises many kinds for a file it cannot parse
        raise SceneError(key, path, f"is not a mesh file trimesh can read ({_first_line(error)}); "
                                    "give an " + ", ".join(SUFFIXES) + " file") from None
    faces = getattr(loaded, "faces", None)
    require(faces is not None and len(faces) > 0, key, path, "holds no triangles")
    vertices = np.asarray(loaded.vertices, float)
    require(is_finite(vertices), key, path, "has vertices that are not finite numbers")
    return TriangleMesh(vertices, np.asarray(faces, np.int64))


def _first_line(error: Exception) -> str:
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0]}" if text else type(error).__name__


def placed(mesh: TriangleMesh, scale: float, rotation_degrees: float, rotation_axis,
           position) -> TriangleMesh:
    """The mesh scaled, rotated about its own origin, then moved by ``position``."""
    vertices = float(scale) * mesh.vertices
    if rotation_degrees:
        axis = np.asarray(rotation_axis, float)
        rotvec = np.radians(rotation_degrees) * axis / np.linalg.norm(axis)
        vertices = Rotation.from_rotvec(rotvec).apply(vertices)
    return TriangleMesh(vertices + np.asarray(position, float), mesh.triangles)


def validate_placement(spec, key: str) -> None:
    """The keys every mesh setting has: scale, rotation_degrees, rotation_axis, position."""
    require(is_finite(spec.scale) and spec.scale > 0, f"{key}.scale", spec.scale,
            "must be > 0 (a factor on the file's coordinates)")
    require(is_finite(spec.rotation_degrees), f"{key}.rotation_degrees", spec.rotation_degrees,
            "must be a finite number of degrees")
    require(np.shape(spec.rotation_axis) == (3,) and is_finite(spec.rotation_axis)
            and np.linalg.norm(spec.rotation_axis) > 0, f"{key}.rotation_axis",
            spec.rotation_axis, "must be a non-zero vector")
    require(np.shape(spec.position) == (3,) and is_finite(spec.position), f"{key}.position",
            spec.position, "must be three finite numbers (m)")


def triangle_areas(mesh: TriangleMesh) -> np.ndarray:
    a, b, c = (mesh.vertices[mesh.triangles[:, k]] for k in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def check_triangles(mesh: TriangleMesh, key: str, file: str) -> None:
    """Refuse degenerate (zero-area) triangles: they have no normal to collide or embed with."""
    size = float(np.max(np.ptp(mesh.vertices, axis=0)))
    require(size > 0, key, file, "has no extent: all its vertices coincide")
    degenerate = np.flatnonzero(triangle_areas(mesh) <= 1e-12 * size * size)
    require(degenerate.size == 0, key, file,
            f"has {degenerate.size} degenerate (zero-area) triangles (the first is number "
            f"{degenerate[:1].tolist()[0] if degenerate.size else -1}); remove them, for example "
            "with trimesh: mesh.update_faces(mesh.nondegenerate_faces())")


def open_edges(mesh: TriangleMesh) -> int:
    """How many edges do not join exactly two triangles (consistently wound): 0 when closed."""
    t = mesh.triangles
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    _, inverse, counts = np.unique(undirected, axis=0, return_inverse=True, return_counts=True)
    # a closed, consistently wound surface has each edge once in each direction
    forward = directed[:, 0] < directed[:, 1]
    balance = np.bincount(inverse.ravel(), weights=np.where(forward, 1.0, -1.0))
    return int(np.count_nonzero((counts != 2) | (balance != 0)))


def enclosed_volume(mesh: TriangleMesh) -> float:
    """Signed volume (m^3) of a closed mesh: positive when its normals point out."""
    a, b, c = (mesh.vertices[mesh.triangles[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def check_closed(mesh: TriangleMesh, key: str, file: str) -> float:
    """Refuse a mesh that is not a closed surface with outward normals; returns its volume."""
    check_triangles(mesh, key, file)
    edges = open_edges(mesh)
    require(edges == 0, key, file,
            f"is not watertight ({edges} edges are not shared by exactly two consistently wound "
            "triangles): a body must be a closed surface; fill its holes, for example with "
            "trimesh: mesh.fill_holes(), mesh.fix_normals()")
    volume = enclosed_volume(mesh)
    require(volume > 0, key, file,
            f"encloses no volume ({volume:.3g} m^3)" + (
                "; its normals point inwards: flip them (trimesh: mesh.invert())"
                if volume < 0 else ""))
    return volume
