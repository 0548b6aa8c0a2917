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


def fresh(folder: Path, frames: int):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    springsim_blender.register()
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.frame_start, scene.frame_end = 1, frames
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


if __name__ == "__main__":
    scenario, folder = sys.argv[1], Path(sys.argv[2])
    print(json.dumps(globals()[scenario](folder)), flush=True)
    sys.stderr.flush()
    os._exit(0)     # bpy 4.2 as a module may crash while Python shuts down; the answer is out
