"""The figure of the ``cape`` preset: a body, a head, arms and legs that swing as it walks a
turning path, baked to a point cache (PC2) as Blender bakes a character an armature moves.

Each part is a mesh that its bone turns rigidly (legs and arms swing about the hips and
shoulders, opposite in phase), and the whole figure walks forward at WALK_SPEED while it turns at
TURN_RATE: together a mesh whose vertices move every frame, a deforming terrain
(terrains/deforming_mesh.py) of about 10,000 triangles. The files are made once per version
into the user's cache folder, written whole (safe_files.py), and are the same bytes on every
machine: nothing in them is random.
"""
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from .export.pc2 import encode
from .safe_files import atomic_output

VERSION = 2
FPS = 30.0
SECONDS = 6.0
WALK_SPEED = 0.8            # m/s along its heading
TURN_RATE = 0.35            # rad/s about the vertical
STRIDE_RATE = 2 * np.pi * 0.9   # rad/s: a leg swings forward and back 0.9 times a second
NECK = np.array([0.0, 1.575, 0.0])   # the top of the body, where the cape's front edge is pinned
NECK_HALF_WIDTH = 0.12                # m: the pinned stretch of it, clear of the swinging arms


class Part(NamedTuple):
    """A mesh of the figure, the point its bone turns about, how far (rad) and in which phase."""

    vertices: np.ndarray
    faces: np.ndarray
    pivot: tuple
    swing: float
    phase: float


def parts() -> list[Part]:
    import trimesh

    def capsule(height, radius, count, centre):
        """An upright capsule: trimesh's lies along z; turned by -90 degrees about x (a
        rotation, so that its faces stay wound outwards)."""
        mesh = trimesh.creation.capsule(height=height, radius=radius, count=count)
        x, y, z = np.asarray(mesh.vertices).T
        return np.stack([x, z, -y], axis=1) + centre, np.asarray(mesh.faces)

    head = trimesh.creation.icosphere(subdivisions=3, radius=0.12)
    pieces = [(*capsule(0.45, 0.2, [64, 32], [0.0, 1.15, 0.0]), (0.0, 1.15, 0.0), 0.0, 0.0),
              (np.asarray(head.vertices) + [0.0, 1.72, 0.0], np.asarray(head.faces),
               (0.0, 1.6, 0.0), 0.0, 0.0)]
    for side, phase in ((-1.0, 0.0), (1.0, np.pi)):
        pieces.append((*capsule(0.62, 0.08, [32, 24], [0.11 * side, 0.45, 0.0]),
                       (0.11 * side, 0.85, 0.0), 0.45, phase))
        pieces.append((*capsule(0.5, 0.055, [24, 16], [0.29 * side, 1.13, 0.0]),
                       (0.29 * side, 1.42, 0.0), 0.35, phase + np.pi))
    return [Part(*piece) for piece in pieces]


def root(t: float) -> tuple[np.ndarray, np.ndarray]:
    """(R, c): the figure's turn and place at time t; a point x of it is at c + R x."""
    heading = TURN_RATE * t
    turn = Rotation.from_rotvec([0.0, heading, 0.0]).as_matrix()
    # walking forward (+z in its own frame) while turning: an arc of radius v / w
    radius = WALK_SPEED / TURN_RATE
    centre = np.array([radius * (1.0 - np.cos(heading)), 0.0, radius * np.sin(heading)])
    return turn, centre


def posed(t: float, pieces: list[Part]) -> np.ndarray:
    """Every vertex of the figure at time t (V, 3), parts in order."""
    turn, centre = root(t)
    out = []
    for part in pieces:
        angle = part.swing * np.sin(STRIDE_RATE * t + part.phase)
        swing = Rotation.from_rotvec([angle, 0.0, 0.0]).as_matrix()   # about the hip's x axis
        local = (part.vertices - part.pivot) @ swing.T + part.pivot
        out.append(local @ turn.T + centre)
    return np.concatenate(out)


class FigureFiles(NamedTuple):
    mesh: Path
    cache: Path


def figure_paths() -> FigureFiles:
    """Where the figure's files are made (in the user's cache), made or not."""
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    folder = base / "springsim" / f"walking-figure-{VERSION}"
    return FigureFiles(folder / "figure.obj", folder / "figure.pc2")


def figure_files() -> FigureFiles:
    """The figure's OBJ (its rest pose at time 0) and PC2 (every frame), made once."""
    files = figure_paths()
    if files.mesh.is_file() and files.cache.is_file():
        return files
    files.mesh.parent.mkdir(parents=True, exist_ok=True)
    pieces = parts()
    faces, offset = [], 0
    for part in pieces:
        faces.append(part.faces + offset)
        offset += len(part.vertices)
    rest = posed(0.0, pieces)
    times = np.arange(int(round(SECONDS * FPS)) + 1) / FPS
    with atomic_output(files.cache) as file:
        encode(file, np.stack([posed(t, pieces) for t in times]), times, FPS, 0)
    with atomic_output(files.mesh) as file:
        file.write("".join(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in rest).encode())
        file.write("".join(f"f {a + 1} {b + 1} {c + 1}\n"
                           for a, b, c in np.concatenate(faces)).encode())
    return files
