"""The viewer: a polyscope window (or a headless context, for tests) with the control panel.

Every frame: the panel, the mouse, one frame of simulation, then the drawing follows the state.
The window stays open when the simulation diverges; the panel says so in red.
"""
import numpy as np
import polyscope as ps
import polyscope.imgui as psim

from ..render.backend import capture, show_frames, start_renderer
from ..render.camera import apply_camera
from ..render.follow import start_camera
from ..render.drawing import SceneDrawing
from .mouse_spring import nearest_particle, point_on_drag_plane
from .panel import WIDTH as PANEL_WIDTH, Panel
from .recorder import ScreenRecorder

MOUSE_SPRING_NAME = "mouse spring"
PANEL_SPACE = PANEL_WIDTH + 20          # pixels on the left that the panel covers


class Viewer:
    def __init__(self, controls, *, headless: bool = False, width: int = 1280,
                 height: int = 800, record_folder="."):
        self.controls = controls
        controls.compile_in_background = True   # a compile must not freeze the window
        self.headless = headless
        self.backend = start_renderer(headless=headless, width=width, height=height)
        self.recorder = ScreenRecorder(record_folder)
        self.panel = Panel(controls, self)
        self.drawing = None
        self._drawn_version = -1
        self._drag_plane = None          # (point, normal) in which the held particle is pulled
        ps.set_open_imgui_window_for_user_callback(False)
        ps.set_user_callback(self.frame)
        self._follow_controls()

    # --- the frame ------------------------------------------------------------------------
    def frame(self) -> None:
        """polyscope's per-frame callback."""
        self.panel.build()
        self._handle_mouse()
        self.controls.advance_frame()
        self._follow_controls()
        if self.recorder.recording:
            self.recorder.add(capture())

    def _follow_controls(self) -> None:
        c = self.controls
        if c.version != self._drawn_version:
            self.drawing = SceneDrawing(c.sim.model, c.draw, c.sim.positions)
            self._drawn_version = c.version
        else:
            self.drawing.update(c.sim.positions, c.sim.time)
        if c.reframe:
            self.look("auto")
            c.reframe = False
        self._draw_mouse_spring()

    def run(self, frames: int | None = None) -> None:
        """Show the window until it is closed, or for ``frames`` frames."""
        show_frames(self.headless, frames)

    def close(self):
        """Finish a recording still under way; the path it was written to, if any."""
        return self.recorder.stop() if self.recorder.recording else None

    # --- what the panel asks for ----------------------------------------------------------
    def look(self, view: str) -> None:
        """Frame what moves as it is now from one of the named directions (``auto``: facing the
        side of the bodies the terrains moving with them leave open)."""
        width, height = ps.get_window_size()
        height = max(height, 1)
        panel = min(PANEL_SPACE, width // 2)     # keep the scene clear of the panel
        c = self.controls
        camera = start_camera(view, c.sim.model, c.sim.positions, (width - panel) / height,
                              c.sim.time)
        apply_camera(camera.shifted(panel / 2, height))

    def set_drawn(self, name: str, shown: bool) -> None:
        setattr(self.controls.draw, name, shown)
        self.drawing.apply_options(self.controls.draw)

    def start_recording(self) -> None:
        self.recorder.start(self.controls.scene_name)

    def stop_recording(self):
        return self.recorder.stop()

    # --- pulling a particle ---------------------------------------------------------------
    def _handle_mouse(self) -> None:
        io = psim.GetIO()
        c = self.controls
        if self._drag_plane is not None and not c.mouse.holding:
            self.let_go()                # the controls let go (a reset, a divergence)
        if c.mouse.holding:
            if psim.IsMouseDown(0):
                self.pull_at(io.MousePos)
            else:
                self.let_go()
        elif io.KeyCtrl and psim.IsMouseClicked(0) and not io.WantCaptureMouse:
            self.grab_at(io.MousePos)

    def grab_at(self, screen_xy) -> int:
        """Take hold of the particle under the screen point; its number, or -1 if none."""
        hit = ps.pick(screen_coords=tuple(screen_xy))
        if not hit.is_hit:
            return -1
        c = self.controls
        particle = nearest_particle(c.sim.positions, hit.position, 3.0 * self.drawing.spacing)
        if particle < 0:
            return -1
        anchor = c.sim.positions[particle].copy()
        look = np.asarray(ps.get_view_camera_parameters().get_look_dir(), float)
        self._drag_plane = (anchor, look)
        c.grab(particle, anchor)
        ps.set_do_default_mouse_interaction(False)   # the drag pulls instead of turning the view
        return particle

    def pull_at(self, screen_xy) -> None:
        """Move the held particle's target under the screen point, in the plane facing the view."""
        if self._drag_plane is None:
            return
        origin = ps.get_view_camera_parameters().get_position()
        ray = ps.screen_coords_to_world_ray(tuple(screen_xy))
        target = point_on_drag_plane(origin, ray, *self._drag_plane)
        if target is not None:
            self.controls.pull_to(target)

    def let_go(self) -> None:
        self.controls.release()
        self._drag_plane = None
        ps.set_do_default_mouse_interaction(True)

    def _draw_mouse_spring(self) -> None:
        held = self.controls.held_position()
        if held is None:
            if ps.has_curve_network(MOUSE_SPRING_NAME):
                ps.remove_curve_network(MOUSE_SPRING_NAME)
            return
        nodes = np.stack([held, self.controls.mouse.target])
        line = ps.register_curve_network(MOUSE_SPRING_NAME, nodes, np.array([[0, 1]]),
                                         color=(0.1, 0.1, 0.1))
        line.set_radius(0.05 * self.drawing.spacing, relative=False)
