"""The control panel (Dear ImGui through polyscope): it shows values and calls Controls.

Nothing here decides what a control does; that is controls.py, which tests drive directly.
Numbers typed or dragged are applied when the field is let go (not at every keystroke or pixel
of a drag), since most of them rebuild the simulation.
"""
import polyscope.imgui as psim

from ..integrators import integrator_names
from ..presets import preset_names
from ..render.contacts import has_body_contact
from ..render.drawing import has_wind, pinned_particles
from ..springs import SpringKind
from .controls import TERRAINS

RED = (1.0, 0.15, 0.1, 1.0)
AMBER = (0.95, 0.65, 0.1, 1.0)
WIDTH = 320


class Panel:
    def __init__(self, controls, viewer):
        self.controls, self.viewer = controls, viewer
        self._pending = {}    # label -> value being edited, applied when the field is let go
        self.scenes = preset_names()
        if controls.scene_name not in self.scenes:
            self.scenes.append(controls.scene_name)   # a scene file given on the command line

    def build(self) -> None:
        psim.SetNextWindowPos((10, 10), psim.ImGuiCond_FirstUseEver)
        psim.SetNextWindowSize((WIDTH, 0), psim.ImGuiCond_FirstUseEver)
        psim.Begin("springsim", True)
        psim.PushItemWidth(130)
        self._message()
        self._run()
        self._figures()
        self._scene()
        self._springs()
        self._contact()
        self._bodies()
        self._drawing()
        self._view_and_mouse()
        psim.PopItemWidth()
        psim.End()

    # --- sections -------------------------------------------------------------------------
    def _message(self) -> None:
        c = self.controls
        if not c.message:
            return
        psim.PushTextWrapPos(WIDTH - 20)
        if c.unstable:     # the course's red line, then what diverged and what to try
            headline, _, details = c.message.partition("\n")
            psim.TextColored(RED, headline)
            if details:
                psim.TextColored(AMBER, details)
        else:
            psim.TextColored(AMBER, c.message)
        psim.PopTextWrapPos()

    def _run(self) -> None:
        c = self.controls
        if psim.Button("Start"):
            c.start()
        psim.SameLine()
        if c.running:
            if psim.Button("Stop"):
                c.stop()
        else:
            psim.BeginDisabled(c.unstable)    # a diverged state must be reset first
            if psim.Button("Resume"):
                c.resume()
            psim.SameLine()
            if psim.Button("Step"):
                c.step_frame()
            psim.EndDisabled()
        psim.SameLine()
        if psim.Button("Reset"):
            c.reset()
        self._record()
        names = integrator_names()
        current = names.index(c.sim.integrator.name) if c.sim.integrator.name in names else 0
        changed, chosen = psim.Combo("integrator", current, names)
        if changed:
            c.set_integrator(names[chosen])
        self._number("dt (s)", c.sim.dt, c.set_dt, fmt="%.2e")
        changed, steps = psim.SliderInt("steps per frame", c.steps_per_frame, 1, 200)
        if changed:
            c.set_steps_per_frame(steps)

    def _scene(self) -> None:
        c = self.controls
        if not psim.CollapsingHeader("Scene and terrain", psim.ImGuiTreeNodeFlags_DefaultOpen):
            return
        current = self.scenes.index(c.scene_name) if c.scene_name in self.scenes else 0
        changed, chosen = psim.Combo("scene", current, self.scenes)
        if changed:
            c.choose_scene(self.scenes[chosen])
        terrain = c.terrain_name()
        for number, name in enumerate(TERRAINS):
            if number % 3:
                psim.SameLine()
            if psim.RadioButton(name, terrain == name) and terrain != name:
                c.choose_terrain(name)

    def _springs(self) -> None:
        c = self.controls
        if not psim.CollapsingHeader("Springs"):
            return
        for kind in SpringKind:
            params = c.spring(kind)
            if params is None or (kind == SpringKind.FACE and not c.has_face_springs()):
                continue
            self._number(f"{kind.label} ks (N/m)", params.ks,
                         lambda value, k=kind: c.set_spring(k, ks=value), fmt="%.1f")
            self._number(f"{kind.label} kd (N s/m)", params.kd,
                         lambda value, k=kind: c.set_spring(k, kd=value), fmt="%.2f")

    def _contact(self) -> None:
        c = self.controls
        if not psim.CollapsingHeader("Contact and drag"):
            return
        restitution = c.terrain_value("restitution")
        if restitution is not None:
            self._number("restitution", restitution, c.set_restitution, 0.0, 1.0)
            self._number("friction", c.terrain_value("friction"), c.set_friction, 0.0, 2.0)
        self._number("drag (N s/m)", c.sim.scene.drag, c.set_drag, fmt="%.4f")
        self._body_contact()

    def _body_contact(self) -> None:
        """Per body with a surface: self-collision and thickness (``##number`` keeps ImGui's
        labels apart)."""
        c = self.controls
        for number, name, body in c.contact_bodies():
            changed, on = psim.Checkbox(f"{name} self-collision##{number}", body.self_collision)
            if changed:
                c.set_self_collision(number, on)
            self._number(f"{name} thickness (m)##{number}", body.contact_thickness(),
                         lambda value, n=number: c.set_thickness(n, value), fmt="%.4f")

    def _bodies(self) -> None:
        c = self.controls
        if not psim.CollapsingHeader("Bodies (these restart)"):
            return
        cube = c.cube()
        if cube is not None:
            self._number("cube height (m)", cube.position[1], c.set_cube_height, -5.0, 30.0)
            self._number("cube rotation (deg)", cube.rotation_degrees, c.set_cube_rotation,
                         0.0, 360.0)
        count = c.particles_per_edge()
        if count is not None:
            self._integer("particles per edge", count, c.set_particles_per_edge, 2, 40)

    def _drawing(self) -> None:
        if psim.CollapsingHeader("Draw", psim.ImGuiTreeNodeFlags_DefaultOpen):
            model = self.controls.sim.model
            draw_toggles(self.controls.draw, model, self.viewer.set_drawn,
                         contacts=has_body_contact(model))

    def _view_and_mouse(self) -> None:
        c, viewer = self.controls, self.viewer
        if not psim.CollapsingHeader("View and mouse", psim.ImGuiTreeNodeFlags_DefaultOpen):
            return
        for number, name in enumerate(("auto", "front", "side", "top")):
            if number:
                psim.SameLine()
            if psim.Button(name):
                viewer.look(name)
        psim.TextWrapped("Ctrl + left drag: pull a particle with a spring")
        changed, value = psim.SliderFloat("mouse spring (N/m/kg)", c.mouse.stiffness_per_mass,
                                          10.0, 10000.0, "%.0f", psim.ImGuiSliderFlags_Logarithmic)
        if changed:
            c.mouse.stiffness_per_mass = value

    def _record(self) -> None:
        viewer = self.viewer
        recorder = viewer.recorder
        if recorder.recording:
            if psim.Button("Stop recording"):
                viewer.stop_recording()
            psim.SameLine()
            psim.Text(f"{recorder.frames} frames")
        elif psim.Button("Record"):
            viewer.start_recording()
        if recorder.last_message:
            psim.TextWrapped(recorder.last_message)

    def _figures(self) -> None:
        c = self.controls
        if not psim.CollapsingHeader("Figures", psim.ImGuiTreeNodeFlags_DefaultOpen):
            return
        stats = c.stats
        psim.Text(f"simulated time  {c.sim.time:9.3f} s")
        psim.Text(f"frames/s        {stats.fps:9.1f}")
        psim.Text(f"steps/s         {stats.steps_per_second:9.0f}")
        psim.Text(f"real-time factor {stats.real_time_factor:8.3f}")
        energy = c.energy()
        for name in ("kinetic", "gravitational", "spring", "total"):
            psim.Text(f"{name + ' energy':<20}{energy[name]:12.5g} J")

    # --- fields applied when let go -------------------------------------------------------
    def _number(self, label, value, apply, low=None, high=None, fmt="%.3f") -> None:
        shown = self._pending.get(label, float(value))
        if low is None:
            changed, shown = psim.InputDouble(label, shown, 0.0, 0.0, fmt)
        else:
            changed, shown = psim.SliderFloat(label, shown, low, high, fmt)
        self._settle(label, changed, shown, apply)

    def _integer(self, label, value, apply, low, high) -> None:
        shown = self._pending.get(label, int(value))
        changed, shown = psim.SliderInt(label, shown, low, high)
        self._settle(label, changed, shown, apply)

    def _settle(self, label, changed, value, apply) -> None:
        if changed:
            self._pending[label] = value
        if psim.IsItemDeactivatedAfterEdit() and label in self._pending:
            apply(self._pending.pop(label))
        elif not psim.IsItemActive():
            self._pending.pop(label, None)


def draw_toggles(draw, model, set_drawn, contacts: bool = False) -> None:
    """A checkbox per part the model has (``draw``: render.DrawOptions); ``set_drawn(name, shown)``
    applies a change; ``contacts``: whether the model has surfaces that touch. Shared by the
    viewer and the replay (springsim play)."""
    present = {SpringKind(k).label for k in set(model.spring_kind.tolist())}
    toggles = ["particles", *[k.label for k in SpringKind if k.label in present],
               "surfaces", "balls", "terrains",
               *(["pins"] if pinned_particles(model).any() else []),
               *(["wind"] if has_wind(model) else []), *(["contacts"] if contacts else [])]
    for number, name in enumerate(toggles):
        if number % 3:
            psim.SameLine()
        changed, shown = psim.Checkbox(name, getattr(draw, name))
        if changed:
            set_drawn(name, shown)
