"""Run by tests/test_blender_addon.py in a Python with ``bpy`` (Blender 4.2 as a module): build a
scene from Python, load the extension with a plain import + register(), simulate, and print, as
JSON on the last line, what Blender shows (world-space vertices through the Mesh Cache modifier)
and what the test needs to judge it.

    python tests/blender_addon_scenes.py SCENARIO FOLDER
"""
import json
import math
import os
import sys
from pathlib import Path

import bpy
import numpy as np

import springsim_blender

FPS = 24


def fresh(folder: Path, frames: int, save: bool = True):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    springsim_blender.register()
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.frame_start, scene.frame_end = 1, frames
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=str(folder / "scene.blend"))
    return scene


def world_vertices(obj, frame: int, cache: bool = True) -> list:
    scene = bpy.context.scene
    modifier = obj.modifiers.get("springsim")
    if modifier is not None:
        modifier.show_viewport = cache
    scene.frame_set(frame)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    matrix = np.array(evaluated.matrix_world)
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    if modifier is not None:
        modifier.show_viewport = True
    co = co.reshape(-1, 3)
    return (co @ matrix[:3, :3].T + matrix[:3, 3]).tolist()


def frames_of(obj, frames, cache=True) -> dict:
    return {frame: world_vertices(obj, frame, cache) for frame in frames}


