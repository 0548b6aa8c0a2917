"""The replay's clock: which recorded frame to show, as plain Python (no window), so that the
panel's buttons and the browser's controls are tested by calling these methods.

Playing, the recording's own time runs ``speed`` times as fast as the wall clock, and the frame
shown is the last one recorded at or before that time (the recorded ``time`` array, so frames
that are not evenly spaced still play at their pace). At the end it starts over when ``loop`` is
on, and stops on the last frame otherwise.
"""
import time as clock

import numpy as np

SPEEDS = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0)   # the panel's choices; any speed > 0 works


class Timeline:
    def __init__(self, times, *, speed: float = 1.0, loop: bool = True):
        self.times = np.asarray(times, float)
        self.frame = 0
        self.playing = False
        self.loop = loop
        self.speed = float(speed)
        self._clock_start = None     # wall-clock time at which the shown time was ``_played``
        self._played = float(self.times[0])

    @property
    def frame_count(self) -> int:
        return len(self.times)

    @property
    def time(self) -> float:
        """The recorded time (s) of the frame shown."""
        return float(self.times[self.frame])

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0])

    # --- the buttons --------------------------------------------------------------------------
    def play(self, now: float | None = None) -> None:
        if self.frame == self.frame_count - 1:
            self.seek(0)                 # play at the end starts again
        self.playing = True
        self._restart_clock(now)

    def pause(self) -> None:
        self.playing = False

    def toggle(self, now: float | None = None) -> None:
        self.pause() if self.playing else self.play(now)

    def seek(self, frame: int, now: float | None = None) -> None:
        """Show ``frame`` (clamped to the recording); playing goes on from there."""
        self.frame = int(np.clip(frame, 0, self.frame_count - 1))
        self._restart_clock(now)

    def step(self, frames: int = 1) -> None:
        """Pause and move ``frames`` frames (negative: back)."""
        self.pause()
        self.seek(self.frame + frames)

    def set_speed(self, speed: float, now: float | None = None) -> None:
        """From now on, play ``speed`` times as fast as the wall clock (the time played so far
        is kept)."""
        if speed > 0:
            if self.playing and self._clock_start is not None:
                now = clock.perf_counter() if now is None else now
                self._played += (now - self._clock_start) * self.speed
                self._clock_start = now
            self.speed = float(speed)

    # --- every drawn frame --------------------------------------------------------------------
    def advance(self, now: float | None = None) -> int:
        """Move the frame on by the wall time passed since the last call; the frame to show."""
        if not self.playing or self.frame_count == 1:
            self.playing = False
            return self.frame
        now = clock.perf_counter() if now is None else now
        if self._clock_start is None:
            self._restart_clock(now)
        played = self._played + (now - self._clock_start) * self.speed
        end = self.times[-1]
        if played > end:
            if self.loop and self.duration > 0:
                played = self.times[0] + (played - self.times[0]) % self.duration
                self._played, self._clock_start = played, now
            else:
                self.frame = self.frame_count - 1
                self.playing = False
                return self.frame
        self.frame = int(np.searchsorted(self.times, played, side="right") - 1)
        return self.frame

    def _restart_clock(self, now: float | None) -> None:
        self._played = self.time
        self._clock_start = None if now is None else now
