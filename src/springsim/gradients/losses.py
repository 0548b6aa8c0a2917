"""Losses on the simulated positions, each with its gradient with respect to them.

A loss says which steps it reads (``frame_steps``), checks itself against the model before any
work (``check``: one clear line), and maps the positions at those steps (F, P, 3) to
(value, gradient). Three kinds:

- ``ObservedTake``: every particle at every frame of a springsim NPZ take (``springsim run``
  writes one), compared at the take's own times: the mean squared distance (m^2).
- ``MarkerTracks``: a CSV of ``time, marker, x, y, z`` rows (motion capture, video tracking;
  a marker missing at a time is a gap, simply absent), each marker tied to a particle by index
  (``match="index"``: the marker is the particle's number) or to the particle nearest its first
  observation in the initial positions (``match="nearest"``, within ``match_distance`` m): the
  mean squared distance over the observations (m^2).
- ``FunctionLoss``: a user's function of the positions at ``fps`` frames, returning (value,
  gradient), or the value alone, then differentiated by central differences of its own inputs
  (cheap for a small model; a large one should give its gradient).
"""
import csv
import math
import warnings
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ..errors import SceneError, require

TIME_MATCH = 1e-6   # of a step: how near a whole step an observed time must be


def steps_of(times, dt, key):
    """The step of each time (a whole number of steps from the start), or a clear error."""
    steps = np.rint(np.asarray(times, float) / dt)
    off = np.abs(steps * dt - times) > TIME_MATCH * dt + 1e-12
    if off.any():
        k = int(np.argmax(off))
        raise SceneError(key, f"time {float(times[k])!r} s",
                         f"is not a whole number of steps of dt = {dt:g} s: choose a dt that "
                         "divides the observed times (the take's time base)")
    return steps.astype(np.int64)


class ShorterLastStep(UserWarning):
    """A take's last frame follows a step shorter than dt (the run ended at its duration, which
    dt does not divide) and is left out of the comparison."""


def after_a_shorter_step(times, dt) -> bool:
    """Whether the last of ``times`` is off the step grid of ``dt`` with no whole step between it
    and the frame before: the last frame `springsim run` records when dt does not divide the
    duration, after a shorter step (recording.last_steps)."""
    times = np.asarray(times, float)
    if len(times) < 2:
        return False
    last, tolerance = float(times[-1]), TIME_MATCH * dt + 1e-12
    whole = math.floor(last / dt + TIME_MATCH) * dt
    return last - whole > tolerance and whole >= float(times[-2]) - tolerance


def read_take(path, source: str) -> dict:
    """The time, positions and fps of the NPZ take at ``path``; one line, not a traceback, for a
    file that is missing, empty, truncated or corrupt, or not an NPZ file at all."""
    require(Path(path).is_file(), "--observed", source,
            "must be an NPZ take (springsim run writes one) that exists")
    try:
        if zipfile.is_zipfile(path):   # NumPy reads an array without checking its CRC
            with zipfile.ZipFile(path) as archive:
                damaged = archive.testzip()
            require(damaged is None, "--observed", source, f"is a corrupt NPZ take: its "
                    f"{damaged!r} fails its checksum (a damaged copy? record it again)")
        loaded = np.load(path, allow_pickle=False)
        if isinstance(loaded, np.lib.npyio.NpzFile):
            with loaded:
                return {key: loaded[key] for key in ("time", "positions", "fps") if key in loaded}
    except SceneError:
        raise
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as error:
        raise SceneError("--observed", source, "is not an NPZ take (springsim run writes one): "
                         + (str(error) or type(error).__name__)) from None
    raise SceneError("--observed", source, "is an .npy array, not an NPZ take (springsim run "
                     "writes one)")