def grid_cloth(name="Cloth", size=1.0, location=(0, 0, 1), rotation=(0, 0, 0), edge="y"):
    """A 20 x 20 vertex grid, its vertices on the +edge side in the vertex group 'pin'."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=19, y_subdivisions=19, size=size,
                                    location=location, rotation=rotation)
    cloth = bpy.context.object
    cloth.name = name
    group = cloth.vertex_groups.new(name="pin")
    axis = "xyz".index(edge)
    top = max(v.co[axis] for v in cloth.data.vertices)
    pinned = [v.index for v in cloth.data.vertices if v.co[axis] > top - 1e-6]
    group.add(pinned, 1.0, "REPLACE")
    cloth.springsim.role = "CLOTH"
    cloth.springsim.pin_group = "pin"
    return cloth, pinned


def simulate() -> str:
    """Simulate; the report's message ('' when it worked) - the operator's own error line."""
    try:
        bpy.ops.springsim.simulate()
    except RuntimeError as error:
        return str(error).strip()
    return ""


def sphere_through(folder: Path) -> dict:
    """A 20 x 20 grid hanging from its top edge; a sphere keyframed through it. Then the take is
    saved, the file reopened (it still plays), the scene exported, and the take freed."""
    frames = 24
    scene = fresh(folder, frames)
    cloth, pinned = grid_cloth(rotation=(math.radians(90), 0, 0))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.2, segments=32, ring_count=16,
                                         location=(0.05, -0.5, 0.95))
    sphere = bpy.context.object
    sphere.name = "Ball"
    sphere.springsim.role = "COLLIDER"
    sphere.keyframe_insert("location", frame=1)
    sphere.location = (0.05, 0.6, 0.95)
    sphere.keyframe_insert("location", frame=frames)
    error = simulate()
    result = {"error": error, "pinned": pinned, "frames": list(range(1, frames + 1))}
    result["cloth"] = frames_of(cloth, result["frames"])
    result["rest"] = world_vertices(cloth, 1, cache=False)
    result["sphere"] = {f: world_vertices(sphere, f) for f in result["frames"]}
    result["sphere_centre"] = {}
    for f in result["frames"]:
        scene.frame_set(f)
        result["sphere_centre"][f] = list(sphere.matrix_world.translation)
    modifier = cloth.modifiers["springsim"]
    cache = Path(bpy.path.abspath(modifier.filepath))
    result.update(cache=str(cache), modifier_last=cloth.modifiers[-1].name == "springsim")
    bpy.ops.springsim.export_scene(filepath=str(folder / "exported"))
    bpy.ops.wm.save_mainfile()
    bpy.ops.wm.open_mainfile(filepath=str(folder / "scene.blend"))
    cloth = bpy.data.objects["Cloth"]
    result["reopened"] = world_vertices(cloth, frames)
    bpy.ops.springsim.free()
    result["after_free"] = {"modifiers": [m.name for m in cloth.modifiers],
                            "cache_exists": cache.exists(),
                            "folder_exists": cache.parent.exists()}
    return result


def moving_pin(folder: Path) -> dict:
    """A cloth parented to an empty that moves and turns by keyframes, pinned along an edge."""
    frames = 24
    fresh(folder, frames)
    bpy.ops.object.empty_add(location=(0, 0, 1))
    handle = bpy.context.object
    cloth, pinned = grid_cloth(location=(0, 0, 1))
    cloth.parent = handle
    cloth.matrix_parent_inverse = handle.matrix_world.inverted()
    handle.keyframe_insert("location", frame=1)
    handle.keyframe_insert("rotation_euler", frame=1)
    handle.location = (0.5, 0.2, 1.3)
    handle.rotation_euler = (0, 0, math.radians(60))
    handle.keyframe_insert("location", frame=frames)
    handle.keyframe_insert("rotation_euler", frame=frames)
    error = simulate()
    frame_list = list(range(1, frames + 1))
    return {"error": error, "pinned": pinned, "frames": frame_list,
            "cloth": frames_of(cloth, frame_list),
            "animated": frames_of(cloth, frame_list, cache=False)}


def wind(folder: Path) -> dict:
    """A cloth hanging in the x-z plane; a Wind field along +y at two strengths."""
    frames = 12
    fresh(folder, frames)
    cloth, _ = grid_cloth(rotation=(math.radians(90), 0, 0), edge="y")
    bpy.ops.object.effector_add(type="WIND", rotation=(math.radians(-90), 0, 0))
    field = bpy.context.object
    result = {"rest": world_vertices(cloth, 1, cache=False)}
    for strength in (0.0, 4.0, 8.0):
        field.field.strength = strength
        result[str(strength)] = {"error": simulate(), "last": world_vertices(cloth, frames)}
    return result


def jelly(folder: Path) -> dict:
    """A UV-mapped sphere as a jelly body, dropped on a plane collider."""
    frames = 30
    fresh(folder, frames)
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.3, segments=16, ring_count=8,
                                         location=(0, 0, 0.6))
    body = bpy.context.object
    body.springsim.role = "BODY"
    body.springsim.particles = 150
    bpy.ops.mesh.primitive_plane_add(size=3.0)
    bpy.context.object.springsim.role = "COLLIDER"
    error = simulate()
    modifier = body.modifiers["springsim"]
    cache = Path(bpy.path.abspath(modifier.filepath))
    header = np.fromfile(cache, "<i4", count=8)
    return {"error": error, "has_uv": bool(body.data.uv_layers),
            "vertex_count": len(body.data.vertices), "cache_points": int(header[4]),
            "cache_samples": int(header[7]), "rest": world_vertices(body, 1, cache=False),
            "first": world_vertices(body, 1), "last": world_vertices(body, frames)}


def failures(folder: Path) -> dict:
    """A missing springsim, a non-manifold collider, a diverging setting: the report's line."""
    fresh(folder, 6)
    cloth, _ = grid_cloth()
    result = {}
    os.environ["SPRINGSIM_PYTHON"] = str(folder / "no-such-python")
    result["no_python"] = simulate()
    os.environ["SPRINGSIM_PYTHON"] = str(folder / "bare-python")
    result["no_springsim"] = simulate()
    del os.environ["SPRINGSIM_PYTHON"]
    mesh = bpy.data.meshes.new("Fin")        # three faces on one edge: no inside
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1)], [],
                     [(0, 1, 2), (1, 0, 3), (0, 1, 4)])
    fin = bpy.data.objects.new("Fin", mesh)
    bpy.context.scene.collection.objects.link(fin)
    fin.springsim.role = "COLLIDER"
    result["non_manifold"] = simulate()
    fin.springsim.role = "NONE"
    scene = bpy.context.scene
    scene.springsim.integrator = "explicit_euler"
    cloth.springsim.preset = "LEATHER"
    result["diverged"] = simulate()
    scene.springsim.integrator = "implicit_euler"
    result["after"] = simulate()
    return result


