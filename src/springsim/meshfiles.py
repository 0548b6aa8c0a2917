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
from .sizes import check_reading

SUFFIXES = (".obj", ".stl", ".ply", ".off", ".glb", ".gltf")
# Reading takes up to this many bytes of memory per byte of the file (traced: 13 for an OBJ of
# short lines read here, 17 through trimesh, 12 for an STL), so a file is measured before it is
# read; and no OBJ line may be longer than MAX_LINE (a face of 100,000 corners fits), so that a
# file of one huge line is refused at its first megabyte.
READ_BYTES_PER_BYTE = 20
MAX_LINE = 1 << 20


class TriangleMesh(NamedTuple):
    vertices: np.ndarray   # (V, 3) float64, m
    triangles: np.ndarray  # (T, 3) int64 rows of vertices, wound counter-clockwise seen from
                           # the side the normals point to


def read_mesh(file: str, key: str) -> TriangleMesh:
    """The mesh in ``file``, its vertices merged (trimesh's processing); ``key`` names the
    setting in errors. The file passes ``read_mesh_file``'s checks first, so that a terrain
    refuses what a body or a cloth refuses (a vertex that is not a number, which trimesh's
    processing would drop, a face naming a missing vertex, a file too big to read)."""
    read_mesh_file(file, key)
    path = Path(file).expanduser()
    stat = path.stat()
    return _read(str(path.resolve()), stat.st_mtime_ns, stat.st_size, key)


@functools.lru_cache(maxsize=16)
def _read(path: str, mtime_ns: int, size: int, key: str) -> TriangleMesh:
    loaded = _trimesh_load(path, key, process=True)
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


# --- a mesh file as the artist has it: its own vertices in its own order, polygons, groups -------

class MeshFile(NamedTuple):
    """A mesh file as written: the file's own vertices in the file's order (seam duplicates
    included, so that what we export applies to the same file in Blender or Houdini), its faces
    as polygons, and its named groups."""

    vertices: np.ndarray   # (V, 3) float64, m, in the file's order
    faces: np.ndarray      # (F, K) int64 rows of vertices, padded with -1 (K: the largest face)
    groups: dict           # name -> (n,) int64 vertices of the faces in the OBJ group or object

    def triangles(self) -> np.ndarray:
        """(T, 3) the faces split into fans from their first corner (quads into two)."""
        return fan_triangles(self.faces)


def read_mesh_file(file: str, key: str) -> MeshFile:
    """The mesh in ``file`` as written (MeshFile): OBJ is read here, keeping its quads, groups
    and vertex order (trimesh would split vertices along UV seams and triangulate); other
    formats through trimesh without merging or reordering anything."""
    require(isinstance(file, str) and file != "", key, file,
            "must name a mesh file (" + ", ".join(SUFFIXES) + ")")
    path = Path(file).expanduser()
    require(path.is_file(), key, file, "no such file" + (
        "" if path.is_absolute() else f" (relative to {Path.cwd()}; in a scene file a "
        "relative path is relative to the scene file's folder)"))
    stat = path.stat()
    check_reading(key, file, stat.st_size, READ_BYTES_PER_BYTE, "a mesh file")
    try:
        return _read_file(str(path.resolve()), stat.st_mtime_ns, stat.st_size)
    except SceneError as error:   # read once whatever key asks; the error names the asker's
        raise SceneError(key, error.value, error.allowed) from None


@functools.lru_cache(maxsize=16)
def _read_file(path: str, mtime_ns: int, size: int, key: str = "file") -> MeshFile:
    if path.lower().endswith(".obj"):
        mesh = _read_obj(path, key)
    else:
        loaded = _trimesh_load(path, key, process=False)
        faces = getattr(loaded, "faces", None)
        mesh = MeshFile(np.asarray(loaded.vertices, float),
                        np.asarray(faces if faces is not None else np.empty((0, 3)), np.int64),
                        {})
    require(len(mesh.vertices) > 0, key, path, "holds no vertices")
    bad = np.flatnonzero(~np.isfinite(mesh.vertices).all(axis=1))
    if bad.size:
        raise SceneError(key, path, f"has vertices that are not finite numbers ({bad.size}; the "
                                    f"first is number {int(bad[0])}); fix or remove them")
    require(len(mesh.faces) > 0, key, path, "holds no faces (triangles or polygons)")
    return mesh


def _read_obj(path: str, key: str) -> MeshFile:
    """Wavefront OBJ: ``v`` lines, ``f`` lines of ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``
    corners (negative numbers count back from the last vertex above the face), ``g`` and ``o``
    names. Each line is checked as it is read, and a refusal names its line."""
    vertices, faces, groups, current = [], [], {}, []
    largest = (0, 0)   # the largest vertex number a face names, and its line
    with open(path, encoding="utf-8", errors="replace") as file:
        for number, line in enumerate(iter(lambda: file.readline(MAX_LINE + 1), ""), 1):
            require(len(line) <= MAX_LINE, key, path,
                    f"has a line longer than {MAX_LINE:,} characters (line {number}): it is not "
                    "an OBJ file; give an OBJ, STL, PLY, OFF or GLB file")
            words = line.split()
            if not words:
                continue
            if words[0] == "v":
                vertices.append(_vertex(words, number, key, path))
            elif words[0] == "f":
                corners = _corners(words, len(vertices), number, key, path)
                largest = max(largest, (max(corners, default=0) + 1, number))
                if len(corners) >= 3:
                    faces.append(corners)
                    for name in current:
                        groups[name].append(corners)
            elif words[0] in ("g", "o"):
                current = words[1:] or ["default"]
                for name in current:
                    groups.setdefault(name, [])
    require(largest[0] <= len(vertices), key, path,
            f"has a face naming a vertex it does not have (vertex {largest[0]}, line "
            f"{largest[1]}; the file has {len(vertices)})")
    padded = _padded(faces)
    named = {name: np.unique(_padded(rows)[_padded(rows) >= 0]) for name, rows in groups.items()
             if rows}
    return MeshFile(np.asarray(vertices, float).reshape(-1, 3), padded, named)