class ObservedTake:
    def __init__(self, path_or_arrays):
        self.source = str(path_or_arrays) if not isinstance(path_or_arrays, dict) else "take"
        if isinstance(path_or_arrays, dict):
            arrays = path_or_arrays
        else:
            arrays = read_take(path_or_arrays, self.source)
        require("time" in arrays and "positions" in arrays, "--observed", self.source,
                "must hold 'time' (F,) and 'positions' (F, P, 3), as springsim run writes")
        # the frame rate `run` recorded at, where the take says it: the time base a --dt that
        # rounds a frame's step is read against (commands/run.on_frames)
        fps = np.asarray(arrays.get("fps", np.nan), float)
        self.fps = float(fps) if fps.shape == () and np.isfinite(fps) and fps > 0 else None
        require(all(np.asarray(arrays[key]).dtype.kind in "biuf" for key in ("time", "positions")),
                "--observed", self.source, "must hold numbers in 'time' and 'positions'")
        self.time = np.asarray(arrays["time"], float)
        self.positions = np.asarray(arrays["positions"], float)
        require(self.positions.ndim == 3 and self.positions.shape[2] == 3
                and self.positions.shape[0] == self.time.shape[0] and len(self.time) > 0,
                "--observed", self.source, "must have positions (F, P, 3) for its F times")
        require(np.all(np.isfinite(self.positions)) and np.all(np.isfinite(self.time)),
                "--observed", self.source, "holds NaN or infinite values")
        require(np.all(self.time >= 0), "--observed", self.source, f"has the time "
                f"{float(np.min(self.time))!r} s: the run starts at 0 s, so a frame's time must "
                "be >= 0 s")
        self.compared = len(self.time)   # the frames compared (check leaves one out)

    def check(self, model, duration, dt):
        count = model.particle_count
        require(self.positions.shape[1] == count, "--observed", self.source,
                f"has {self.positions.shape[1]} particles; the scene has {count}")
        require(self.time[-1] <= duration + 1e-9, "--observed", self.source,
                f"ends at {self.time[-1]:g} s, after the run's {duration:g} s")
        # a take `run` recorded over a duration that dt does not divide ends after a shorter
        # step, which a fit (whole steps of dt) does not take: its last frame is left out, said
        self.compared = len(self.time) - after_a_shorter_step(self.time, dt)
        steps_of(self.time[:self.compared], dt, "--observed")
        if self.compared < len(self.time):
            from ..scenefile import user_stacklevel
            warnings.warn(f"{self.source}: the last frame, at {self.time[-1]:g} s, follows a "
                          f"step shorter than dt = {dt:g} s (the run ended at its duration): "
                          f"compared at the {self.compared} frames before it, on whole steps",
                          ShorterLastStep, stacklevel=user_stacklevel())

    def frame_steps(self, duration, dt, particles):
        return steps_of(self.time[:self.compared], dt, "--observed")

    def __call__(self, frames):
        difference = frames - self.positions[:self.compared]
        count = difference.shape[0] * difference.shape[1]
        return (float(np.sum(difference * difference)) / count, 2.0 * difference / count)


class MarkerTracks:
    def __init__(self, path, match="nearest", match_distance=None):
        require(match in ("nearest", "index"), "--match", match, "must be nearest or index")
        self.source, self.match, self.match_distance = str(path), match, match_distance
        require(Path(path).is_file(), "--observed", self.source, "must be a CSV file that exists")
        try:
            rows = self._rows(path)
        except UnicodeDecodeError:
            raise SceneError("--observed", self.source, "is not a text file (not UTF-8): give a "
                             "CSV of time,marker,x,y,z rows") from None
        except csv.Error as error:
            raise SceneError("--observed", self.source, f"is not a CSV file ({error}): give "
                             "time,marker,x,y,z rows") from None
        require(len(rows) > 0, "--observed", self.source, "has no observations")
        self.time = np.array([r[0] for r in rows])
        self.marker = [r[1] for r in rows]
        self.observed = np.array([r[2:] for r in rows])

    def _rows(self, path) -> list:
        """(time, marker, x, y, z) of every row, each checked."""
        rows = []
        with open(path, newline="", encoding="utf-8") as file:
            reader = csv.reader(file)
            header = [cell.strip().lower() for cell in next(reader, [])]
            require(header[:5] == ["time", "marker", "x", "y", "z"], "--observed", self.source,
                    "must start with the header time,marker,x,y,z")
            for number, row in enumerate(reader, start=2):
                if row:
                    rows.append(self._row(row, f"{self.source} line {number}"))
        return rows

    @staticmethod
    def _row(row, where: str) -> tuple:
        try:
            t, marker, x, y, z = float(row[0]), row[1].strip(), *map(float, row[2:5])
        except (ValueError, IndexError):
            raise SceneError("--observed", where, "must be time,marker,x,y,z with numbers for "
                             "time, x, y, z") from None
        require(all(math.isfinite(c) for c in (t, x, y, z)), "--observed", where,
                "holds NaN or infinite values")
        require(t >= 0, "--observed", where, f"has the time {t!r} s: the run starts at 0 s, so "
                "an observation's time must be >= 0 s")
        return t, marker, x, y, z

    def check(self, model, duration, dt):
        names = list(dict.fromkeys(self.marker))
        initial = model.initial_positions
        particle = {}
        if self.match == "index":
            for name in names:
                require(name.isdigit() and int(name) < model.particle_count, "marker", name,
                        f"matches no particle: with --match index a marker is a particle "
                        f"number from 0 to {model.particle_count - 1}")
                particle[name] = int(name)
        else:
            reach = self.match_distance
            if reach is None:   # half the shortest spring: a marker between two is ambiguous
                reach = 0.5 * float(np.min(model.arrays.rest_length)) if len(
                    model.arrays.rest_length) else np.inf
            for name in names:
                first = self.observed[self.marker.index(name)]
                distance = np.linalg.norm(initial - first, axis=1)
                nearest = int(np.argmin(distance))
                require(distance[nearest] <= reach, "marker", name,
                        f"matches no particle: its first observation is {distance[nearest]:.3g} m "
                        f"from the nearest (particle {nearest}), more than {reach:.3g} m")
                particle[name] = nearest
        require(np.max(self.time) <= duration + 1e-9, "--observed", self.source,
                f"ends at {np.max(self.time):g} s, after the run's {duration:g} s")
        self.particles = np.array([particle[m] for m in self.marker])
        steps = steps_of(self.time, dt, "--observed")
        self.unique_steps, self.row_frame = np.unique(steps, return_inverse=True)

    def frame_steps(self, duration, dt, particles):
        return self.unique_steps

    def __call__(self, frames):
        simulated = frames[self.row_frame, self.particles]
        difference = simulated - self.observed
        count = len(difference)
        gradient = np.zeros_like(frames)
        np.add.at(gradient, (self.row_frame, self.particles), 2.0 * difference / count)
        return float(np.sum(difference * difference)) / count, gradient