def armature_pin(folder: Path) -> dict:
    """A cloth whose pinned edge an armature bends (the cloth's weights to the bone grow across
    it, so the deformation is no rigid motion): the pins follow the deformed mesh."""
    frames = 24
    fresh(folder, frames)
    bpy.ops.object.armature_add(location=(0, 0, 1))
    rig = bpy.context.object
    cloth, pinned = grid_cloth(location=(0, 0, 1))
    bone = cloth.vertex_groups.new(name="Bone")
    for vertex in cloth.data.vertices:
        bone.add([vertex.index], float(vertex.co.x + 0.5), "REPLACE")
    modifier = cloth.modifiers.new("Armature", "ARMATURE")
    modifier.object = rig
    pose = rig.pose.bones["Bone"]
    pose.rotation_mode = "XYZ"
    pose.keyframe_insert("location", frame=1)
    pose.keyframe_insert("rotation_euler", frame=1)
    pose.location = (0.0, 0.3, 0.2)
    pose.rotation_euler = (math.radians(30), 0, 0)
    pose.keyframe_insert("location", frame=frames)
    pose.keyframe_insert("rotation_euler", frame=frames)
    error = simulate()
    frame_list = list(range(1, frames + 1))
    return {"error": error, "pinned": pinned, "frames": frame_list,
            "cloth": frames_of(cloth, frame_list),
            "animated": frames_of(cloth, frame_list, cache=False)}


def deforming_collider(folder: Path) -> dict:
    """A cloth hanging from its top edge; a sphere collider that a shape key swells into it."""
    frames = 24
    scene = fresh(folder, frames)
    cloth, _ = grid_cloth(rotation=(math.radians(90), 0, 0))
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.1, segments=32, ring_count=16,
                                         location=(0.05, -0.3, 0.95))
    sphere = bpy.context.object
    sphere.springsim.role = "COLLIDER"
    sphere.shape_key_add(name="Basis")
    swell = sphere.shape_key_add(name="Swell")
    for point in swell.data:
        point.co = point.co * 4.0          # radius 0.4: 0.1 m through the cloth at y = 0
    swell.value = 0.0
    swell.keyframe_insert("value", frame=1)
    swell.value = 1.0
    swell.keyframe_insert("value", frame=frames)
    error = simulate()
    frame_list = list(range(1, frames + 1))
    radius = {}
    for frame in frame_list:
        scene.frame_set(frame)
        radius[frame] = 0.1 * (1 + 3 * swell.value)
    return {"error": error, "frames": frame_list, "cloth": frames_of(cloth, frame_list),
            "centre": [0.05, -0.3, 0.95], "radius": radius,
            "exported": open(folder / "scene_springsim" / "Scene" / "scene" / "scene.toml").read()}


def soft_pins(folder: Path) -> dict:
    """A flat grid held by its +y edge at weight 1 and its -y edge at weight 0.5."""
    frames = 24
    fresh(folder, frames)
    cloth, hard = grid_cloth()
    cloth.springsim.pin_stiffness = 200.0
    low = min(v.co.y for v in cloth.data.vertices)
    soft = [v.index for v in cloth.data.vertices if v.co.y < low + 1e-6]
    cloth.vertex_groups["pin"].add(soft, 0.5, "REPLACE")
    error = simulate()
    bpy.ops.springsim.export_scene(filepath=str(folder / "exported"))
    return {"error": error, "hard": hard, "soft": soft,
            "rest": world_vertices(cloth, 1, cache=False), "last": world_vertices(cloth, frames)}


