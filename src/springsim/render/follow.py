"""The cameras of a video (``camera_path``) and of a window's first picture: by default one that
frames what moves and follows it.

What moves is the bodies (the simulated particles: cloth, jelly, balls) and the terrains that move
with them when they are of the bodies' size (the cape's walking figure, a sweeping ball, a
conveyor's platform); a still terrain, or one much larger than the bodies, is only background.

The ``auto`` view looks at the bodies from the side they are on of the terrains that move with
them (the cape hangs behind the figure: it is seen from behind), turned a three-quarter angle
(THREE_QUARTER) off that side; with no such terrain beside them, from the fixed ``auto``
direction. Each frame the camera looks at the middle of the subject's box, from just far enough
that the subject fills at most FILL of the picture's half width and height. The look-at point
and the direction are smoothed over time (a Gaussian over SMOOTHING seconds, both ways in time,
so that it never lags), and the distance is a running maximum followed by a running mean over
the same window: never shorter than what the frame needs, and without jumps.
"""
import math
from typing import NamedTuple

import numpy as np
from scipy.ndimage import gaussian_filter1d, maximum_filter1d, uniform_filter1d

from ..errors import require
from .camera import (FOV_DEGREES, VIEWS, Camera, body_points, frame_along, scene_points,
                     view_direction)

FILL = 0.8                  # the subject's farthest point at 80% of the half width or height
SMOOTHING = 0.5             # s: the time scale of the camera's motion
TERRAIN_WITH_BODIES = 4.0   # a moving terrain at most this many times the bodies' size is framed
SIDEWAYS = 0.1              # bodies beside a moving terrain by this fraction of their size
THREE_QUARTER = 35.0        # degrees: turned off the side the bodies are on
MOST_TERRAIN_POINTS = 2000  # per terrain and frame (the box is all that matters)
CAMERA_NAMES = (*VIEWS, "still", "follow")
FACING = ("auto", "follow", "still")   # views that face the side the bodies are on


class Subject(NamedTuple):
    """What the camera frames at each of F frames."""

    points: list               # F arrays (n, 3): the bodies' points and the moving terrains'
    bodies: np.ndarray         # (F, 3) the middle of the bodies' box
    movers: np.ndarray | None  # (F, 3) the middle of the moving terrains' box, if any
    size: float                # m: the largest side of the bodies' box at the first frame


def subject(model, positions, times=None) -> Subject:
    """The subject of each frame of ``positions`` (F, P, 3) at ``times`` (F,) s (the terrains
    where they are then; at 0 s when no times are given)."""
    positions = np.asarray(positions, float)
    times = np.zeros(len(positions)) if times is None else np.asarray(times, float)
    bodies = [body_points(model, frame) for frame in positions]
    movers = moving_with_bodies(model, bodies[0])
    points, mover_middles = [], []
    for body, t in zip(bodies, times):
        moving = [thinned(terrain.vertices_at(vertices, t)) for terrain, vertices in movers]
        points.append(np.concatenate([body, *moving]))
        if moving:
            mover_middles.append(box_middle(np.concatenate(moving)))
    return Subject(points, np.array([box_middle(body) for body in bodies]),
                   np.array(mover_middles) if movers else None, extent(bodies[0]))


def moving_with_bodies(model, bodies: np.ndarray) -> list:
    """(terrain, display vertices as placed) of each terrain that moves and is at most
    TERRAIN_WITH_BODIES times the size of the ``bodies`` points."""
    size = extent(bodies)
    found = []
    for terrain in model.terrains:
        if not terrain.moves():
            continue
        vertices = terrain.display_mesh(bodies.mean(axis=0), size).vertices
        if extent(vertices) <= TERRAIN_WITH_BODIES * size:
            found.append((terrain, vertices))
    return found


def extent(points: np.ndarray) -> float:
    """The largest side (m) of the points' box."""
    return max(float(np.max(np.ptp(points, axis=0))), 1e-3)


