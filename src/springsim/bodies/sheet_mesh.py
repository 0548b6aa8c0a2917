"""A cloth's particles and springs from any triangle or quad mesh (``type = "cloth"`` with a
``file``).

- Particles: the file's vertices welded by position (a file splits a vertex along its UV and
  normal seams; a cloth must not tear there), numbered in the order they first appear in the file,
  so a file without seams keeps its own vertex numbers.
- Springs, as a cloth's grid has them: *structural* along every edge of every face; *shear*
  across both diagonals of every quad (a triangle's edges already resist shear); *bend* between
  the two vertices opposite an interior edge shared by two triangles, and, where quads meet at a
  vertex, between each two of its quad neighbours that share no quad with it (on a quad grid: the
  straight vertex lines, one cell to each side, as the grid's +2 springs). A pair joined by a
  spring of an earlier kind gets no second one.
- On a quad grid written in the grid's order this gives the grid cloth's particles, springs and
  triangles exactly (tests/test_cloth_mesh.py).
"""
from typing import NamedTuple

import numpy as np

from ..meshfiles import MeshFile, fan_triangles, weld
from ..springs import SpringKind


class SheetMesh(NamedTuple):
    positions: np.ndarray       # (W, 3) welded vertices, m, in the file's frame
    faces: np.ndarray           # (F, K) rows of welded vertices, padded with -1
    groups: dict                # name -> welded vertex numbers
    of_file_vertex: np.ndarray  # (V,) the welded vertex (particle) of each file vertex
    file_triangles: np.ndarray  # (T, 3) the file's faces as triangles of file vertices
    springs: dict               # SpringKind -> (S, 2) int32 (sheet_springs)


def sheet_mesh(mesh: MeshFile) -> SheetMesh:
    """The welded sheet of ``mesh``; faces that collapse when welded (a repeated corner) go."""
    welded = weld(mesh.vertices)
    faces = np.where(mesh.faces >= 0, welded.of_file_vertex[np.maximum(mesh.faces, 0)], -1)
    groups = {name: np.unique(welded.of_file_vertex[members])
              for name, members in mesh.groups.items()}
    faces = faces[_distinct_corners(faces)]
    return SheetMesh(welded.vertices, faces, groups, welded.of_file_vertex,
                     fan_triangles(mesh.faces), sheet_springs(faces, len(welded.vertices)))


def _distinct_corners(faces: np.ndarray) -> np.ndarray:
    ordered = np.sort(faces, axis=1)
    repeated = (ordered[:, 1:] == ordered[:, :-1]) & (ordered[:, 1:] >= 0)
    return ~repeated.any(axis=1)


def corner_count(faces: np.ndarray) -> np.ndarray:
    return np.count_nonzero(faces >= 0, axis=1)


def faces_of(faces: np.ndarray, corners: int) -> np.ndarray:
    """(n, corners) the faces that have ``corners`` corners."""
    if faces.shape[1] < corners:
        return np.empty((0, corners), np.int64)
    return faces[corner_count(faces) == corners][:, :corners]


def face_edges(faces: np.ndarray) -> np.ndarray:
    """(E, 2) the directed edges of every face, corner k to corner k + 1 (the last to the
    first), face by face."""
    count = corner_count(faces)
    following = np.roll(faces, -1, axis=1)
    following[np.arange(len(faces)), count - 1] = faces[:, 0]
    valid = faces >= 0
    return np.stack([faces[valid], following[valid]], axis=1)


def sheet_springs(faces: np.ndarray, particle_count: int) -> dict:
    """SpringKind -> (S, 2) int32 springs (lower particle first, in ascending order)."""
    quads, triangles = faces_of(faces, 4), faces_of(faces, 3)
    kinds = {SpringKind.STRUCTURAL: face_edges(faces),
             SpringKind.SHEAR: np.concatenate([quads[:, [0, 2]], quads[:, [1, 3]]]),
             SpringKind.BEND: np.concatenate([across_edges(triangles),
                                              quad_lines(quads, particle_count)])}
    built, taken = {}, np.empty(0, np.int64)
    for kind, pairs in kinds.items():
        pairs = np.sort(pairs.reshape(-1, 2), axis=1).astype(np.int64)
        codes = np.unique(pairs[:, 0] * particle_count + pairs[:, 1])
        codes = codes[~np.isin(codes, taken)]
        taken = np.concatenate([taken, codes])
        built[kind] = np.stack([codes // particle_count, codes % particle_count],
                               axis=1).astype(np.int32)
    return built


def across_edges(triangles: np.ndarray) -> np.ndarray:
    """(B, 2) for each edge shared by exactly two triangles, their two corners off the edge."""
    if len(triangles) == 0:
        return np.empty((0, 2), np.int64)
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    opposite = np.concatenate([triangles[:, 2], triangles[:, 0], triangles[:, 1]])
    n = np.int64(triangles.max() + 1)
    code = np.minimum(edges[:, 0], edges[:, 1]) * n + np.maximum(edges[:, 0], edges[:, 1])
    _, edge, counts = np.unique(code, return_inverse=True, return_counts=True)
    shared = counts[edge] == 2
    order = np.argsort(edge[shared], kind="stable")
    corners = opposite[shared][order].reshape(-1, 2)
    return corners[corners[:, 0] != corners[:, 1]]


def quad_lines(quads: np.ndarray, particle_count: int) -> np.ndarray:
    """(B, 2) for each vertex v of the quads, the pairs (a, b) of its neighbours that lie on
    either side of a third neighbour c (a and c share a quad with v, and so do c and b) but
    share no quad with v themselves: the straight line a-v-b of a quad grid, also along its
    border and around a hole's corner (where a and b on the two sides of the hole have no c)."""
    if len(quads) == 0:
        return np.empty((0, 2), np.int64)
    n = np.int64(particle_count)
    centre = quads.ravel()
    before, after = np.roll(quads, 1, axis=1).ravel(), np.roll(quads, -1, axis=1).ravel()
    # around v, c's partners: the neighbours that share a quad with v and c
    entries = np.unique(np.concatenate([np.stack([centre, after, before], 1),
                                        np.stack([centre, before, after], 1)]), axis=0)
    key = entries[:, 0] * n + entries[:, 1]
    # groups of exactly two entries (a manifold vertex: c has a quad on each side)
    two = np.flatnonzero((key[1:] == key[:-1]) & np.r_[key[2:] != key[1:-1], True]
                         & np.r_[True, key[1:-1] != key[:-2]])
    a, b, v = entries[two, 2], entries[two + 1, 2], entries[two, 0]
    adjacent = np.unique((centre * n + np.minimum(before, after)) * n + np.maximum(before, after))
    code = (v * n + np.minimum(a, b)) * n + np.maximum(a, b)
    keep = ~np.isin(code, adjacent)
    return np.stack([a[keep], b[keep]], axis=1)


def polygon_areas(positions: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(F,) m^2: each face's area, as the sum of its fan triangles' areas."""
    area = np.zeros(len(faces))
    for k in range(1, faces.shape[1] - 1):
        has = faces[:, k + 1] >= 0
        a, b, c = (positions[faces[has][:, j]] for j in (0, k, k + 1))
        area[has] += 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    return area
