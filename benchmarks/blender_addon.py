"""Simulate in Blender against `springsim run` of the exported scene, and Blender's own cloth.

A 50 x 50 grid (2,500 vertices, 1 m square) pinned along one edge swings down from flat for
120 frames at 24 fps: springsim's backward Euler at one step a frame, no self-collision, no
collider. Measured, in wall-clock seconds on this machine:

- Simulate: `bpy.ops.springsim.simulate()` in background mode (bpy 4.2 as a module): scene
  export, springsim's process from start to end (Python, springsim and its cached kernels
  loading included), the point caches written;
- `springsim run`: the exported scene folder on the command line (`python -m springsim run
  scene.toml --fps 24 --export take.pc2 --quiet`), a fresh process too;
- Blender's own cloth modifier on the same mesh (its default "Cotton" settings, quality 5, the
  same pins, self-collision off), stepped frame by frame from frame 1 (its point cache bakes as
  it goes).

The issue's bar: Simulate costs at most 20% more than `springsim run`, plus at most 3 s. Run
twice the first time (Numba compiles springsim's kernels once, then loads them from its cache):

    .venv/bin/python benchmarks/blender_addon.py [--picture docs/images/blender-cloths.png]

``--picture`` also renders both cloths at frame 36 with Cycles: springsim's on the left, Blender's
on the right.
"""
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import bpy

import springsim_blender

FRAMES, FPS, SIDE = 120, 24, 50


def empty_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0
    scene.frame_start, scene.frame_end = 1, FRAMES
    return scene


def hanging_grid(x: float):
    """The 50 x 50 grid, 1 m square, flat at 1 m, its +y edge in the vertex group 'pin'."""
    bpy.ops.mesh.primitive_grid_add(x_subdivisions=SIDE - 1, y_subdivisions=SIDE - 1, size=1.0,
                                    location=(x, 0, 1))
    cloth = bpy.context.object
    group = cloth.vertex_groups.new(name="pin")
    top = max(v.co.y for v in cloth.data.vertices)
    group.add([v.index for v in cloth.data.vertices if v.co.y > top - 1e-6], 1.0, "REPLACE")
    assert len(cloth.data.vertices) == SIDE * SIDE
    return cloth


def simulate_in_blender(folder: Path) -> tuple[float, Path, object]:
    scene = empty_scene()
    cloth = hanging_grid(-0.6)
    cloth.springsim.role = "CLOTH"
    cloth.springsim.pin_group = "pin"
    scene.springsim.self_collision = False
    bpy.ops.wm.save_as_mainfile(filepath=str(folder / "bench.blend"))
    started = time.perf_counter()
    bpy.ops.springsim.simulate()
    seconds = time.perf_counter() - started
    bpy.ops.springsim.export_scene(filepath=str(folder / "exported"))
    return seconds, folder / "exported", cloth


def springsim_run(exported: Path) -> float:
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "springsim", "run", "scene.toml", "--fps", str(FPS),
                    "--export", "take.pc2", "--quiet"], cwd=exported, check=True)
    return time.perf_counter() - started


def blender_cloth(springsim_cloth) -> float:
    """Blender's cloth on a copy of the grid beside springsim's (hidden meanwhile, so that only
    Blender's cloth is evaluated), stepped through the frames from frame 1."""
    scene = bpy.context.scene
    springsim_cloth.hide_viewport = True
    cloth = hanging_grid(0.6)
    modifier = cloth.modifiers.new("Cloth", "CLOTH")
    modifier.settings.vertex_group_mass = "pin"
    modifier.collision_settings.use_self_collision = False
    modifier.point_cache.frame_start, modifier.point_cache.frame_end = 1, FRAMES
    started = time.perf_counter()
    for frame in range(1, FRAMES + 1):
        scene.frame_set(frame)
    seconds = time.perf_counter() - started
    springsim_cloth.hide_viewport = False
    return seconds


def picture(path: str, frame: int) -> None:
    """Both cloths at ``frame``, springsim's on the left, Blender's on the right (Cycles)."""
    scene = bpy.context.scene
    bpy.ops.object.camera_add(location=(0.0, -3.2, 0.55), rotation=(math.radians(88), 0, 0))
    scene.camera = bpy.context.object
    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(40), math.radians(20), 0))
    bpy.context.object.data.energy = 3.0
    scene.world = bpy.data.worlds.new("World")
    scene.world.color = (0.6, 0.6, 0.65)
    scene.render.engine = "CYCLES"
    scene.cycles.samples = 16
    scene.render.resolution_x, scene.render.resolution_y = 640, 360
    scene.render.filepath = str(Path(path).resolve())
    scene.frame_set(frame)
    bpy.ops.render.render(write_still=True)


def main() -> None:
    springsim_blender.register()
    with tempfile.TemporaryDirectory() as folder:
        simulate, exported, cloth = simulate_in_blender(Path(folder))
        run = springsim_run(exported)
        blender = blender_cloth(cloth)
        if "--picture" in sys.argv:
            picture(sys.argv[sys.argv.index("--picture") + 1], frame=36)
    print(f"# {date.today()}, {platform.node()}, {os.cpu_count()} cores, Blender "
          f"{bpy.app.version_string}; {SIDE * SIDE} vertices, {FRAMES} frames at {FPS} fps")
    print("| what | wall s | ms per frame |")
    print("|---|---|---|")
    for name, seconds in (("Simulate in Blender (springsim extension)", simulate),
                          ("springsim run of the exported scene", run),
                          ("Blender's own cloth (quality 5)", blender)):
        print(f"| {name} | {seconds:.2f} | {1000 * seconds / FRAMES:.1f} |")
    extra = simulate - run
    print(f"Simulate - run = {extra:.2f} s ({100 * extra / run:.0f}% of run); "
          f"bar: <= 20% of run + 3 s = {0.2 * run + 3:.2f} s")
    sys.stdout.flush()
    os._exit(0)      # bpy 4.2 as a module may crash while Python shuts down


if __name__ == "__main__":
    main()
