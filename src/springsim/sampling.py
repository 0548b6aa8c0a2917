"""The one frame sampler: which states a recording, a video or a replay keeps.

One rule for every command (``run``, ``render``, ``run --video``, export): ``duration`` and
``fps`` are finite and > 0; frame k is the state after ``round(k / (fps dt))`` steps for
k = 0 .. floor(duration fps), plus a last frame at ``duration`` when it falls between two (so a
recording ends where it was asked to; ``recording.record`` takes whole steps up to the duration
and a shorter last one that ends exactly there when dt does not divide it). Each frame is a whole number of steps from the start, not a
fixed number of steps per frame, so the frames stay within dt/2 of k/fps (a video stays in real
time at dt = 1/60 s and 25 fps). When 1/fps is shorter than dt neighbouring frames repeat a state:
the frame count, and so a video's pace, stays that of the fps asked for.

A dt that is a frame's step written to a few digits (0.016667 for 1/60 s, 0.033333 for 1/30 s)
is taken as that step exactly (``frame_step``): frames then fall on whole steps at the exact
frame times, and a take that ``run`` writes lies on the step grid that ``fit`` compares it on.

The frame count and the memory the frames need are checked from these numbers alone, before any
array is made, and refused with one line naming the value, the estimate and the machine's memory.
"""
import math

import numpy as np

from .errors import require
from . import sizes

MAX_FRAMES = 1_000_000        # 4.6 hours at 60 fps; more would take hours to record or draw
FRAME_MEMORY_SHARE = 0.5      # of the machine's memory, for the kept frames
MAX_STEPS = 2 ** 53           # steps are counted exactly in float64
# The fewest significant digits a dt must be written with to be read as a rounded frame step:
# 0.0167 is 1/60 s to 0.2 %, but 0.02 is not meant as 1/60 s (20 % off)
ROUNDED_STEP_DIGITS = 3
# The most steps a frame (or frames a step) a rounded dt is read as a whole fraction of: past
# it, 3 digits would match some 1/(n fps) by chance (0.000125 s, 1/8000 s, is 1/(133 * 60) s
# to 3 digits)
MOST_FRAME_PARTS = 4


def frame_count(duration: float, fps: float, dt: float) -> int:
    """How many frames ``duration`` s at ``fps`` make (checked: one rule for every command)."""
    check_fps(fps)
    check_duration(duration)
    require(duration / dt < MAX_STEPS, "dt", dt,
            f"is too small for a {duration:g} s run (more than 2^53 steps): use a larger dt")
    intervals = math.floor(duration * fps + 1e-9)   # 1e-9: 8 s * 60 fps is 480 intervals
    require(intervals < MAX_FRAMES, "fps", fps,
            f"makes {intervals + 1:.3g} frames in {duration:g} s; at most {MAX_FRAMES:,} frames "
            f"are kept: lower fps or duration")
    return intervals + 1 + int(duration - intervals / fps > dt / 2)


def frame_step(dt: float, fps: float) -> float:
    """``dt``, or the whole fraction or multiple of a frame, 1/(n fps) or m/fps, that it is
    when written to its own significant digits (at least ROUNDED_STEP_DIGITS of them; n and m
    at most MOST_FRAME_PARTS):
    0.016667 at 60 fps (or 30) is 1/60 s exactly, 0.033333 at 60 fps is 2/60 s."""
    ratio = dt * fps
    if not 1 / (MOST_FRAME_PARTS + 0.5) < ratio < MOST_FRAME_PARTS + 0.5:
        return dt
    parts = round(1 / ratio) if ratio < 1 else round(ratio)
    exact = 1 / (fps * parts) if ratio < 1 else parts / fps
    digits = significant_digits(dt)
    if digits >= ROUNDED_STEP_DIGITS and float(f"{exact:.{digits - 1}e}") == dt:
        return exact
    return dt


def significant_digits(value: float) -> int:
    """The significant digits of the shortest decimal that reads back as ``value``."""
    return next(d for d in range(1, 18) if float(f"{value:.{d - 1}e}") == value)


def check_duration(duration) -> None:
    require(_finite_number(duration) and duration > 0, "duration", duration,
            "must be a finite time > 0 s")


def check_fps(fps) -> None:
    require(_finite_number(fps) and fps > 0, "fps", fps,
            "must be a finite number of frames per simulated second > 0")


def check_frame_memory(frames: int, particles: int, arrays: int, fps: float) -> None:
    """Refuse frames that will not fit: ``arrays`` (F, P, 3) float64 arrays of them."""
    needed = arrays * frames * particles * 3 * 8 + 8 * frames * 8
    memory = sizes.machine_memory()
    if memory is None:
        return   # no way to tell on this system; let NumPy try
    require(needed <= FRAME_MEMORY_SHARE * memory, "fps", fps,
            f"keeping {frames:,} frames of {particles:,} particles needs about "
            f"{sizes.gigabytes(needed)}; this machine has {sizes.gigabytes(memory)} of memory: "
            f"lower fps or duration (`springsim bench` times large models without recording them)")


def plan_frames(duration: float, fps: float, dt: float, particles: int,
                arrays: int = 2) -> int:
    """The frame count, with the count and its memory checked (``arrays`` per frame)."""
    frames = frame_count(duration, fps, dt)
    check_frame_memory(frames, particles, arrays, fps)
    return frames


def frame_steps(duration: float, fps: float, dt: float, particles: int = 0,
                arrays: int = 2) -> np.ndarray:
    """The step count of each frame, counted from the state the frames start from."""
    frames = plan_frames(duration, fps, dt, particles, arrays)
    intervals = math.floor(duration * fps + 1e-9)
    times = np.arange(intervals + 1) / fps
    if frames > intervals + 1:
        times = np.append(times, duration)          # a last, shorter interval ends at duration
    return np.rint(times / dt).astype(np.int64)


def _finite_number(value) -> bool:
    return (isinstance(value, (int, float, np.number)) and not isinstance(value, bool)
            and math.isfinite(value))
