"""Point-cache animation: a mesh's vertices at a series of times, as Blender and Houdini write
them (PC2, MDD), driving a deforming terrain (terrains/deforming_mesh.py) or pins that follow an
animated mesh (bodies/pins.py).

An ``[... .animation]`` table names the ``file`` and says when its samples are: sample k of a PC2
is at ``start + k * rate / fps`` (s), ``rate`` being the file's own frames per sample (1 as
Blender writes it); an MDD carries its samples' times, shifted so that the first is at
``start``. Between samples the points move linearly (so their velocity is the chord's); before
the first and after the last they hold still.

The file is read whole, checked (its header against its size, finite numbers, increasing
times), and kept per file version.
"""
import functools
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .errors import SceneError, is_finite, require

PC2_HEADER = np.dtype([("signature", "S12"), ("version", "<i4"), ("points", "<i4"),
                       ("start", "<f4"), ("rate", "<f4"), ("samples", "<i4")])
MAX_CACHE_BYTES = 4 << 30   # a cache larger than this is refused before it is read


class PointCache(NamedTuple):
    """Samples of a point set: their times (F,) in s from the cache's first, points (F, V, 3)."""

    times: np.ndarray
    points: np.ndarray


@dataclass
class Animation:
    """A point cache (``file``, PC2 or MDD) sampled at ``fps`` from time ``start`` (s)."""

    file: str = ""
    fps: float = 24.0
    start: float = 0.0

    def validate(self, key: str) -> None:
        require(is_finite(self.fps) and self.fps > 0, f"{key}.fps", self.fps,
                "must be > 0 frames per second")
        require(is_finite(self.start), f"{key}.start", self.start, "must be a finite number (s)")
        self.cache(f"{key}.file")

    def cache(self, key: str = "file") -> PointCache:
        """The cache's samples, with their times in the scene (s)."""
        read = read_point_cache(self.file, key)
        if Path(self.file).suffix.lower() == ".pc2":
            times = self.start + read.times / float(self.fps)   # PC2 times count frames
        else:
            times = self.start + read.times
        return PointCache(times, read.points)

    def check_points(self, count: int, key: str, what: str) -> None:
        """The cache moves ``count`` points (``what`` says which)."""
        points = self.cache(f"{key}.file").points.shape[1]
        require(points == count, f"{key}.file", self.file,
                f"moves {points} points, but {what} has {count}")


def read_point_cache(file: str, key: str) -> PointCache:
    """The samples of a PC2 (times in frames from the first) or MDD (times in s from the
    first) file, checked; ``key`` names the setting in errors."""
    require(isinstance(file, str) and file != "", key, file,
            "must name a point cache (.pc2 or .mdd)")
    path = Path(file).expanduser()
    require(path.suffix.lower() in (".pc2", ".mdd"), key, file,
            "must be a point cache: a .pc2 or .mdd file")
    require(path.is_file(), key, file, "no such file" + (
        "" if path.is_absolute() else f" (relative to {Path.cwd()}; in a scene file a "
        "relative path is relative to the scene file's folder)"))
    stat = path.stat()
    require(stat.st_size <= MAX_CACHE_BYTES, key, file,
            f"is {stat.st_size:,} bytes; a point cache may have at most {MAX_CACHE_BYTES:,}")
    return _read(str(path.resolve()), stat.st_mtime_ns, stat.st_size, key)


@functools.lru_cache(maxsize=8)
def _read(path: str, mtime_ns: int, size: int, key: str) -> PointCache:
    raw = Path(path).read_bytes()
    reader = _pc2 if path.lower().endswith(".pc2") else _mdd
    times, points = reader(raw, key, path)
    require(is_finite(points), key, path, "holds a number that is not finite")
    require(bool(np.all(np.diff(times) > 0)), key, path,
            "has sample times that do not increase")
    points.setflags(write=False)
    return PointCache(times, points)


def _pc2(raw: bytes, key: str, path: str):
    require(len(raw) >= PC2_HEADER.itemsize, key, path, "is too short for a PC2 header")
    header = np.frombuffer(raw[:PC2_HEADER.itemsize], PC2_HEADER)[0]
    require(header["signature"] == b"POINTCACHE2", key, path,
            "is not a PC2 file (it does not start with POINTCACHE2)")
    count, samples, rate = int(header["points"]), int(header["samples"]), float(header["rate"])
    require(count > 0 and samples > 0, key, path,
            f"says it has {count} points and {samples} samples; both must be > 0")
    require(np.isfinite(rate) and rate > 0, key, path,
            f"says its samples are {rate} frames apart; that must be > 0")
    expected = PC2_HEADER.itemsize + 12 * count * samples
    require(len(raw) == expected, key, path,
            f"is {len(raw):,} bytes, but its header ({count} points, {samples} samples) "
            f"needs {expected:,}: it is truncated or not a PC2 file")
    points = np.frombuffer(raw, "<f4", offset=PC2_HEADER.itemsize).reshape(samples, count, 3)
    return rate * np.arange(samples, dtype=float), points.astype(float)


def _mdd(raw: bytes, key: str, path: str):
    require(len(raw) >= 8, key, path, "is too short for an MDD header")
    samples, count = (int(n) for n in np.frombuffer(raw[:8], ">i4"))
    require(count > 0 and samples > 0, key, path,
            f"says it has {count} points and {samples} samples; both must be > 0")
    expected = 8 + 4 * samples + 12 * count * samples
    require(len(raw) == expected, key, path,
            f"is {len(raw):,} bytes, but its header ({count} points, {samples} samples) "
            f"needs {expected:,}: it is truncated or not an MDD file")
    times = np.frombuffer(raw, ">f4", samples, offset=8).astype(float)
    points = np.frombuffer(raw, ">f4", offset=8 + 4 * samples).reshape(samples, count, 3)
    if not is_finite(times):
        raise SceneError(key, path, "holds a sample time that is not finite")
    return times - times[0], points.astype(float)


def interpolated_points(cache: PointCache, t: float) -> tuple[np.ndarray, np.ndarray]:
    """(positions, velocities) (V, 3) of the cache's points at time t (module doc): the NumPy
    reference of the kernels'."""
    times, points = cache.times, cache.points
    if len(times) == 1 or t <= times[0] or t >= times[-1]:
        held = points[0] if (len(times) == 1 or t <= times[0]) else points[-1]
        return held.copy(), np.zeros_like(held)
    k = int(np.searchsorted(times, t, side="right")) - 1
    span = times[k + 1] - times[k]
    s = (t - times[k]) / span
    return (points[k] + s * (points[k + 1] - points[k]),
            (points[k + 1] - points[k]) / span)
