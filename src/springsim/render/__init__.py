"""Drawing simulations with polyscope: shared by the interactive viewer and headless video.

``write_video(model, times, positions, path)`` renders recorded frames to .mp4, .gif or a folder
of PNGs with no display and no GPU (polyscope's EGL backend on Mesa). polyscope is imported
only when this package is.
"""
from .. import signals

# polyscope's C++ module init aborts the process (SIGABRT) when an exception is raised while it
# runs: a Ctrl-C during the import waits for it to end (signals.py)
with signals.deferred():
    import polyscope
    import polyscope.imgui  # noqa: F401

from .backend import RenderUnavailable, capture, start_renderer
from .camera import Camera, apply_camera, frame_points, scene_points
from .follow import CAMERA_NAMES, camera_path, start_camera, still_camera
from .drawing import DrawOptions, SceneDrawing
from .movie import draw_frame, render_video, write_video
from .frames import simulate_frames
from .video import FrameWriter, output_format

__all__ = ["write_video", "render_video", "draw_frame", "DrawOptions", "SceneDrawing",
           "Camera",
           "CAMERA_NAMES", "camera_path", "frame_points", "scene_points", "apply_camera",
           "start_camera", "still_camera",
           "start_renderer", "capture", "RenderUnavailable", "FrameWriter", "output_format",
           "simulate_frames"]