def streaming(folder: Path) -> dict:
    """The interface's path without the interface: frames reach the object's cache while the
    run goes on, and a cancelled run keeps the frames computed (the modal operator's timer calls
    update(), Esc calls cancel())."""
    import time

    from springsim_blender.operators import start_run

    scene = fresh(folder, 48)
    scene.springsim.substeps = 40               # slow enough to be seen frame by frame
    grid_cloth()
    seen = []
    run = start_run(bpy.context)
    while run.running:
        run.update()
        seen.append(run.shown)
        time.sleep(0.05)
    run.finish()
    whole = run.shown
    run = start_run(bpy.context)
    while run.running and run.update() == 0 or run.shown < 5:
        time.sleep(0.02)
    run.cancel()
    cache = run.caches["Cloth"]
    kept = int(np.fromfile(cache, "<i4", count=8)[7])
    return {"seen": seen, "whole": whole, "cancelled_at": run.shown, "kept": kept,
            "modal": modal_operator(folder)}


def modal_operator(folder: Path) -> dict:
    """The modal operator's own methods, driven by stand-in timer and Esc events (bpy as a
    module has no window to send them): a run to the end, then one cancelled."""
    import time
    from types import SimpleNamespace

    from springsim_blender.operators import SPRINGSIM_OT_simulate, start_run

    reports = []
    answers = []
    for cancel_after in (None, 3):
        operator = SimpleNamespace(_run=start_run(bpy.context), _timer=None,
                                   report=lambda kind, text: reports.append(text),
                                   _end=lambda context: None)
        answer, ticks = {"PASS_THROUGH"}, 0
        while answer == {"PASS_THROUGH"}:
            time.sleep(0.05)
            ticks += 1
            kind = "ESC" if cancel_after and operator._run.shown >= cancel_after else "TIMER"
            answer = SPRINGSIM_OT_simulate.modal(operator, bpy.context, SimpleNamespace(type=kind))
        answers.append(sorted(answer))
    return {"answers": answers, "reports": reports}



def centre_and_radius(obj, frame: int) -> tuple[list, float]:
    """A sphere as Blender evaluates it at ``frame``: the mean of its vertices (a UV sphere's
    centre) and their least distance from it (its radius)."""
    points = np.asarray(world_vertices(obj, frame))
    centre = points.mean(axis=0)
    return centre.tolist(), float(np.linalg.norm(points - centre, axis=1).min())


def animated_colliders(folder: Path) -> dict:
    """A cloth hanging from its top edge; three spheres pass through it side by side, each moved
    another way Blender evaluates: one carried by a keyframed empty it is parented to (which
    also turns, so the sphere swings on an arc), one deformed by an armature whose bone moves
    and grows it, one moved by a Displace modifier whose strength is keyframed."""
    frames = 24
    scene = fresh(folder, frames)
    cloth, pinned = grid_cloth(rotation=(math.radians(90), 0, 0))

    def ball(name, x):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.12, segments=32, ring_count=16,
                                             location=(x, -0.35, 0.85))
        sphere = bpy.context.object
        sphere.name = name
        sphere.springsim.role = "COLLIDER"
        return sphere

    carried = ball("Carried", -0.3)
    bpy.ops.object.empty_add(location=(-0.3, -0.5, 0.85))
    carrier = bpy.context.object
    carrier.name = "Carrier"
    carried.parent = carrier
    carried.matrix_parent_inverse = carrier.matrix_world.inverted()
    carrier.rotation_mode = "XYZ"
    carrier.keyframe_insert("location", frame=1)
    carrier.keyframe_insert("rotation_euler", frame=1)
    carrier.location = (-0.3, 0.05, 0.85)
    carrier.rotation_euler = (0, 0, math.radians(-30))
    carrier.keyframe_insert("location", frame=frames)
    carrier.keyframe_insert("rotation_euler", frame=frames)

    rigged = ball("Rigged", 0.0)
    bpy.ops.object.armature_add(location=(0.0, -0.35, 0.85))   # the bone's head: the centre
    rig = bpy.context.object
    group = rigged.vertex_groups.new(name="Bone")
    group.add([v.index for v in rigged.data.vertices], 1.0, "REPLACE")
    rigged.modifiers.new("Armature", "ARMATURE").object = rig
    pose = rig.pose.bones["Bone"]
    pose.keyframe_insert("location", frame=1)
    pose.keyframe_insert("scale", frame=1)
    pose.location = (0.0, 0.0, -0.6)       # the bone points up: its -z is the world's +y
    pose.scale = (1.3, 1.3, 1.3)
    pose.keyframe_insert("location", frame=frames)
    pose.keyframe_insert("scale", frame=frames)

    displaced = ball("Displaced", 0.3)
    displace = displaced.modifiers.new("Displace", "DISPLACE")
    displace.direction, displace.space, displace.mid_level = "Y", "LOCAL", 0.0
    displace.strength = 0.0
    displace.keyframe_insert("strength", frame=1)
    displace.strength = 0.6
    displace.keyframe_insert("strength", frame=frames)

    error = simulate()
    frame_list = list(range(1, frames + 1))
    result = {"error": error, "frames": frame_list, "pinned": pinned,
              "cloth": frames_of(cloth, frame_list), "spheres": {}}
    for sphere in (carried, rigged, displaced):
        shapes = {frame: centre_and_radius(sphere, frame) for frame in frame_list}
        result["spheres"][sphere.name] = {
            "centre": {f: shapes[f][0] for f in frame_list},
            "radius": {f: shapes[f][1] for f in frame_list},
            "vertices": {f: world_vertices(sphere, f) for f in frame_list}}
    result["exported"] = str(folder / "scene_springsim" / "Scene" / "scene")
    return result


