"""Point-cache animation: a mesh's vertices at a series of times, as Blender and Houdini write
them (PC2, MDD, or a numbered sequence of OBJ files), driving a deforming terrain
(terrains/deforming_mesh.py) or pins that follow an animated mesh (bodies/pins.py).

An ``[... .animation]`` table names the ``file`` and says when its samples are: sample k of a PC2
is at ``start + k * rate / fps`` (s), ``rate`` being the file's own frames per sample (1 as
Blender writes it); an MDD carries its samples' times, shifted so that the first is at
``start``. An OBJ sequence is named by one of its files (``walk_0001.obj``) or by its pattern
with the frame number as a run of ``#`` (``walk_####.obj``, as Blender's output paths write
it): every file of the folder with the same name around a number is a sample, at
``start + (number - first number) / fps``, so a sequence exported every other frame keeps its
timing. Between samples the points move linearly (so their velocity is the chord's); before
the first and after the last they hold still.

The files are read whole, checked (a header against its size, every OBJ of a sequence with the
first one's vertex count, finite numbers, increasing times), and kept per file version.
"""
import functools
import re
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .errors import SceneError, is_finite, require
from .meshfiles import READ_BYTES_PER_BYTE
from .sizes import check_reading

PC2_HEADER = np.dtype([("signature", "S12"), ("version", "<i4"), ("points", "<i4"),
                       ("start", "<f4"), ("rate", "<f4"), ("samples", "<i4")])
MAX_CACHE_BYTES = 4 << 30   # a cache larger than this is refused before it is read
BINARY_BYTES_PER_BYTE = 4   # reading a PC2 or MDD: its bytes, and its points as float64
FRAME_TIMED = (".pc2", ".obj")   # the formats whose sample times count frames (of ``fps``)
NUMBERED = re.compile(r"^(?P<head>.*?)(?P<number>#+|\d+)(?P<tail>\D*)$")


class PointCache(NamedTuple):
    """Samples of a point set: their times (F,) in s from the cache's first, points (F, V, 3)."""

    times: np.ndarray
    points: np.ndarray


@dataclass
class Animation:
    """A point cache (``file``: PC2, MDD or a numbered OBJ sequence) sampled at ``fps`` from
    time ``start`` (s)."""

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
        if Path(self.file).suffix.lower() in FRAME_TIMED:
            times = self.start + read.times / float(self.fps)
        else:
            times = self.start + read.times
        return PointCache(times, read.points)

    def check_points(self, count: int, key: str, what: str) -> None:
        """The cache moves ``count`` points (``what`` says which)."""
        points = self.cache(f"{key}.file").points.shape[1]
        require(points == count, f"{key}.file", self.file,
                f"moves {points} points, but {what} has {count}")

    def version(self) -> tuple:
        """What changes when any of the cache's files does (for keeping what is built from it)."""
        return tuple((str(path.resolve()), path.stat().st_mtime_ns)
                     for path in cache_files(self.file, "file"))


def read_point_cache(file: str, key: str) -> PointCache:
    """The samples of a PC2 (times in frames from the first), an MDD (times in s from the
    first) or an OBJ sequence (times in frames from the first), checked; ``key`` names the
    setting in errors."""
    files = cache_files(file, key)
    size = sum(path.stat().st_size for path in files)
    require(size <= MAX_CACHE_BYTES, key, file,
            f"is {size:,} bytes; a point cache may have at most {MAX_CACHE_BYTES:,}")
    text = files[0].suffix.lower() == ".obj"
    check_reading(key, file, size, READ_BYTES_PER_BYTE if text else BINARY_BYTES_PER_BYTE,
                  "an OBJ sequence" if text else "a point cache")
    return _read(tuple((str(path.resolve()), path.stat().st_mtime_ns, path.stat().st_size)
                       for path in files), key)


