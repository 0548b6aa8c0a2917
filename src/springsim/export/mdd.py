"""MDD point cache (LightWave's Motion Designer format), read by Blender's Mesh Cache modifier
and Houdini's MDD SOP; written with a rest-pose OBJ beside it (point_cache.py).

The format, all big-endian (as Blender reads it in source/blender/modifiers/intern/
MOD_meshcache_mdd.cc and writes it in its io_shape_mdd add-on, export_mdd.py):

    int32 frame count F, int32 point count N,
    float32 time of each frame (F values, in seconds),
    then frame by frame, point by point: float32 x, y, z.
"""
import numpy as np

from .point_cache import check_available, outputs, write_with_rest_mesh

EXTENSIONS = (".mdd",)
DESCRIPTION = "MDD point cache (big-endian) + rest-pose OBJ, for Blender's Mesh Cache / Houdini"


__all__ = ["EXTENSIONS", "DESCRIPTION", "check_available", "outputs", "write", "encode"]


def write(take, path) -> list:
    return write_with_rest_mesh(take, path, encode)


def encode(file, points: np.ndarray, times: np.ndarray, fps: float, start_frame: int = 0) -> None:
    frames, count = points.shape[:2]
    file.write(np.array([frames, count], ">i4").tobytes())
    file.write(times.astype(">f4").tobytes())
    file.write(points.astype(">f4").tobytes())
