"""``bpy.ops.springsim.simulate()``, ``.free()`` and ``.export_scene(filepath=...)``.

Simulate exports the scene to a folder beside the .blend (a temporary one for an unsaved file),
runs springsim in its own process and plays the take through a Mesh Cache modifier on each
simulated object. In background mode (``blender -b``, bpy as a module) and when called from a
script it runs to the end before returning; from the interface it is modal: frames appear as they
are computed, the status bar shows the progress, Esc cancels and keeps what was computed. Every
failure is one line in Blender's report; Blender keeps running.
"""
import os
import tempfile
from pathlib import Path

import bpy
from bpy.props import StringProperty

from .properties import preferred_python
from .runner import Run, RunFailed, choose_python, remove_folder
from .scene_export import MODIFIER, SetupError, export_scene

TIMER_SECONDS = 0.1


def cache_folder(scene) -> Path:
    """Where a take's files go: ``<blend>_springsim/`` beside a saved .blend, else a folder of
    this session in the temporary folder."""
    if bpy.data.filepath:
        blend = Path(bpy.data.filepath)
        return blend.with_name(f"{blend.stem}_springsim") / safe(scene.name)
    return Path(tempfile.gettempdir()) / f"springsim_{os.getpid()}" / safe(scene.name)


def safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in name) or "scene"


def blend_path(path: Path) -> str:
    """A path as a modifier keeps it: relative to the .blend (//...) when it is saved."""
    return bpy.path.relpath(str(path)) if bpy.data.filepath else str(path)


def start_run(context) -> Run:
    scene = context.scene
    folder = cache_folder(scene)
    remove_folder(folder / "scene")
    exported = export_scene(scene, folder / "scene")
    caches = {target.name: folder / f"{target.file_name}.pc2" for target in exported.targets}
    python, source = choose_python(preferred_python(context))
    run = Run(exported, caches, python, source)
    run.start()
    for target in exported.targets:
        attach_cache(scene.objects[target.name], caches[target.name], exported.frame_start)
    return run


def attach_cache(obj, path: Path, frame_start: int) -> None:
    """The Mesh Cache modifier that plays ``path``, last in the stack (it overwrites what the
    modifiers before it did: the take starts from the mesh as evaluated)."""
    modifier = obj.modifiers.get(MODIFIER)
    if modifier is None or modifier.type != "MESH_CACHE":
        if modifier is not None:
            obj.modifiers.remove(modifier)
        modifier = obj.modifiers.new(MODIFIER, "MESH_CACHE")
    modifier.cache_format = "PC2"
    modifier.filepath = blend_path(path)
    modifier.frame_start = float(frame_start)
    modifier.show_viewport = modifier.show_render = True
    index = list(obj.modifiers).index(modifier)
    if index != len(obj.modifiers) - 1:
        obj.modifiers.move(index, len(obj.modifiers) - 1)


def refresh(context, run: Run) -> None:
    for target in run.exported.targets:
        obj = context.scene.objects.get(target.name)
        if obj is not None:
            obj.update_tag()
    for window in context.window_manager.windows:
        for area in window.screen.areas:
            area.tag_redraw()


def say(operator, context, kind: str, message: str) -> None:
    context.scene.springsim.last_message = message
    operator.report({kind}, message)


class SPRINGSIM_OT_simulate(bpy.types.Operator):
    bl_idname = "springsim.simulate"
    bl_label = "Simulate"
    bl_description = "Simulate the springsim objects over the frame range in springsim's process"
    bl_options = {"REGISTER"}

    _run = None
    _timer = None
    running = None       # the interface's run in progress, one at a time

    def execute(self, context):
        try:
            run = start_run(context)
            run.wait()
            run.finish()
        except (SetupError, RunFailed) as error:
            say(self, context, "ERROR", str(error))
            return {"CANCELLED"}
        say(self, context, "INFO", f"springsim: simulated {run.shown} frames")
        refresh(context, run)
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        if SPRINGSIM_OT_simulate.running is not None and SPRINGSIM_OT_simulate.running.running:
            say(self, context, "ERROR", "springsim: a simulation is already running (Esc "
                                        "cancels it)")
            return {"CANCELLED"}
        try:
            self._run = start_run(context)
            SPRINGSIM_OT_simulate.running = self._run
        except (SetupError, RunFailed) as error:
            say(self, context, "ERROR", str(error))
            return {"CANCELLED"}
        manager = context.window_manager
        self._timer = manager.event_timer_add(TIMER_SECONDS, window=context.window)
        manager.progress_begin(0, 1)
        manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        run = self._run
        if event.type == "ESC":
            run.cancel()
            self._end(context)
            say(self, context, "WARNING", f"springsim: cancelled; kept the {run.shown} frames "
                                          "computed")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if run.update():
            refresh(context, run)
        context.window_manager.progress_update(run.progress())
        context.workspace.status_text_set(
            f"springsim: frame {run.shown} of {run.exported.frame_count} (Esc cancels)")
        if run.running:
            return {"PASS_THROUGH"}
        self._end(context)
        try:
            run.finish()
        except RunFailed as error:
            refresh(context, run)
            say(self, context, "ERROR", str(error))
            return {"CANCELLED"}
        refresh(context, run)
        say(self, context, "INFO", f"springsim: simulated {run.shown} frames")
        return {"FINISHED"}

    def _end(self, context):
        context.window_manager.event_timer_remove(self._timer)
        context.window_manager.progress_end()
        context.workspace.status_text_set(None)


class SPRINGSIM_OT_free(bpy.types.Operator):
    bl_idname = "springsim.free"
    bl_label = "Free"
    bl_description = "Remove the springsim take: the Mesh Cache modifiers and their files"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        removed = free_take(context.scene)
        say(self, context, "INFO", f"springsim: freed {removed} objects")
        return {"FINISHED"}


def free_take(scene) -> int:
    removed = 0
    for obj in scene.objects:
        modifier = obj.modifiers.get(MODIFIER)
        if modifier is None or modifier.type != "MESH_CACHE":
            continue
        path = Path(bpy.path.abspath(modifier.filepath))
        path.unlink(missing_ok=True)
        obj.modifiers.remove(modifier)
        removed += 1
    folder = cache_folder(scene)
    remove_folder(folder / "scene")
    for empty in (folder, folder.parent):
        try:
            empty.rmdir()
        except OSError:
            pass
    return removed


class SPRINGSIM_OT_export_scene(bpy.types.Operator):
    bl_idname = "springsim.export_scene"
    bl_label = "Export Scene"
    bl_description = ("Write the scene as a springsim scene folder (scene.toml, meshes, "
                      "animation) for `springsim run`")
    bl_options = {"REGISTER"}

    filepath: StringProperty(name="Folder", subtype="DIR_PATH")

    def execute(self, context):
        if not self.filepath:
            say(self, context, "ERROR", "springsim: give the folder to export to (filepath)")
            return {"CANCELLED"}
        folder = Path(bpy.path.abspath(self.filepath))
        if folder.suffix == ".toml":
            folder = folder.parent
        try:
            exported = export_scene(context.scene, folder)
        except (SetupError, OSError) as error:
            say(self, context, "ERROR", f"springsim: {error}")
            return {"CANCELLED"}
        say(self, context, "INFO", f"springsim: wrote {exported.scene_file}")
        return {"FINISHED"}

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}


CLASSES = (SPRINGSIM_OT_simulate, SPRINGSIM_OT_free, SPRINGSIM_OT_export_scene)