def _vertex(words: list, number: int, key: str, path: str) -> list:
    """A ``v x y z [w]`` line's three numbers (a weight or colours after them are left out)."""
    try:
        xyz = [float(word) for word in words[1:4]]
    except ValueError:
        xyz = []
    require(len(xyz) == 3, key, path,
            f"has a vertex line that is not three numbers (line {number}: "
            f"{' '.join(words)[:80]!r}); each vertex is 'v x y z'")
    return xyz


def _corners(words: list, above: int, number: int, key: str, path: str) -> list:
    """An ``f`` line's vertices, numbered from 0: a number n >= 1 is the file's n-th vertex
    (checked against the whole file once it is read), -n the n-th counting back from the last
    of the ``above`` vertices defined before the line."""
    try:
        corners = [int(word.split("/", 1)[0]) for word in words[1:]]
    except ValueError:
        corners = None
    require(corners is not None, key, path,
            f"has a face line that is not vertex numbers (line {number}: "
            f"{' '.join(words)[:80]!r}); give an OBJ, STL, PLY, OFF or GLB file")
    for corner in corners:
        require(corner >= 1 or -above <= corner <= -1, key, path,
                f"has a face naming a vertex it does not have (vertex {corner}, line {number}; "
                f"{above} are defined before it: a face names vertices from 1, or -1 to "
                f"-{above} counting back from the last)")
    return [c - 1 if c > 0 else above + c for c in corners]


def _padded(faces: list) -> np.ndarray:
    width = max((len(face) for face in faces), default=3)
    padded = np.full((len(faces), width), -1, np.int64)
    for row, face in enumerate(faces):
        padded[row, :len(face)] = face
    return padded


def _trimesh_load(path: str, key: str, process: bool):
    try:
        import trimesh
    except ImportError:   # pragma: no cover - the mesh extra is part of every set-up
        raise SceneError(key, path, "needs trimesh: pip install 'springsim[mesh]'") from None
    try:
        return trimesh.load(path, force="mesh", process=process)
    except Exception as error:  # noqa: BLE001  (trimesh raises many kinds for a bad file)
        raise SceneError(key, path, f"is not a mesh file trimesh can read ({_first_line(error)}); "
                                    "give an " + ", ".join(SUFFIXES) + " file") from None


def fan_triangles(faces: np.ndarray) -> np.ndarray:
    """(T, 3) int64: each polygon (a row padded with -1) as a fan from its first corner: every
    face's first triangle in face order, then every second one (of quads and larger), and so on
    (the order a grid's two triangles per cell come in, bodies/cube.py grid_triangles)."""
    fans = [faces[faces[:, k + 1] >= 0][:, [0, k, k + 1]] for k in range(1, faces.shape[1] - 1)]
    return np.concatenate(fans) if fans else np.empty((0, 3), np.int64)


class Welded(NamedTuple):
    vertices: np.ndarray   # (W, 3) one per distinct position, in order of first appearance
    of_file_vertex: np.ndarray   # (V,) int64: the welded vertex of each file vertex


def first_file_vertex(of_file_vertex: np.ndarray) -> np.ndarray:
    """(W,) each welded vertex's first file vertex: where a per-file-vertex array (a point
    cache) gives the welded vertex its value."""
    first = np.full(int(of_file_vertex.max()) + 1 if len(of_file_vertex) else 0,
                    len(of_file_vertex), np.int64)
    np.minimum.at(first, of_file_vertex, np.arange(len(of_file_vertex)))
    return first


def weld(vertices: np.ndarray, tolerance: float = 1e-9) -> Welded:
    """Vertices at the same position (within ``tolerance`` of the mesh's size) made one: a file
    splits a vertex along its UV and normal seams, and a body or cloth must not split there."""
    size = float(np.max(np.ptp(vertices, axis=0))) if len(vertices) else 0.0
    quantum = max(tolerance * size, 1e-300)
    cells = np.round(vertices / quantum).astype(np.int64) if size else \
        np.zeros((len(vertices), 3), np.int64)
    order = np.lexsort(cells.T[::-1])                   # by x, then y, then z: a fast sort
    ordered = cells[order]
    starts = np.r_[True, np.any(ordered[1:] != ordered[:-1], axis=1)] if len(cells) else \
        np.zeros(0, bool)
    group = np.cumsum(starts) - 1
    inverse = np.empty(len(cells), np.int64)
    inverse[order] = group
    first = np.full(int(starts.sum()), len(cells), np.int64)
    np.minimum.at(first, group, order)                  # each position's first file vertex
    # number the distinct positions in order of their first appearance in the file
    rank = np.empty(len(first), np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return Welded(vertices[np.sort(first)], rank[inverse])


def is_closed(triangles: np.ndarray) -> bool:
    """Whether every edge of the triangle mesh is shared by exactly two triangles."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                    triangles[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))
