"""PC2 point cache (the "Point Cache 2" format of 3ds Max, by Matt Ebb's original exporter), read
by Blender's Mesh Cache modifier and Houdini; written with a rest-pose OBJ beside it.

The format, all little-endian (as Blender reads it in source/blender/modifiers/intern/
MOD_meshcache_pc2.cc: a 32-byte header, ``PC2Head``):

    char[12] "POINTCACHE2\\0", int32 file version (1), int32 point count N,
    float32 start frame, float32 sample rate (frames per sample), int32 sample count F,
    then sample by sample, point by point: float32 x, y, z.

The start frame is the take's (1 unless `export --start-frame` says otherwise) and the sample rate
1: sample k is frame start + k. Blender's Mesh Cache modifier reads frames as its own "Frame
Start" says, not the header: set it to the same number.
"""
import numpy as np

from .point_cache import check_available, outputs, write_with_rest_mesh

EXTENSIONS = (".pc2",)
DESCRIPTION = "PC2 point cache (little-endian) + rest-pose OBJ, for Blender's Mesh Cache / Houdini"
HEADER = np.dtype([("signature", "S12"), ("version", "<i4"), ("points", "<i4"),
                   ("start", "<f4"), ("rate", "<f4"), ("samples", "<i4")])


__all__ = ["EXTENSIONS", "DESCRIPTION", "check_available", "outputs", "write", "encode"]


def write(take, path) -> list:
    return write_with_rest_mesh(take, path, encode)


def encode(file, points: np.ndarray, times: np.ndarray, fps: float, start_frame: int = 0) -> None:
    frames, count = points.shape[:2]
    header = np.array([(b"POINTCACHE2\0", 1, count, float(start_frame), 1.0, frames)], HEADER)
    file.write(header.tobytes())
    file.write(points.astype("<f4").tobytes())
