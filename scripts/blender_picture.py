"""The README's picture of a take in Blender: simulate jelly-balls, export it to USD, open the USD
in Blender (bpy, the ``blender`` extra) and render one frame with Cycles on the CPU.

    .venv/bin/python scripts/blender_picture.py [--out docs/images/blender.png] [--frame 40]

Everything in the picture comes from the exported file: the meshes, the balls, the plane, the
frame; only the camera, the light and the materials (the files' display colours) are added here.
The camera is springsim's own default (``springsim.render.follow``: it frames what moves at that
frame, as ``springsim render`` does), turned from springsim's y up to Blender's z up.
"""
import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

RENDER = r'''
import sys, bpy, math, json
from mathutils import Vector
usd, out, frame, width, height, view = sys.argv[-6:]
view = json.loads(view)
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=usd, set_frame_range=True)
scene = bpy.context.scene
scene.frame_set(int(frame))
colours = {"cube": (0.95, 0.55, 0.2), "ball": (0.6, 0.62, 0.7), "terrain": (0.35, 0.37, 0.34)}
for obj in bpy.data.objects:
    if obj.type != "MESH":
        continue
    kind = next((k for k in colours if obj.name.startswith(k)), "cube")
    material = bpy.data.materials.new(obj.name)
    material.use_nodes = True
    shader = material.node_tree.nodes["Principled BSDF"]
    shader.inputs["Base Color"].default_value = (*colours[kind], 1.0)
    shader.inputs["Roughness"].default_value = 0.5
    obj.data.materials.append(material)
    for polygon in obj.data.polygons:
        polygon.use_smooth = kind != "terrain"
camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = view["eye"]
direction = Vector(view["target"]) - camera.location
camera.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
camera.data.sensor_fit = "VERTICAL"        # springsim's field of view is the vertical one
camera.data.angle_y = math.radians(view["fov_degrees"])
scene.camera = camera
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (math.radians(40), math.radians(20), math.radians(30))
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("world")
world.use_nodes = True
world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.75, 0.8, 0.86, 1.0)
world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.35
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 32
scene.view_settings.view_transform = "Standard"
scene.render.resolution_x, scene.render.resolution_y = int(width), int(height)
scene.render.resolution_percentage = 100
scene.render.filepath = out
bpy.ops.render.render(write_still=True)
'''


def springsim_camera(take_path: Path, frame: int, aspect: float) -> dict:
    """springsim's default camera at Blender frame ``frame`` of the take, in Blender's axes
    (z up: springsim's (x, y, z) is Blender's (x, -z, y), as Blender imports a y-up USD)."""
    from springsim.export import load_take
    from springsim.render.follow import camera_path
    from springsim.replay.recorded_model import recorded_model

    take = load_take(take_path)
    cameras = camera_path("auto", recorded_model(take), take.positions, aspect, take.time)
    camera = cameras[min(max(frame - take.start_frame, 0), take.frame_count - 1)]

    def blender(point):
        x, y, z = (float(v) for v in point)
        return [x, -z, y]

    return {"eye": blender(camera.eye), "target": blender(camera.target),
            "fov_degrees": camera.fov_degrees}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/images/blender.png")
    parser.add_argument("--frame", type=int, default=55)
    parser.add_argument("--width", type=int, default=480)
    parser.add_argument("--height", type=int, default=270)
    args = parser.parse_args()
    from springsim.cli import main as springsim

    with tempfile.TemporaryDirectory() as folder:
        usd = Path(folder) / "jelly-balls.usd"
        code = springsim(["run", "jelly-balls", "--quiet", "--duration", "2", "--fps", "30",
                          "--out", str(Path(folder) / "jelly-balls.npz"), "--export", str(usd)])
        if code:
            sys.exit(code)
        rendered = Path(folder) / "render.png"
        view = springsim_camera(Path(folder) / "jelly-balls.npz", args.frame,
                                args.width / args.height)
        subprocess.run([sys.executable, "-c", RENDER, str(usd), str(rendered), str(args.frame),
                        str(args.width), str(args.height), json.dumps(view)], check=True,
                       capture_output=True)
        from PIL import Image

        # a 64-colour palette keeps the README's picture small
        Image.open(rendered).convert("RGB").quantize(64).save(args.out, optimize=True)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