def turbulence(folder: Path) -> dict:
    """A cloth hanging in a Wind field along +y: simulated without, then twice with, a
    Turbulence field; and what the Turbulence field exports to at other settings."""
    frames = 12
    fresh(folder, frames)
    cloth, _ = grid_cloth(rotation=(math.radians(90), 0, 0), edge="y")
    bpy.ops.object.effector_add(type="WIND", rotation=(math.radians(-90), 0, 0))
    wind = bpy.context.object
    wind.field.strength = 4.0
    frame_list = list(range(1, frames + 1))
    result = {"error": [simulate()]}
    result["steady"] = frames_of(cloth, frame_list)
    bpy.ops.object.effector_add(type="TURBULENCE", location=(0, 0, 1))
    gusts = bpy.context.object.field
    gusts.strength, gusts.size, gusts.seed = 3.0, 0.4, 7
    result["error"].append(simulate())
    result["gusty"] = frames_of(cloth, frame_list)
    result["error"].append(simulate())
    result["again"] = frames_of(cloth, frame_list)
    result["exports"] = {}
    bpy.ops.springsim.export_scene(filepath=str(folder / "gusty"))
    result["exports"]["gusty"] = str(folder / "gusty" / "scene.toml")
    gusts.size = 0.0                     # Blender's default: its noise unscaled, not 0 m
    bpy.ops.springsim.export_scene(filepath=str(folder / "default_size"))
    result["exports"]["default_size"] = str(folder / "default_size" / "scene.toml")
    gusts.size = 0.4
    wind.field.strength = 0.0            # gusts in still air: m/s, not a share of no wind
    bpy.ops.springsim.export_scene(filepath=str(folder / "still"))
    result["exports"]["still"] = str(folder / "still" / "scene.toml")
    return result