def thinned(points: np.ndarray) -> np.ndarray:
    return points[::max(1, len(points) // MOST_TERRAIN_POINTS)]


def box_middle(points: np.ndarray) -> np.ndarray:
    return (points.min(axis=0) + points.max(axis=0)) / 2


def middle_across(points: np.ndarray, toward_eye: np.ndarray) -> np.ndarray:
    """The middle of the points' box in the axes of a view along ``toward_eye`` (what is seen
    as the middle of the picture, before perspective)."""
    right, up, _ = Camera(eye=toward_eye, target=np.zeros(3)).basis()
    axes = np.stack([right, up, toward_eye])
    return box_middle(points @ axes.T) @ axes


def facing(seen: Subject, azimuth: float, elevation: float, frames_smoothed: float) -> np.ndarray:
    """(F, 3) unit vectors from the look-at point towards the eye for the ``auto`` view: from
    the side the bodies are on of the terrains that move with them, turned THREE_QUARTER
    degrees, when they are beside them at the first frame; else from (azimuth, elevation)."""
    count = len(seen.points)
    fixed = np.tile(view_direction(azimuth, elevation), (count, 1))
    if seen.movers is None:
        return fixed
    beside = seen.bodies - seen.movers
    beside[:, 1] = 0.0
    if np.linalg.norm(beside[0]) <= SIDEWAYS * seen.size:
        return fixed
    # smoothed as vectors (an angle would wrap at 180 degrees), then turned and lifted
    beside = gaussian_filter1d(beside, frames_smoothed, axis=0, mode="nearest") \
        if frames_smoothed > 0 else beside
    sides = np.degrees(np.arctan2(beside[:, 0], beside[:, 2]))
    return np.array([view_direction(side + THREE_QUARTER, elevation) for side in sides])


def fit_distance(points, target, toward_eye, aspect: float, fov_degrees: float) -> float:
    """The least distance from ``target`` along ``toward_eye`` at which every point lies within
    FILL of the picture's half width and height: a point at offset p from the target appears at
    (p.right, p.up) over a depth of D - p.d (d towards the eye), and fits when
    |p.right| <= (D - p.d) FILL tan(half width angle), and likewise upwards."""
    right, up, _ = Camera(eye=toward_eye, target=np.zeros(3)).basis()
    offsets = np.asarray(points, float) - target
    along = offsets @ toward_eye
    tan_vertical = FILL * math.tan(math.radians(fov_degrees) / 2)
    tan_horizontal = tan_vertical * aspect
    return float(max(np.max(np.abs(offsets @ right) / tan_horizontal + along),
                     np.max(np.abs(offsets @ up) / tan_vertical + along), 1e-3))


def follow(seen: Subject, directions: np.ndarray, aspect: float, frames_smoothed: float,
           fov_degrees: float) -> list:
    """One camera a frame that looks at the subject's smoothed middle along ``directions``
    (F, 3), never closer than the frame needs (a running maximum, then a running mean, over
    the same window: the mean of maxima that each include the frame is at least its need)."""
    middles = np.array([middle_across(points, direction)
                        for points, direction in zip(seen.points, directions)])
    targets = gaussian_filter1d(middles, frames_smoothed, axis=0, mode="nearest") \
        if frames_smoothed > 0 else middles
    needed = np.array([fit_distance(points, target, direction, aspect, fov_degrees)
                       for points, target, direction in zip(seen.points, targets, directions)])
    window = 2 * math.ceil(2 * frames_smoothed) + 1
    distances = uniform_filter1d(maximum_filter1d(needed, window, mode="nearest"), window,
                                 mode="nearest")
    # a mean of values at least ``needed`` is at least it; the maximum keeps rounding honest
    distances = np.maximum(distances, needed)
    return [Camera(eye=target + distance * direction, target=target, fov_degrees=fov_degrees)
            for target, distance, direction in zip(targets, distances, directions)]


def frames_per_smoothing(times) -> float:
    """SMOOTHING seconds in frames of ``times`` (0 for a single frame: nothing to smooth)."""
    if times is None or len(times) < 2:
        return 0.0
    step = float(np.median(np.diff(np.asarray(times, float))))
    return SMOOTHING / step if step > 0 else 0.0


def camera_path(name: str, model, positions, aspect: float, times=None) -> list:
    """One camera per frame of ``positions`` (F, P, 3) at ``times`` (F,) s (frames 1/30 s
    apart when not given).

    ``auto`` (and its older name ``follow``) frames what moves and follows it (follow.py), from
    the side of the bodies the terrains moving with them leave open; ``front``, ``side`` and
    ``top`` follow it alike from their fixed directions; ``still`` stays put and frames the
    whole motion and the terrain near it, from the ``auto`` direction of the first frame.
    """
    require(name in CAMERA_NAMES, "camera", name, "must be one of " + ", ".join(CAMERA_NAMES))
    positions = np.asarray(positions, float)
    times = np.arange(len(positions)) / 30.0 if times is None else np.asarray(times, float)
    if name == "still":
        return [still_camera("auto", model, positions, aspect, times)] * len(positions)
    seen = subject(model, positions, times)
    smoothing = frames_per_smoothing(times)
    return follow(seen, directions(name, seen, smoothing), aspect, smoothing, FOV_DEGREES)


def directions(view: str, seen, smoothing: float) -> np.ndarray:
    """(F, 3) unit vectors towards the eye: the named direction, or ``auto``'s (facing)."""
    if view in FACING:
        return facing(seen, *VIEWS["auto"], smoothing)
    return np.tile(view_direction(*VIEWS[view]), (len(seen.points), 1))


def still_camera(view: str, model, positions, aspect: float, times=None) -> Camera:
    """One camera for the whole motion ``positions`` (F, P, 3): every frame's bodies and the
    terrain near them in sight, from the named direction (``auto``'s as at the first frame);
    for a replay, whose viewer turns the camera at will."""
    positions = np.asarray(positions, float)
    first = subject(model, positions[:1], None if times is None else times[:1])
    toward_eye = directions(view, first, 0.0)[0]
    return frame_along(scene_points(model, positions), toward_eye, aspect)


def start_camera(view: str, model, positions, aspect: float, time: float = 0.0) -> Camera:
    """The camera of a window's first picture of the state ``positions`` (P, 3) at ``time`` s
    (and of its view buttons): ``camera_path``'s for that one frame."""
    return camera_path(view, model, np.asarray(positions)[None], aspect, [time])[0]
