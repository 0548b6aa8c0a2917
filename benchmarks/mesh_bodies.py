"""Real meshes as jelly bodies (issue 29's bars): every test model of scripts/make_test_models.py
(closed, UV-seamed, open scans, several shells, thin limbs, inside out, a CAD part with a hole,
millimetres, 70,000 triangles), scaled to 2 m, spacing "auto" (about 2,000 particles), dropped
tilted from 0.5 m onto the plane y = 0 under implicit_euler at 1/60 s for 10 s (a soft jelly box
  rocks on its edges for about 8 s). A row per model:
its build time, the lowest any surface vertex went at any step (the bar: no lower than -2 cm),
and, at the end, the speed of its centre of mass and its fastest particle (at rest: small). Then the build time of the 70,000-triangle
model, built cold (no cache) five times (the bar: under 5 s).

    .venv/bin/python benchmarks/mesh_bodies.py
"""
import importlib.util
import platform
import sys
import tempfile
import time
import warnings
from datetime import date
from pathlib import Path

import numpy as np

import springsim
from springsim import meshfiles
from springsim.bodies import mesh as mesh_module
from springsim.bodies.mesh import MeshBody
from springsim.scene import Scene
from springsim.terrains import Plane

ROOT = Path(__file__).resolve().parent.parent
KINDS = {"box.obj": "closed", "capsule_mm.obj": "closed, millimetres",
         "cone.obj": "closed, Blender UVs", "cylinder.obj": "closed, Blender UVs",
         "inside_out.ply": "inside out", "open_scan.obj": "open scan",
         "suzanne.obj": "open, 3 shells (Blender)", "teapot.obj": "4 overlapping shells",
         "animal.obj": "thin limbs, 8 shells", "uv_egg.glb": "UV-seamed (glTF)",
         "uv_sphere_unwelded.obj": "UV-seamed (OBJ)", "washer.stl": "CAD part with a hole",
         "torus_70k.obj": "closed, 70,000 triangles"}
DURATION, DT = 10.0, 1 / 60


def models(folder: Path) -> None:
    spec = importlib.util.spec_from_file_location("make_test_models",
                                                  ROOT / "scripts" / "make_test_models.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    module.everything(folder)


def cold_build(body: MeshBody) -> float:
    mesh_module._cached_lattice.cache_clear()
    meshfiles._read_file.cache_clear()
    start = time.perf_counter()
    body.validate("bodies.0")
    body.build()
    return time.perf_counter() - start


def drop(path: Path) -> dict:
    size = float(np.max(np.ptp(MeshBody(file=str(path)).solid().vertices, axis=0)))
    body = MeshBody(file=str(path), scale=2.0 / size, rotation_degrees=30.0,
                    rotation_axis=(1.0, 0.0, 1.0))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        build = cold_build(body)
        body.position = (0.0, 0.5 - float(body.mesh().vertices[:, 1].min()), 0.0)
        simulation = springsim.Simulation(Scene(bodies=[body], terrains=[Plane(point=(0, 0, 0))],
                                                integrator="implicit_euler", dt=DT))
    lowest = np.inf
    for _ in range(round(DURATION / DT)):
        simulation.step(1)
        lowest = min(lowest, float(simulation.surfaces()[0].vertices[:, 1].min()))
    lattice = body.lattice()
    return {"vertices": len(body.mesh().vertices), "particles": len(lattice.positions),
            "spacing": lattice.spacing, "build": build, "lowest": lowest,
            "speed": float(np.linalg.norm(simulation.velocities, axis=1).max()),
            "centre": float(np.linalg.norm(simulation.velocities.mean(axis=0))),
            "warned": "yes" if caught else "no"}


def main() -> None:
    print(f"{date.today()}, {platform.processor() or platform.machine()}, Python "
          f"{sys.version.split()[0]}, springsim {springsim.__version__}")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        models(folder)
        print("\n| model | kind | file vertices | particles | spacing (m) | build (s) | "
              "lowest vertex (cm) | centre of mass at the end (m/s) | fastest particle at the end (m/s) | "
              "warning |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        worst = np.inf
        for name, kind in KINDS.items():
            row = drop(folder / name)
            worst = min(worst, row["lowest"])
            print(f"| {name} | {kind} | {row['vertices']:,} | {row['particles']:,} | "
                  f"{row['spacing']:.4g} | {row['build']:.2f} | {100 * row['lowest']:+.2f} | "
                  f"{row['centre']:.3f} | {row['speed']:.3f} | {row['warned']} |", flush=True)
        print(f"\nlowest vertex of all: {100 * worst:+.2f} cm (bar: >= -2 cm)")
        times = [cold_build(MeshBody(file=str(folder / "torus_70k.obj"))) for _ in range(5)]
        print(f"70,000-triangle model, cold builds: {min(times):.2f} to {max(times):.2f} s "
              "(bar: < 5 s)")


if __name__ == "__main__":
    main()