class Layout:
    """A stand-in for ``bpy.types.UILayout`` (bpy in background mode draws no panel): it records
    what a panel's draw() puts in it, and checks every call against the real UILayout's RNA
    (its functions, their parameters and enum values, the data's properties, the operators),
    so that what it accepts the real layout accepts too."""

    API = bpy.types.UILayout.bl_rna

    def __init__(self, log: list, problems: list):
        object.__setattr__(self, "log", log)
        object.__setattr__(self, "problems", problems)

    def __setattr__(self, name, value):
        if name not in self.API.properties:
            self.problems.append(f"UILayout has no attribute {name!r}")
        object.__setattr__(self, name, value)

    def __getattr__(self, name):
        function = self.API.functions.get(name)
        if function is None:
            self.problems.append(f"UILayout has no function {name!r}")
            raise AttributeError(name)
        inputs = [p for p in function.parameters if not p.is_output]
        names = [p.identifier for p in inputs]

        def call(*args, **kwargs):
            if len(args) > len(names):
                self.problems.append(f"{name}: {len(args)} positional arguments")
            given = dict(zip(names, args))
            for key, value in kwargs.items():
                if key not in names or key in given:
                    self.problems.append(f"{name}: bad keyword {key!r}")
                given[key] = value
            for parameter in inputs:
                if parameter.is_required and parameter.identifier not in given:
                    self.problems.append(f"{name}: {parameter.identifier!r} missing")
                value = given.get(parameter.identifier)
                if parameter.type == "ENUM" and value is not None and value not in {
                        item.identifier for item in parameter.enum_items}:
                    self.problems.append(f"{name}: {parameter.identifier}={value!r} unknown")
            entry = [name]
            if name in ("prop", "prop_search"):
                data, prop = given.get("data"), given.get("property")
                if prop not in data.bl_rna.properties:
                    self.problems.append(f"{name}: {data.bl_rna.identifier} has no {prop!r}")
                entry += [prop, data.bl_rna.identifier]
                if name == "prop_search":
                    search, collection = given.get("search_data"), given.get("search_property")
                    if collection not in search.bl_rna.properties:
                        self.problems.append(f"prop_search: no collection {collection!r}")
                    entry.append(collection)
            elif name == "operator":
                module, operator = given["operator"].split(".")
                try:
                    getattr(getattr(bpy.ops, module), operator).get_rna_type()
                except (AttributeError, KeyError):
                    self.problems.append(f"operator: no {given['operator']!r}")
                entry.append(given["operator"])
            elif name == "label":
                entry.append(given.get("text", ""))
            self.log.append(entry)
            if function.parameters.get("layout") is not None:       # row, column, box, ...
                return Layout(self.log, self.problems)
            return None

        return call


def drawn(panel_class, **context) -> dict:
    """What ``panel_class.draw`` shows for ``context`` (the stand-in layout's record)."""
    from types import SimpleNamespace

    log, problems = [], []
    panel = SimpleNamespace(layout=Layout(log, problems), **context.pop("self", {}))
    panel_class.draw(panel, SimpleNamespace(**context))
    return {"items": log, "problems": problems}