class FunctionLoss:
    def __init__(self, function, fps=None):
        self.function = function
        self.fps = 60.0 if fps is None else fps

    def check(self, model, duration, dt):
        from ..sampling import check_fps
        check_fps(self.fps)

    def frame_steps(self, duration, dt, particles):
        from ..sampling import frame_steps
        return frame_steps(duration, self.fps, dt, particles)

    def __call__(self, frames):
        answer = self.function(frames)
        if isinstance(answer, tuple):
            require(len(answer) == 2, "loss", f"a tuple of {len(answer)}",
                    "must return a number, or (value, gradient)")
            value, grad = answer
            require(np.asarray(grad).dtype.kind in "biuf", "loss",
                    f"a gradient of {type(grad).__name__}",
                    f"must be an array of numbers of the positions' shape {frames.shape}")
            grad = np.asarray(grad, float)
            require(grad.shape == frames.shape, "loss", f"a gradient of shape {grad.shape}",
                    f"must have the positions' shape {frames.shape}")
            return loss_value(value), grad
        value = loss_value(answer)
        grad = np.zeros_like(frames)
        flat, out = frames.reshape(-1), grad.reshape(-1)
        for k in range(flat.size):   # central differences of the loss's own inputs only
            step = 1e-6 * max(1.0, abs(flat[k]))
            keep = flat[k]
            flat[k] = keep + step
            plus = loss_value(self.function(frames))
            flat[k] = keep - step
            minus = loss_value(self.function(frames))
            flat[k] = keep
            out[k] = (plus - minus) / (2 * step)
        return value, grad


def loss_value(value) -> float:
    """A loss function's value as a float: a real number (a Python or NumPy scalar, or a 0-d
    array), never a string that float() would read."""
    number = np.asarray(value) if not isinstance(value, (str, bytes)) else None
    require(number is not None and number.shape == () and number.dtype.kind in "iuf", "loss",
            value if len(repr(value)) <= 40 else f"a {type(value).__name__}",
            "must return a real number (the loss), or (value, gradient)")
    return float(number)


def as_loss(loss, fps=None):
    if isinstance(loss, (ObservedTake, MarkerTracks, FunctionLoss)):
        return loss
    if callable(loss):
        return FunctionLoss(loss, fps)
    raise SceneError("loss", type(loss).__name__, "must be an ObservedTake, MarkerTracks or a "
                     "function of the positions (F, P, 3)")


def observed(path, match="nearest"):
    """The loss for an observed file: an NPZ take or a marker CSV, by its suffix."""
    suffix = Path(str(path)).suffix.lower()
    if suffix == ".npz":
        return ObservedTake(path)
    if suffix == ".csv":
        return MarkerTracks(path, match)
    raise SceneError("--observed", str(path), "must be an NPZ take (.npz) or a marker CSV (.csv)")
