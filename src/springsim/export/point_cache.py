"""What the point-cache formats (MDD, PC2) share: their points and the rest mesh beside them.

A point cache is only positions, point by point and frame by frame; the mesh it moves comes from
a rest-pose OBJ written beside it (``take.mdd`` -> ``take.obj``) whose vertices are the cache's
points in the same order: every body surface, then a UV sphere per ball. Blender's Mesh Cache
modifier and Houdini's MDD SOP apply the cache to that mesh. The points are springsim's
coordinates (Y up, metres); Blender's OBJ importer turns Y-up into Z-up with the object's
transform, which the cached points then go through as well.
"""
from pathlib import Path

import numpy as np

from .geometry import point_pieces, stacked_vertices
from .obj import write_obj
from ..safe_files import staged_paths


def outputs(path) -> list:
    """A cache and its rest mesh."""
    return [path, rest_mesh_path(path)]


def check_available() -> None:
    """No dependency: NumPy writes both formats."""


def rest_mesh_path(path) -> Path:
    return Path(path).with_suffix(".obj")


def write_with_rest_mesh(take, path, encode) -> list:
    """The cache ``path`` (its bytes from ``encode(points (F, N, 3), times (F,), fps,
    start_frame)``) and its rest
    mesh, both written whole or neither."""
    pieces = point_pieces(take.layout, take.positions[0])
    points = stacked_vertices(pieces, take.positions)
    obj = rest_mesh_path(path)
    with staged_paths([path, obj]) as (staged_cache, staged_obj):
        with open(staged_cache, "xb") as file:
            encode(file, points, np.asarray(take.time, float), take.fps, take.start_frame)
        write_obj(staged_obj, pieces, points[0], take.name)
    return [Path(path), obj]