def interface(folder: Path) -> dict:
    """An unsaved file: the panels as each role draws them, the presets' numbers as applied and
    as exported, then a Simulate (where its cache goes, what Free leaves) and the modules
    Blender's process holds afterwards."""
    import importlib.util
    import tempfile
    import tomllib

    from springsim_blender import presets
    from springsim_blender.panels import PHYSICS_PT_springsim, SCENE_PT_springsim
    from springsim_blender.properties import Preferences

    frames = 6
    scene = fresh(folder, frames, save=False)
    result = {"blend": bpy.data.filepath, "pid": os.getpid(), "tempdir": tempfile.gettempdir(),
              "findable": importlib.util.find_spec("springsim") is not None}
    cloth, _ = grid_cloth()
    bpy.ops.mesh.primitive_uv_sphere_add(radius=0.2, location=(2, 0, 1))
    body = bpy.context.object
    body.name = "Body"
    body.springsim.role = "BODY"
    bpy.ops.mesh.primitive_cube_add(size=0.5, location=(-2, 0, 0))
    box = bpy.context.object
    box.name = "Box"
    box.springsim.role = "COLLIDER"
    bpy.ops.mesh.primitive_plane_add(location=(0, 3, 0))
    plain = bpy.context.object
    plain.name = "Plain"
    bpy.ops.object.empty_add()
    empty = bpy.context.object

    panels = {}
    for name, obj in (("cloth", cloth), ("body", body), ("collider", box), ("none", plain)):
        panels[name] = drawn(PHYSICS_PT_springsim, object=obj, scene=scene)
    cloth.springsim.pin_group = ""
    panels["cloth_unpinned"] = drawn(PHYSICS_PT_springsim, object=cloth, scene=scene)
    cloth.springsim.pin_group = "pin"
    panels["scene"] = drawn(SCENE_PT_springsim, scene=scene)
    settings = scene.springsim
    settings.use_frame_range = settings.use_air = True
    settings.last_message = "springsim: simulated 6 frames"
    panels["scene_all"] = drawn(SCENE_PT_springsim, scene=scene)
    settings.use_frame_range = settings.use_air = False
    settings.last_message = ""
    panels["preferences"] = drawn(Preferences, self={"bl_rna": Preferences.bl_rna})

    class Wrong:                     # the stand-in must refuse what the real layout refuses
        def draw(self, context):
            settings = context.scene.springsim
            self.layout.prop(settings, "no_such_setting")
            self.layout.prop(settings, "gravity", txt="typo")
            self.layout.operator("springsim.no_such_operator")
            self.layout.row().operator("springsim.free", icon="NO_SUCH_ICON")
    panels["wrong"] = drawn(Wrong, scene=scene)
    result["panels"] = panels
    result["poll"] = {name: bool(PHYSICS_PT_springsim.poll(SimpleContext(obj)))
                      for name, obj in (("mesh", plain), ("empty", empty), ("nothing", None))}

    # presets: each one over scrambled numbers, then as the exported scene has them
    applied = {}
    for name, _, _ in presets.ITEMS:
        if name == "CUSTOM":
            continue
        target = cloth if name in presets.CLOTH else body
        target.springsim.preset = "CUSTOM"
        for key in (*presets.CLOTH_KEYS, "spring_ks", "spring_kd"):
            setattr(target.springsim, key, 123.0)
        target.springsim.preset = name
        applied[name] = {key: getattr(target.springsim, key)
                         for key in (*presets.CLOTH_KEYS, "spring_ks", "spring_kd")}
    result["applied"] = applied
    exported = {}
    for number, name in enumerate(presets.CLOTH):
        cloth.springsim.preset = name
        body_preset = list(presets.BODY)[number % len(presets.BODY)]
        body.springsim.preset = body_preset
        out = folder / f"preset_{name}"
        bpy.ops.springsim.export_scene(filepath=str(out))
        table = tomllib.loads((out / "scene.toml").read_text())
        kinds = {entry["type"]: entry for entry in table["bodies"]}
        exported[name] = kinds["cloth"]["material"]
        exported[body_preset] = {kind: kinds["mesh"][kind] for kind in
                                 ("structural", "shear", "bend")}
    result["exported"] = exported

    # an unsaved file's take, and Free
    body.springsim.role = box.springsim.role = "NONE"
    cloth.springsim.preset = "COTTON"
    result["before"] = modules_of_interest()
    result["error"] = simulate()
    result["after"] = modules_of_interest()
    modifier = cloth.modifiers.get("springsim")
    result["modifier_path"] = modifier.filepath if modifier else None
    cache = Path(bpy.path.abspath(modifier.filepath)) if modifier else None
    result["cache_header"] = np.fromfile(cache, "<i4", count=8).tolist() if cache else None
    result["temp_listing"] = sorted(os.listdir(tempfile.gettempdir()))
    result["take_folder"] = sorted(str(p.relative_to(tempfile.gettempdir()))
                                   for p in Path(tempfile.gettempdir()).glob("springsim_*/**/*"))
    bpy.ops.springsim.free()
    result["after_free"] = {"modifiers": [m.name for m in cloth.modifiers],
                            "cache_exists": cache.exists() if cache else None,
                            "temp_listing": sorted(os.listdir(tempfile.gettempdir()))}
    result["after_free_modules"] = modules_of_interest()
    return result


class SimpleContext:
    def __init__(self, obj):
        self.object = obj


def modules_of_interest() -> list:
    """springsim's, Numba's and SciPy's modules loaded in this (Blender's) process, and the
    extension's package (which must be)."""
    return sorted(name for name in sys.modules
                  if name.split(".")[0] in ("springsim", "numba", "scipy", "springsim_blender"))


if __name__ == "__main__":
    scenario, folder = sys.argv[1], Path(sys.argv[2])
    print(json.dumps(globals()[scenario](folder)), flush=True)
    sys.stderr.flush()
    os._exit(0)     # bpy 4.2 as a module may crash while Python shuts down; the answer is out