def cache_files(file: str, key: str) -> list[Path]:
    """The file or files that hold the cache: a PC2 or MDD, or every file of an OBJ sequence in
    the order of their numbers (module doc)."""
    require(isinstance(file, str) and file != "", key, file,
            "must name a point cache (.pc2 or .mdd) or a numbered OBJ sequence (walk_####.obj)")
    path = Path(file).expanduser()
    suffix = path.suffix.lower()
    require(suffix in (".pc2", ".mdd", ".obj"), key, file,
            "must be a point cache: a .pc2 or .mdd file, or a numbered sequence of .obj files")
    where = "" if path.is_absolute() else (
        f" (relative to {Path.cwd()}; in a scene file a relative path is relative to the scene "
        "file's folder)")
    if suffix != ".obj":
        require(path.is_file(), key, file, "no such file" + where)
        return [path]
    numbered = NUMBERED.match(path.name)
    require(numbered is not None, key, file,
            "an OBJ animation is a numbered sequence: name one of its files (walk_0001.obj) or "
            "its pattern, the frame number as #s (walk_####.obj)")
    head, tail = numbered["head"], numbered["tail"]
    pattern = re.compile(re.escape(head) + r"(\d+)" + re.escape(tail) + "$")
    folder = path.parent
    found = sorted((int(match[1]), folder / name) for name in
                   (sorted(p.name for p in folder.iterdir()) if folder.is_dir() else [])
                   if (match := pattern.match(name)) and (folder / name).is_file())
    require(len(found) > 0, key, file, f"no file {head}<number>{tail} found" + where)
    numbers = [number for number, _ in found]
    twice = [p.name for n, p in found if numbers.count(n) > 1]
    require(not twice, key, file, f"two files have one frame number ({', '.join(twice[:2])})")
    return [p for _, p in found]


@functools.lru_cache(maxsize=8)
def _read(versions: tuple, key: str) -> PointCache:
    paths = [version[0] for version in versions]
    path = paths[0]
    if path.lower().endswith(".obj"):
        times, points = _obj_sequence(paths, key)
    else:
        raw = Path(path).read_bytes()
        reader = _pc2 if path.lower().endswith(".pc2") else _mdd
        times, points = reader(raw, key, path)
    require(is_finite(points), key, path, "holds a number that is not finite")
    require(bool(np.all(np.diff(times) > 0)), key, path,
            "has sample times that do not increase")
    points.setflags(write=False)
    return PointCache(times, points)


def _obj_sequence(paths: list[str], key: str):
    """Times (frames from the first file's number) and the vertices of every file, each in its
    file's order (``v`` lines), as many in each as in the first."""
    frames = []
    for path in paths:
        vertices = obj_vertices(Path(path).read_bytes(), key, path)
        require(not frames or len(vertices) == len(frames[0]), key, path,
                f"has {len(vertices)} vertices, but the sequence's first file "
                f"{Path(paths[0]).name} has {len(frames[0]) if frames else 0}: every file of "
                f"an OBJ sequence must list the same vertices")
        frames.append(vertices)
    numbers = np.array([int(NUMBERED.match(Path(path).name)["number"]) for path in paths], float)
    return numbers - numbers[0], np.stack(frames)


def obj_vertices(raw: bytes, key: str, path: str) -> np.ndarray:
    """The (V, 3) positions of an OBJ's ``v`` lines, in file order (a fourth number, a weight
    or colours after x y z, are left out)."""
    rows = [words[1:4] for words in map(bytes.split, raw.splitlines())
            if words and words[0] == b"v"]   # as meshfiles reads an OBJ's vertices
    require(len(rows) > 0, key, path, "has no vertex (no 'v x y z' line)")
    try:
        vertices = np.array(rows, float)
    except ValueError:
        vertices = None
    require(vertices is not None and vertices.ndim == 2 and vertices.shape[1] == 3, key, path,
            "has a vertex line that is not at least three numbers ('v x y z')")
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    require(bad.size == 0, key, path,
            f"has vertices that are not finite numbers ({bad.size}; the first is number "
            f"{int(bad[:1].sum())}); fix or remove them")
    return vertices


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
