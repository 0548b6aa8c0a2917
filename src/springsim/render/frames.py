"""Simulating a scene for a video: frame k shows the state at time k / fps, to the nearest step."""
import numpy as np
from tqdm import tqdm

from ..errors import require


def simulate_frames(sim, duration: float, fps: float, progress: bool = True):
    """Times (F,) and positions (F, P, 3) of ``round(duration * fps)`` frames (a video of
    ``duration`` s): frame k is the state ``round(k / (fps dt))`` steps after the current one.

    Rounding each frame's own step count, not a fixed number of steps per frame, keeps the video
    in real time when 1 / fps is not a whole number of steps (dt = 1/60 s at 25 fps)."""
    require(duration > 0, "duration", duration, "must be > 0 s")
    require(fps > 0, "fps", fps, "must be > 0 frames per second")
    count = max(1, int(round(duration * fps)))
    positions = np.empty((count, sim.model.particle_count, 3))
    times = np.empty(count)
    done = 0
    for frame in tqdm(range(count), desc="simulating", unit="frame", disable=not progress):
        target = int(round(frame / (fps * sim.dt)))
        sim.step(target - done)
        done = target
        positions[frame] = sim.positions
        times[frame] = sim.time
    return times, positions
