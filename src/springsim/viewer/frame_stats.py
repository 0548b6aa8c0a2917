"""Live figures of the viewer: frames per second, steps per second and the real-time factor."""
from dataclasses import dataclass


@dataclass
class FrameStats:
    """Rates over the last whole window of ``window`` seconds of wall-clock time (over the time
    so far until the first window is complete), so that the figures are steady enough to read."""

    window: float = 0.5
    fps: float = 0.0
    steps_per_second: float = 0.0
    real_time_factor: float = 0.0   # simulated seconds per wall-clock second

    def __post_init__(self):
        self._start = None            # wall time at which the current window began
        self._counts = [0, 0, 0.0]    # frames, steps and simulated seconds since then
        self._complete = False

    def frame(self, now: float, steps: int, sim_seconds: float) -> None:
        """Count one drawn frame, shown at wall time ``now`` (s), for which the simulation took
        ``steps`` steps and advanced ``sim_seconds``."""
        if self._start is None:
            self._start = now         # the first frame only starts the clock
            return
        self._counts[0] += 1
        self._counts[1] += steps
        self._counts[2] += sim_seconds
        elapsed = now - self._start
        if elapsed <= 0:
            return
        if elapsed >= self.window or not self._complete:
            frames, steps_done, simulated = self._counts
            self.fps = frames / elapsed
            self.steps_per_second = steps_done / elapsed
            self.real_time_factor = simulated / elapsed
        if elapsed >= self.window:
            self._start, self._counts, self._complete = now, [0, 0, 0.0], True

    def restart(self) -> None:
        self.__post_init__()
