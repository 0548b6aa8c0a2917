"""The Record button: the 3-D view (without the panel) into an MP4 that plays at the speed it
was seen. The window draws frames at whatever rate the machine allows (a few per second on a
software renderer, hundreds on a GPU), so frames are placed by the wall clock: a frame is written
once for each 1/fps of time since the last one (repeated after a slow frame, dropped when frames
come faster than fps)."""
import math
import time
from pathlib import Path

import numpy as np

from ..render.video import FrameWriter

RECORD_FPS = 30.0
LONGEST_STILL = 2.0   # s: a longer pause of the window (a rebuild, say) is cut to this


class ScreenRecorder:
    """Writes frames to ``folder/springsim-<scene>-<date>.mp4``; the file appears, whole, when
    recording stops. Frames are cut to the first frame's size (even, as H.264 needs), so that
    resizing the window while recording does not break the file."""

    def __init__(self, folder=".", fps: float = RECORD_FPS, clock=time.perf_counter):
        self.folder, self.fps, self.clock = Path(folder), fps, clock
        self.writer = None
        self.path = None
        self.frames = 0          # frames written
        self.timeline = 0.0      # clock reading at which the video's first frame was drawn
        self.last_message = ""

    @property
    def recording(self) -> bool:
        return self.path is not None

    def start(self, scene_name: str) -> None:
        stamp = time.strftime("%Y%m%d-%H%M%S")
        self.path = self.folder / f"springsim-{scene_name}-{stamp}.mp4"
        self.frames = 0
        self.last_message = f"recording to {self.path}"

    def add(self, frame: np.ndarray) -> None:
        if not self.recording:
            return
        now = self.clock()
        if self.writer is None:
            height, width = (frame.shape[0] // 2) * 2, (frame.shape[1] // 2) * 2
            self.writer = FrameWriter(self.path, self.fps, width, height)
            self.timeline = now
        # frames the video should have by now (the 1e-6 keeps t = k / fps from rounding to k - 1)
        due = math.floor((now - self.timeline) * self.fps + 1e-6) + 1
        longest = int(LONGEST_STILL * self.fps)
        if due - self.frames > longest:
            self.timeline += (due - self.frames - longest) / self.fps   # cut the pause short
            due = self.frames + longest
        frame = fit(frame, *self.writer.size)
        for _ in range(due - self.frames):
            self.writer.append(frame)
            self.frames += 1

    def stop(self) -> Path | None:
        """Finish the file; the path written, or None if no frame was recorded."""
        written = None
        if self.writer is not None:
            written = self.writer.close()
            self.last_message = f"wrote {written} ({self.frames} frames)"
        self.writer, self.path = None, None
        return written


def fit(frame: np.ndarray, height: int, width: int) -> np.ndarray:
    """Cut the frame to (height, width), padding with its edge colour where it is smaller."""
    frame = frame[:height, :width]
    pad = ((0, height - frame.shape[0]), (0, width - frame.shape[1]), (0, 0))
    return np.pad(frame, pad, mode="edge") if any(p[1] for p in pad) else frame
