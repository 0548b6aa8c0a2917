"""Writing frames to an MP4, a GIF or a folder of PNGs, whole or not at all.

Frames go to a temporary file (or folder) beside the target, which replaces the target only when
the last frame is written; an error or an interrupt leaves the target as it was.
"""
import os
from pathlib import Path

import imageio.v2 as imageio_v2
import imageio.v3 as iio
import numpy as np

from ..errors import require

FORMATS = ("mp4", "gif", "png folder")


def output_format(path, key: str = "out") -> str:
    """``mp4``, ``gif`` or ``png folder`` (a path with no suffix, or an existing folder);
    ``key`` names the option in the error."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".mp4", ".gif"):
        return suffix[1:]
    require(suffix == "" or path.is_dir(), key, str(path),
            "must end in .mp4 or .gif, or name a folder for PNG frames")
    return "png folder"


def check_output(path, width: int, height: int, fps: float) -> str:
    """Reject, before any rendering, what the writer could not write."""
    kind = output_format(path)
    require(isinstance(width, int) and width >= 16, "width", width, "must be an integer >= 16 px")
    require(isinstance(height, int) and height >= 16, "height", height,
            "must be an integer >= 16 px")
    require(fps > 0, "fps", fps, "must be > 0 frames per second")
    if kind == "mp4":
        for key, value in (("width", width), ("height", height)):
            require(value % 2 == 0, key, value,
                    "must be even for .mp4 (H.264 in the widely playable yuv420p format)")
    path = Path(path)
    require(path.parent.is_dir() or str(path.parent) == "", "out", str(path),
            f"its folder {path.parent} does not exist")
    if kind == "png folder" and path.exists():
        require(path.is_dir() and not any(path.iterdir()), "out", str(path),
                "must be a new or empty folder for PNG frames")
    return kind


class FrameWriter:
    """Append (H, W, 3) uint8 frames; ``close`` finishes the file, ``abort`` discards it.

    Use as a context manager: leaving it by an exception aborts.
    """

    def __init__(self, path, fps: float, width: int, height: int):
        self.kind = check_output(path, width, height, fps)
        self.path, self.fps, self.size = Path(path), float(fps), (height, width)
        self.frames = 0
        self.temporary = self.path.with_name(f".{self.path.name}.partial-{os.getpid()}"
                                             + ("" if self.kind == "png folder"
                                                else self.path.suffix))
        self._writer = self._open()

    def _open(self):
        if self.kind == "mp4":
            return imageio_v2.get_writer(
                self.temporary, format="FFMPEG", mode="I", fps=self.fps, codec="libx264",
                quality=7, pixelformat="yuv420p", macro_block_size=1, ffmpeg_log_level="error",
                output_params=["-movflags", "+faststart"])
        if self.kind == "gif":
            return iio.imopen(self.temporary, "w", extension=".gif", plugin="pillow")
        self.temporary.mkdir()
        return None

    def append(self, frame: np.ndarray) -> None:
        frame = np.ascontiguousarray(frame[..., :3], dtype=np.uint8)
        require(frame.shape[:2] == self.size, "frame size", frame.shape[:2],
                f"every frame must be {self.size[1]} x {self.size[0]} px")
        if self.kind == "mp4":
            self._writer.append_data(frame)
        elif self.kind == "gif":
            # 8 bits: each frame gets its own 256-colour palette; GIF counts time in 10 ms units
            self._writer.write(frame, duration=1000.0 / self.fps, loop=0, bits=8)
        else:
            iio.imwrite(self.temporary / f"frame_{self.frames:05d}.png", frame)
        self.frames += 1

    def close(self) -> Path:
        if self._writer is not None:
            self._writer.close()
            self._writer = None
        os.replace(self.temporary, self.path)
        return self.path

    def abort(self) -> None:
        if self._writer is not None:
            try:
                self._writer.close()
            except Exception:  # the file is discarded anyway; the first error is the one to see
                pass
            self._writer = None
        if self.temporary.is_dir():
            for file in self.temporary.iterdir():
                file.unlink()
            self.temporary.rmdir()
        elif self.temporary.exists():
            self.temporary.unlink()

    def __enter__(self):
        return self

    def __exit__(self, kind, error, traceback):
        if kind is None:
            self.close()
        else:
            self.abort()
        return False
