"""PC2 point caches as Blender's Mesh Cache modifier reads them, written and read with NumPy only
(springsim is never imported inside Blender).

Layout (springsim/export/pc2.py says the same): a 32-byte header, "POINTCACHE2\\0", int32 version
1, int32 point count, float32 start frame, float32 sample rate, int32 sample count, then float32
x, y, z point by point, sample by sample, little-endian. A cache that grows (frames streamed from
the running simulation) is the same file with a larger sample count: a reader that opens it
between two appends sees a whole cache of fewer frames.
"""
import os
from pathlib import Path

import numpy as np

HEADER = np.dtype([("signature", "S12"), ("version", "<i4"), ("points", "<i4"),
                   ("start", "<f4"), ("rate", "<f4"), ("samples", "<i4")])
SIGNATURE = b"POINTCACHE2\0"
SAMPLES_AT = 28    # byte offset of the sample count


def header(path) -> np.void | None:
    """The header of ``path``, or None when the file is missing or shorter than a header."""
    try:
        raw = np.fromfile(path, HEADER, count=1)
    except (FileNotFoundError, ValueError):
        return None
    if len(raw) != 1 or raw[0]["signature"] != SIGNATURE.rstrip(b"\0"):
        return None
    return raw[0]


def read(path, first: int = 0) -> np.ndarray:
    """Samples ``first`` onwards of the cache at ``path``, (F, N, 3) float32 (F may be 0)."""
    head = header(path)
    if head is None:
        return np.empty((0, 0, 3), np.float32)
    points, samples = int(head["points"]), int(head["samples"])
    count = max(samples - first, 0)
    offset = HEADER.itemsize + first * points * 12
    values = np.fromfile(path, "<f4", count=count * points * 3, offset=offset)
    count = len(values) // max(points * 3, 1)       # a sample still being written is left out
    return values[:count * points * 3].reshape(count, points, 3)


def write(path, points: np.ndarray, start_frame: float = 1.0) -> None:
    """A whole cache of ``points`` (F, N, 3), written beside and renamed over ``path``."""
    path = Path(path)
    staged = path.with_name(path.name + ".part")
    with open(staged, "wb") as file:
        _write_header(file, points.shape[1], start_frame, points.shape[0])
        file.write(np.ascontiguousarray(points, "<f4").tobytes())
    os.replace(staged, path)


def append(path, points: np.ndarray, start_frame: float = 1.0) -> None:
    """Add the samples ``points`` (F, N, 3) to the cache at ``path`` (made when missing): the
    samples first, the count in the header last, so that the file is a whole cache throughout."""
    head = header(path)
    if head is None:
        write(path, points, start_frame)
        return
    with open(path, "r+b") as file:
        file.seek(0, os.SEEK_END)
        file.write(np.ascontiguousarray(points, "<f4").tobytes())
        file.flush()
        file.seek(SAMPLES_AT)
        file.write(np.array([int(head["samples"]) + len(points)], "<i4").tobytes())


def _write_header(file, points: int, start_frame: float, samples: int) -> None:
    file.write(np.array([(SIGNATURE, 1, points, float(start_frame), 1.0, samples)],
                        HEADER).tobytes())
