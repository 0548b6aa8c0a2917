"""Write the meshes the built-in mesh scenes use (src/springsim/meshes/), made here with
trimesh.creation and plain NumPy, so they are the project's own (same licence as springsim).

    .venv/bin/python scripts/make_meshes.py
"""
from pathlib import Path

import numpy as np
import trimesh

FOLDER = Path(__file__).resolve().parent.parent / "src" / "springsim" / "meshes"


def stairs(steps: int = 4, run: float = 2.5, rise: float = 0.5, width: float = 8.0,
           landing: float = 6.0) -> trimesh.Trimesh:
    """An open surface (a flight of stairs going down along +x to a floor at y = 0), treads and
    risers only, facing up and forward: an open terrain collides on the side its normals face."""
    vertices, faces = [], []

    def quad(a, b, c, d):   # wound so that the normal is (b - a) x (c - a)
        start = len(vertices)
        vertices.extend([a, b, c, d])
        faces.extend([[start, start + 1, start + 2], [start, start + 2, start + 3]])

    half = width / 2
    for i in range(steps + 1):
        x0, x1 = i * run, (i + 1) * run if i < steps else i * run + landing
        y = (steps - i) * rise
        quad((x0, y, half), (x1, y, half), (x1, y, -half), (x0, y, -half))          # tread, up
        if i < steps:                                                                  # riser, +x
            quad((x1, y, half), (x1, y - rise, half), (x1, y - rise, -half), (x1, y, -half))
    return trimesh.Trimesh(np.array(vertices, float), np.array(faces), process=True)


def main() -> None:
    FOLDER.mkdir(exist_ok=True)
    torus = trimesh.creation.torus(major_radius=1.0, minor_radius=0.4, major_sections=48,
                                   minor_sections=20)
    torus.export(FOLDER / "torus.obj")
    stairs().export(FOLDER / "stairs.obj")
    # the jelly-conveyor's platform: a 4 x 0.3 x 2 m box, its top face at y = 0
    platform = trimesh.creation.box(extents=(4.0, 0.3, 2.0))
    platform.apply_translation((0.0, -0.15, 0.0))
    platform.export(FOLDER / "platform.obj")
    for path in sorted(FOLDER.glob("*.obj")):
        print(path, path.stat().st_size, "bytes")


if __name__ == "__main__":
    main()
