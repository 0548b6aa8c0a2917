"""Starting polyscope, once per process: a window, or the headless EGL backend (no GPU needed).

polyscope can be initialised only once in a process, so every caller goes through
``start_renderer``: the first call decides window or headless, later calls only resize.
"""
import os
import sys

import numpy as np
import polyscope as ps
import polyscope.imgui as psim

from .colors import BACKGROUND_COLOR

HEADLESS_BACKEND = "openGL3_egl"


class RenderUnavailable(RuntimeError):
    """No OpenGL context could be made: no display for a window, or no EGL for headless."""


def start_renderer(*, headless: bool, width: int, height: int) -> str:
    """Start polyscope (if not started) at ``width`` x ``height`` pixels; return the backend."""
    if ps.is_initialized():
        if ps.is_headless():
            ps.set_window_size(int(width), int(height))
        return ps.get_render_engine_backend_name()
    if not headless and not _has_display():
        # polyscope would fail too, and then complain again at exit: say it once, plainly
        raise RenderUnavailable(_advice(False, "DISPLAY is not set"))
    ps.set_program_name("springsim")
    ps.set_use_prefs_file(False)          # polyscope would otherwise write .polyscope.ini here
    ps.set_errors_throw_exceptions(True)
    ps.set_verbosity(0)                   # errors still raise; progress talk is not wanted
    ps.set_window_size(int(width), int(height))
    try:
        if headless:
            ps.set_allow_headless_backends(True)
            ps.init(HEADLESS_BACKEND)
        else:
            ps.init()
    except RuntimeError as error:
        raise RenderUnavailable(_advice(headless, error)) from error
    psim.GetIO().IniFilename = os.devnull   # ImGui would write imgui.ini into the current folder
    _configure_scene()
    return ps.get_render_engine_backend_name()


def show_frames(headless: bool, frames: int | None = None) -> None:
    """Run polyscope's frame loop: until the window is closed, or for ``frames`` frames (one at
    least when headless, where there is no window to close)."""
    if headless:
        for _ in range(frames or 1):
            ps.frame_tick()
    elif frames is None:
        ps.show()
    else:
        ps.show(frames)


def _configure_scene() -> None:
    ps.set_up_dir("y_up")
    ps.set_front_dir("z_front")
    ps.set_ground_plane_mode("none")      # terrains are drawn as structures of their own
    ps.set_automatically_compute_scene_extents(False)
    ps.set_background_color(BACKGROUND_COLOR)
    ps.set_frame_tick_limit_fps_mode("ignore_limits")
    ps.set_build_default_gui_panels(False)


def _has_display() -> bool:
    if not sys.platform.startswith("linux"):
        return True                      # macOS and Windows always have a screen to open on
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _advice(headless: bool, error: Exception) -> str:
    if headless:
        return (f"headless rendering needs EGL with Mesa (Debian: apt-get install libegl1 "
                f"libegl-mesa0 libgl1-mesa-dri): {error}")
    return (f"no window could be opened ({error}); on a machine without a display use "
            f"`springsim render`, or run the viewer under xvfb-run")


def capture(include_ui: bool = False) -> np.ndarray:
    """Render the current view and return it as an (H, W, 3) uint8 RGB image."""
    rgba = ps.screenshot_to_buffer(transparent_bg=False, include_UI=include_ui)
    return np.ascontiguousarray(rgba[..., :3])
