"""Simulating a scene frame by frame and keeping the positions to render afterwards."""
import numpy as np
from tqdm import tqdm

from ..errors import require


def steps_per_frame(dt: float, fps: float) -> int:
    """Whole steps of ``dt`` (s) that come closest to one video frame."""
    steps = int(round(1.0 / (fps * dt)))
    require(steps >= 1, "fps", fps, f"must be at most 1/dt = {1 / dt:g} frames per second")
    return steps


def record(sim, duration: float, fps: float, progress: bool = True):
    """Positions (F, P, 3) and times (F,) of ``round(duration * fps)`` frames, the first one
    being the current state, each next one ``steps_per_frame`` steps later."""
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
