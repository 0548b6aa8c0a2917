"""Simulating a scene for a video: one frame every ``round(1 / (fps dt))`` steps."""
import numpy as np
from tqdm import tqdm

from ..errors import require


def steps_per_frame(dt: float, fps: float) -> int:
    """Whole steps of ``dt`` (s) that come closest to one video frame."""
    steps = int(round(1.0 / (fps * dt)))
    require(steps >= 1, "fps", fps, f"must be at most 1/dt = {1 / dt:g} frames per second")
    return steps


def simulate_frames(sim, duration: float, fps: float, progress: bool = True):
    """Times (F,) and positions (F, P, 3) of ``round(duration * fps)`` frames: the current
    state, then one frame every ``steps_per_frame(dt, fps)`` steps."""
    require(duration > 0, "duration", duration, "must be > 0 s")
    count = max(1, int(round(duration * fps)))
    steps = steps_per_frame(sim.dt, fps)
    positions = np.empty((count, sim.model.particle_count, 3))
    times = np.empty(count)
    for frame in tqdm(range(count), desc="simulating", unit="frame", disable=not progress):
        if frame:
            sim.step(steps)
        positions[frame] = sim.positions
        times[frame] = sim.time
    return times, positions
