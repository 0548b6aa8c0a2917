"""Rendering recorded frames of a simulation to a video (MP4, GIF) or a folder of PNGs, headless."""
import sys

import numpy as np
from tqdm import tqdm

from ..errors import require
from .backend import capture, start_renderer
from .camera import apply_camera
from .follow import camera_path
from .drawing import DrawOptions, SceneDrawing
from .label import stamp_time
from .video import FrameWriter, check_output


def write_video(model, times, positions, path, *, fps=60, width=960, height=540, camera="auto"):
    """Render frames ``positions`` (F, P, 3) at simulated ``times`` (F,) s to ``path``.

    ``path`` ends in .mp4 or .gif, or names a folder for PNG frames; ``camera`` is one of
    ``springsim.render.CAMERA_NAMES``. Returns the path written.
    """
    return render_video(model, times, positions, path, fps=fps, width=width, height=height,
                        camera=camera)


def render_video(model, times, positions, path, *, fps=60, width=960, height=540,
                 camera="auto", draw: DrawOptions | None = None, progress: bool = True):
    """``write_video`` with a choice of what is drawn, and of the progress: a bar on stderr when
    it is a terminal, else one line on stdout (a log gets no bars; stderr keeps to errors)."""
    positions = np.asarray(positions)
    times = np.asarray(times, float)
    require(positions.ndim == 3 and positions.shape[1:] == (model.particle_count, 3),
            "positions", positions.shape, f"must be (frames, {model.particle_count}, 3)")
    require(len(positions) >= 1, "positions", positions.shape, "needs at least one frame")
    require(times.shape == (len(positions),), "times", times.shape,
            f"must hold one time per frame ({len(positions)})")
    check_output(path, width, height, fps)
    cameras = camera_path(camera, model, positions, width / height, times)
    start_renderer(headless=True, width=width, height=height)
    drawing = SceneDrawing(model, draw, positions[0])
    bar = progress and sys.stderr.isatty()
    if progress and not bar:
        print(f"rendering {len(positions)} frames to {path}", flush=True)
    with FrameWriter(path, fps, width, height) as writer:
        for frame in tqdm(range(len(positions)), desc="rendering", unit="frame",
                          disable=not bar, file=sys.stderr):
            image = draw_frame(drawing, cameras[frame], positions[frame], times[frame])
            writer.append(stamp_time(image, times[frame]))
    return writer.path


def draw_frame(drawing: SceneDrawing, camera, positions, time=None) -> np.ndarray:
    """The (H, W, 3) picture of ``positions`` (and the terrains at ``time``, s) seen by
    ``camera``, at the renderer's size."""
    drawing.update(positions, time)
    apply_camera(camera)
    return capture()
