"""Run by tests/test_blender.py in a Python that has ``bpy`` (Blender 4.2 as a module): open the
exported files in Blender itself and print, as JSON, where Blender has every vertex and ball.

    python tests/blender_check.py TAKE.usd TAKE.obj TAKE.mdd TAKE.pc2 FRAME [FRAME ...]

For the USD: Blender's frame range, and at each frame the world-space vertices of every imported
body mesh and the world-space centre of every ball. For each point cache: the OBJ imported with
Blender's default axes, a Mesh Cache modifier reading the cache from Blender frame 1 (its Frame
Start, as docs/tutorials/blender-houdini.md says to set it), and the world-space vertices at each
frame. Blender's world is Z up; the test turns springsim's Y-up coordinates into it.
"""
import json
import sys

import bpy


def evaluated_vertices(obj) -> list:
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    world = evaluated.matrix_world
    vertices = [list(world @ vertex.co) for vertex in mesh.vertices]
    evaluated.to_mesh_clear()
    return vertices


def usd(path: str, frames: list) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.usd_import(filepath=path, set_frame_range=True)
    scene = bpy.context.scene
    result = {"frame_start": scene.frame_start, "frame_end": scene.frame_end, "frames": {}}
    for frame in frames:
        scene.frame_set(frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        bodies, balls = {}, {}
        for obj in bpy.data.objects:
            if obj.type == "MESH" and obj.name.startswith("ball_"):
                balls[obj.name] = list(obj.evaluated_get(depsgraph).matrix_world.translation)
            elif obj.type == "MESH" and not obj.name.startswith("terrain_"):
                bodies[obj.name] = evaluated_vertices(obj)
        result["frames"][frame] = {"bodies": bodies, "balls": balls}
    return result


def point_cache(obj_path: str, cache_path: str, cache_format: str, frames: list,
                start: int = 1) -> dict:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.obj_import(filepath=obj_path)
    (obj,) = bpy.context.selected_objects
    modifier = obj.modifiers.new("springsim", "MESH_CACHE")
    modifier.cache_format = cache_format
    modifier.filepath = cache_path
    modifier.frame_start = start    # springsim's export numbers its first frame 1
    result = {}
    for frame in frames:
        bpy.context.scene.frame_set(frame)
        result[frame] = evaluated_vertices(obj)
    return result


def obj_frames(paths: list) -> list:
    """Each OBJ imported alone with Blender's default axes: its world-space vertices."""
    result = []
    for path in paths:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        bpy.ops.wm.obj_import(filepath=path)
        (obj,) = bpy.context.selected_objects
        result.append(evaluated_vertices(obj))
    return result


def main(argv) -> None:
    usd_path, obj_path, mdd_path, pc2_path, *frames = argv
    frames = [int(frame) for frame in frames]
    print(json.dumps({"usd": usd(usd_path, frames),
                      "mdd": point_cache(obj_path, mdd_path, "MDD", frames),
                      "pc2": point_cache(obj_path, pc2_path, "PC2", frames)}))


if __name__ == "__main__":
    main(sys.argv[1:])
