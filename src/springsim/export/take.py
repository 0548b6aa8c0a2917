"""A take: what every exporter and the replay read, from a recording or an NPZ file.

The frames (times, fps, positions) and the recording's layout (recording_layout.py: bodies and
their surfaces, balls, terrains). ``load_take`` checks a file before anything is exported: one
clear line (SceneError) for a missing file, a file that is not an NPZ, or an NPZ that is not a
springsim recording.
"""
import math
import os
import zipfile
from dataclasses import dataclass, replace

import numpy as np

from ..errors import SceneError, require
from ..file_kinds import NPZ_MAGIC, is_recording_file, names_recording  # noqa: F401
from ..recording_layout import Layout, read_layout
from ..sampling import MAX_FRAMES, check_frame_memory

REQUIRED = ("time", "fps", "positions")
START_FRAME = 1   # an exported take's first frame number: Blender's first frame, Houdini's too
RESAMPLE_ARRAYS = 4   # (F, P, 3) arrays resampling holds at once: two neighbours, two weighted


@dataclass(frozen=True)
class Take:
    name: str
    time: np.ndarray        # (F,) s
    fps: float              # frames per simulated second
    positions: np.ndarray   # (F, P, 3) m
    layout: Layout
    arrays: dict            # everything the recording holds (energies, springs, ...)
    start_frame: int = START_FRAME   # the number an exported file gives the first frame

    @property
    def frame_count(self) -> int:
        return len(self.time)


def take_from_arrays(arrays: dict, name: str | None = None, key: str = "recording") -> Take:
    """A Take from a recording's arrays (``Recording.arrays()`` or an NPZ file's)."""
    missing = [name for name in REQUIRED if name not in arrays]
    require(not missing, key, name or "arrays", "is not a springsim recording (it has no "
            + ", ".join(missing) + " array)")
    positions = np.asarray(arrays["positions"])
    time = np.asarray(arrays["time"], float)
    fps = float(arrays["fps"])
    require(positions.ndim == 3 and positions.shape[2] == 3 and positions.shape[0] >= 1, key,
            name, f"is not a springsim recording: positions has shape {positions.shape}, "
            "not (frames, particles, 3)")
    require(time.shape == (positions.shape[0],), key, name,
            f"is not a springsim recording: {len(time)} times for {positions.shape[0]} frames")
    require(math.isfinite(fps) and fps > 0, key, name, f"has fps = {fps}; must be > 0")
    require(bool(np.all(np.isfinite(positions))), key, name,
            "holds non-finite positions (a diverged run?); nothing to export")
    scene = str(arrays["scene"]) if "scene" in arrays else (name or "take")
    try:
        layout = read_layout(arrays, scene)
    except (KeyError, IndexError, ValueError, TypeError) as error:
        raise SceneError(key, name, f"has a damaged layout ({type(error).__name__}: {error}); "
                         "record it again") from None
    _check_layout(layout, positions.shape[1], key, name)
    return Take(scene, time, fps, positions, layout, arrays)


def load_take(path, key: str = "recording") -> Take:
    """The take in the NPZ file ``path`` written by ``springsim run``."""
    text = os.fspath(path)
    require(os.path.isfile(text), key, text, "no such file; give an NPZ file that "
            "`springsim run` wrote")
    try:
        with np.load(text, allow_pickle=False) as data:
            arrays = {name: data[name] for name in data.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as error:
        raise SceneError(key, text, f"is not an NPZ file that `springsim run` wrote ({error})"
                         ) from None
    return take_from_arrays(arrays, text, key)


def resampled(take: Take, fps: float, duration: float | None = None) -> Take:
    """``take`` at ``fps`` frames per second (frame k at the first frame's time + k / fps) up to
    ``duration`` s after it (default: its last frame): positions interpolated linearly between
    the two recorded frames around each new time; the recorded frames themselves where the
    times are the recording's."""
    require(math.isfinite(fps) and fps > 0, "--fps", fps, "must be > 0")
    start, last = float(take.time[0]), float(take.time[-1])
    span = last - start if duration is None else min(float(duration), last - start)
    # the frame count and its memory are checked from the numbers before any array is made
    require(span * fps < MAX_FRAMES, "--fps", fps, f"makes {span * fps + 1:.3g} frames of the "
            f"{span:g} s take; at most {MAX_FRAMES:,} frames are kept: lower --fps")
    count = int(math.floor(span * fps + 1e-6)) + 1
    check_frame_memory(count, take.positions.shape[1], RESAMPLE_ARRAYS, fps)
    times = start + np.arange(count) / fps
    if count <= take.frame_count and np.allclose(times, take.time[:count], rtol=0, atol=1e-9):
        return replace(take, time=np.asarray(take.time[:count], float), fps=float(fps),
                       positions=take.positions[:count])
    if take.frame_count == 1:
        positions = np.repeat(take.positions[:1], count, axis=0)
    else:
        before = np.clip(np.searchsorted(take.time, times, side="right") - 1, 0,
                         take.frame_count - 2)
        t0, t1 = take.time[before], take.time[before + 1]
        weight = np.clip((times - t0) / np.where(t1 > t0, t1 - t0, 1.0), 0.0, 1.0)[:, None, None]
        positions = (1 - weight) * take.positions[before] + weight * take.positions[before + 1]
    return replace(take, time=times, fps=float(fps), positions=positions)


def _check_layout(layout: Layout, particles: int, key: str, name) -> None:
    """Every particle number the layout holds must lie within the recorded particles."""
    numbers = [layout.ball_particles]
    for body in layout.bodies:
        if body.embedding is not None:
            surface = np.asarray(body.surface)
            require(surface.size == 0 or (surface.min() >= 0
                                          and surface.max() < len(body.embedding.particles)),
                    key, name, f"is not a consistent springsim recording: body {body.name!r} "
                    "numbers embedded vertices it does not have")
        numbers.append(np.asarray([body.start, body.stop - 1]) if body.stop > body.start
                       else np.empty(0, np.int64))
        numbers.append(np.asarray(body.embedding.particles if body.embedding is not None
                                  else body.surface).ravel())
    numbers = np.concatenate([np.asarray(n, np.int64).ravel() for n in numbers])
    require(numbers.size == 0 or (numbers.min() >= 0 and numbers.max() < particles), key, name,
            f"is not a consistent springsim recording: it numbers particles up to "
            f"{numbers.max() if numbers.size else 0} of {particles}")
