"""The replay window: a recording drawn as `springsim view` draws a simulation (render/drawing.py),
with a panel of playback controls (timeline.py does what they do) and the run's energy plot.
Headless (polyscope's EGL backend) for tests, or a window."""
import numpy as np
import polyscope as ps
import polyscope.imgui as psim

from ..render.backend import show_frames, start_renderer
from ..render.camera import apply_camera
from ..render.follow import still_camera
from ..render.drawing import DrawOptions, SceneDrawing
from ..viewer.panel import WIDTH as PANEL_WIDTH, draw_toggles
from .recorded_model import recorded_model
from .timeline import SPEEDS, Timeline

ENERGIES = ("kinetic", "gravitational", "spring", "total")
PANEL_SPACE = PANEL_WIDTH + 20


class ReplayViewer:
    def __init__(self, take, *, headless: bool = False, width: int = 1280, height: int = 800,
                 loop: bool = True, speed: float = 1.0):
        self.take = take
        self.backend = start_renderer(headless=headless, width=width, height=height)
        self.headless = headless
        self.model = recorded_model(take)
        self.timeline = Timeline(take.time, speed=speed, loop=loop)
        self.draw = DrawOptions()
        self.drawing = SceneDrawing(self.model, self.draw, take.positions[0])
        self.energies = recorded_energies(take.arrays)
        ps.set_open_imgui_window_for_user_callback(False)
        ps.set_user_callback(self.frame)
        self.look("auto")

    def frame(self) -> None:
        """polyscope's per-frame callback: the panel, then the clock, then the drawing."""
        self.build_panel()
        self.timeline.advance()
        frame = self.timeline.frame
        self.drawing.update(self.take.positions[frame], float(self.take.time[frame]))

    def run(self, frames: int | None = None) -> None:
        show_frames(self.headless, frames)

    def look(self, view: str) -> None:
        """Frame the whole recorded motion from one of the named directions."""
        width, height = ps.get_window_size()
        height = max(height, 1)
        panel = min(PANEL_SPACE, width // 2)
        stride = max(1, self.take.frame_count // 50)
        camera = still_camera(view, self.model, self.take.positions[::stride],
                              (width - panel) / height, self.take.time[::stride])
        apply_camera(camera.shifted(panel / 2, height))

    def set_drawn(self, name: str, shown: bool) -> None:
        setattr(self.draw, name, shown)
        self.drawing.apply_options(self.draw)

    # --- the panel ----------------------------------------------------------------------------
    def build_panel(self) -> None:
        t = self.timeline
        psim.SetNextWindowPos((10, 10), psim.ImGuiCond_FirstUseEver)
        psim.SetNextWindowSize((PANEL_WIDTH, 0), psim.ImGuiCond_FirstUseEver)
        psim.Begin(f"springsim play: {self.take.name}", True)
        psim.PushItemWidth(180)
        if psim.Button("Pause" if t.playing else "Play"):
            t.toggle()
        psim.SameLine()
        if psim.Button("<"):
            t.step(-1)
        psim.SameLine()
        if psim.Button(">"):
            t.step(1)
        psim.SameLine()
        _, t.loop = psim.Checkbox("loop", t.loop)
        # numbered from 1, as the label below ("frame 114 of 481") and Blender number frames
        changed, number = psim.SliderInt("frame", t.frame + 1, 1, t.frame_count)
        if changed:
            t.seek(number - 1)
        labels = [f"{speed:g}x" for speed in SPEEDS]
        current = SPEEDS.index(t.speed) if t.speed in SPEEDS else SPEEDS.index(1.0)
        changed, chosen = psim.Combo("speed", current, labels)
        if changed:
            t.set_speed(SPEEDS[chosen])
        psim.Text(f"t = {t.time:.3f} s of {t.duration:.3f} s, frame {t.frame + 1} of "
                  f"{t.frame_count}")
        self._energy_plot()
        if psim.CollapsingHeader("Draw", psim.ImGuiTreeNodeFlags_DefaultOpen):
            draw_toggles(self.draw, self.model, self.set_drawn)
        for number, name in enumerate(("auto", "front", "side", "top")):
            if number:
                psim.SameLine()
            if psim.Button(name):
                self.look(name)
        psim.PopItemWidth()
        psim.End()

    def _energy_plot(self) -> None:
        if not self.energies or not psim.CollapsingHeader("Energy",
                                                          psim.ImGuiTreeNodeFlags_DefaultOpen):
            return
        frame = self.timeline.frame
        for name, values in self.energies.items():
            psim.PlotLines(f"{name}", values.astype(np.float32), graph_size=(180, 40),
                           overlay_text=f"{values[frame]:.4g} J")


def recorded_energies(arrays) -> dict:
    """Kinetic, gravitational, spring and total energy (J) per frame, where recorded."""
    names = [f"{name}_energy" for name in ENERGIES[:3]]
    if not all(name in arrays for name in names):
        return {}
    parts = {name: np.asarray(arrays[f"{name}_energy"], float) for name in ENERGIES[:3]}
    return {**parts, "total": sum(parts.values())}
