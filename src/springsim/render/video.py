"""Writing frames to an MP4, a GIF or a folder of PNGs, whole or not at all.

Frames go to a staged file (or folder) in a private staging folder beside the target
(``springsim.safe_files``), which replaces the target only when the last frame is written and the
writer says it succeeded (ffmpeg's exit status included); an error, Ctrl-C or SIGTERM leaves the
target as it was and no temporary file behind.
"""
import signal
import subprocess
import tempfile
from pathlib import Path

import imageio.v3 as iio
import numpy as np

from .. import sizes
from ..errors import OutputFailed, require
from ..safe_files import StagedOutput, check_output_path
from ..sampling import check_fps

FORMATS = ("mp4", "gif", "png folder")
MIN_SIDE, MAX_SIDE = 16, 8192     # pixels; 8192 is twice 4K, and within every GL's limits
MP4_QUALITY = 15                  # x264's constant rate factor (0 lossless, 51 worst)
BYTES_PER_PIXEL = 100             # peak memory of a render: 8192 x 8192 px took 5.9 GB


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


def check_frame_size(width, height) -> None:
    """Picture sizes every renderer and encoder here can make (said before any OpenGL)."""
    for key, value in (("width", width), ("height", height)):
        require(isinstance(value, int) and not isinstance(value, bool)
                and MIN_SIDE <= value <= MAX_SIDE, key, value,
                f"must be a whole number of pixels from {MIN_SIDE} to {MAX_SIDE}")
    needed, memory = BYTES_PER_PIXEL * width * height, sizes.machine_memory()
    require(memory is None or needed <= memory / 2, "width", width,
            f"a {width} x {height} picture needs about {sizes.gigabytes(needed)} to render; "
            f"this machine has {sizes.gigabytes(memory or 0)} of memory")


def check_output(path, width: int, height: int, fps: float, key: str = "out") -> str:
    """Reject, before any rendering, what the writer could not write."""
    kind = output_format(path, key)
    check_frame_size(width, height)
    check_fps(fps)
    if kind == "mp4":
        for name, value in (("width", width), ("height", height)):
            require(value % 2 == 0, name, value,
                    "must be even for .mp4 (H.264 in the widely playable yuv420p format)")
    check_output_path(key, path, folder=kind == "png folder")
    return kind


class FrameWriter:
    """Append (H, W, 3) uint8 frames; ``close`` finishes the file, ``abort`` discards it.

    Use as a context manager: leaving it by an exception aborts.
    """

    def __init__(self, path, fps: float, width: int, height: int):
        self.kind = check_output(path, width, height, fps)
        self.path, self.fps, self.size = Path(path), float(fps), (height, width)
        self.frames = 0
        self._staged = StagedOutput(self.path, folder=self.kind == "png folder")
        self.temporary = self._staged.path
        try:
            self._writer = self._open()
        except BaseException:
            self._staged.discard()
            raise

    def _open(self):
        if self.kind == "mp4":
            return FfmpegPipe(self.temporary, self.fps, *reversed(self.size))
        if self.kind == "gif":
            return GifFrames(self.temporary, self.fps)
        return None

    def append(self, frame: np.ndarray) -> None:
        frame = np.ascontiguousarray(frame[..., :3], dtype=np.uint8)
        require(frame.shape[:2] == self.size, "frame size", frame.shape[:2],
                f"every frame must be {self.size[1]} x {self.size[0]} px")
        try:
            if self._writer is not None:
                self._writer.write(frame)
            else:
                iio.imwrite(self.temporary / f"frame_{self.frames:05d}.png", frame)
        except OSError as error:
            raise OutputFailed(self.path, error) from None
        self.frames += 1

    def close(self) -> Path:
        try:
            if self._writer is not None:
                writer, self._writer = self._writer, None
                writer.close()
        except OSError as error:
            self._staged.discard()
            raise OutputFailed(self.path, error) from None
        return self._staged.commit()

    def abort(self) -> None:
        if self._writer is not None:
            writer, self._writer = self._writer, None
            try:
                getattr(writer, "kill", writer.close)()
            except Exception:  # the file is discarded anyway; the first error is the one to see
                pass
        self._staged.discard()

    def __enter__(self):
        return self

    def __exit__(self, kind, error, traceback):
        if kind is None:
            self.close()
        else:
            self.abort()
        return False


class GifFrames:
    """A GIF as Pillow writes one: the frames, each with its own 256-colour palette, kept until
    ``close`` saves them in one go (GIF counts time in 10 ms units)."""

    def __init__(self, path: Path, fps: float):
        self.path, self.milliseconds, self.images = path, 1000.0 / fps, []

    def write(self, frame: np.ndarray) -> None:
        from PIL import Image

        self.images.append(Image.fromarray(frame).quantize(colors=256))

    def close(self) -> None:
        images, self.images = self.images, []
        if images:
            images[0].save(self.path, format="GIF", save_all=True, append_images=images[1:],
                           duration=self.milliseconds, loop=0)


class FfmpegPipe:
    """Raw RGB frames piped into ffmpeg (imageio-ffmpeg's binary), H.264 in yuv420p; ``close``
    raises OSError unless ffmpeg exits 0 (a full disk, say), with ffmpeg's own last words."""

    def __init__(self, path: Path, fps: float, width: int, height: int):
        from imageio_ffmpeg import get_ffmpeg_exe

        self._errors = tempfile.TemporaryFile()
        command = [get_ffmpeg_exe(), "-nostdin", "-loglevel", "error", "-f", "rawvideo",
                   "-pix_fmt", "rgb24", "-s", f"{width}x{height}", "-r", f"{fps:.10g}",
                   "-i", "pipe:0", "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                   "-crf", str(MP4_QUALITY), "-movflags", "+faststart", "-f", "mp4",
                   "-y", str(path)]
        self._process = subprocess.Popen(command, stdin=subprocess.PIPE,
                                         stdout=subprocess.DEVNULL, stderr=self._errors)

    def write(self, frame: np.ndarray) -> None:
        try:
            self._process.stdin.write(frame.tobytes())
        except (BrokenPipeError, ValueError):
            self.kill()
            raise OSError(f"ffmpeg stopped: {self._last_words()}") from None

    def close(self) -> None:
        try:
            self._process.stdin.close()
        except BrokenPipeError:
            pass
        status = self._process.wait()
        if status < 0:   # SIGXFSZ: the file grew past the size limit, as on a full disk
            raise OSError(f"ffmpeg was stopped by {signal.Signals(-status).name} "
                          f"({signal.strsignal(-status)}): {self._last_words()}")
        if status != 0:
            raise OSError(f"ffmpeg failed (exit status {status}): {self._last_words()}")
        self._errors.close()

    def kill(self) -> None:
        if self._process.poll() is None:
            self._process.kill()
        self._process.wait()
        with_stdin = self._process.stdin
        if with_stdin and not with_stdin.closed:
            try:
                with_stdin.close()
            except BrokenPipeError:
                pass

    def _last_words(self) -> str:
        self._errors.seek(0)
        lines = self._errors.read().decode(errors="replace").strip().splitlines()
        return lines[-1] if lines else "no message"
