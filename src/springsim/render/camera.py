"""Cameras that frame a scene: the bodies plus the part of the terrains near them.

Directions are given as azimuth (degrees from +z towards +x) and elevation (degrees above the
horizontal plane, y up). A camera looks at the centre of a box from far enough that every corner
of the box lies inside the picture, with a small margin.
"""
import math
from dataclasses import dataclass

import numpy as np

from ..errors import require
from ..terrains import Bowl, Plane, Sphere

FOV_DEGREES = 40.0
MARGIN = 1.08
VIEWS = {"auto": (35.0, 25.0), "front": (0.0, 8.0), "side": (90.0, 8.0), "top": (0.0, 88.0)}
CAMERA_NAMES = (*VIEWS, "follow")


@dataclass(frozen=True)
class Camera:
    eye: np.ndarray
    target: np.ndarray
    up: tuple = (0.0, 1.0, 0.0)
    fov_degrees: float = FOV_DEGREES   # vertical field of view

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """right, up and forward unit vectors of the camera."""
        forward = np.asarray(self.target, float) - np.asarray(self.eye, float)
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, self.up)
        right /= np.linalg.norm(right)
        return right, np.cross(right, forward), forward

    def project(self, points, width: int, height: int) -> np.ndarray:
        """Pixel coordinates (column, row from the top) of world points, as a pinhole camera."""
        right, up, forward = self.basis()
        relative = np.atleast_2d(points) - np.asarray(self.eye, float)
        depth = relative @ forward
        focal = 0.5 * height / math.tan(math.radians(self.fov_degrees) / 2)
        column = 0.5 * width + focal * (relative @ right) / depth
        row = 0.5 * height - focal * (relative @ up) / depth
        return np.stack([column, row], axis=1)


def view_direction(azimuth: float, elevation: float) -> np.ndarray:
    """Unit vector from the target towards the eye."""
    a, e = math.radians(azimuth), math.radians(elevation)
    return np.array([math.sin(a) * math.cos(e), math.sin(e), math.cos(a) * math.cos(e)])


def frame_box(low, high, azimuth: float, elevation: float, aspect: float,
              fov_degrees: float = FOV_DEGREES) -> Camera:
    """The camera looking at the box's centre from (azimuth, elevation), just far enough away.

    A corner at offset p from the centre appears at (p.right, p.up) over a depth of D - p.d,
    with d the unit vector towards the eye; it fits when |p.right| <= (D - p.d) tan(half width
    angle), and likewise upwards, which gives the least distance D for every corner.
    """
    low, high = np.asarray(low, float), np.asarray(high, float)
    center = (low + high) / 2
    toward_eye = view_direction(azimuth, elevation)
    camera = Camera(eye=center + toward_eye, target=center, fov_degrees=fov_degrees)
    right, up, _ = camera.basis()
    tan_vertical = math.tan(math.radians(fov_degrees) / 2)
    tan_horizontal = tan_vertical * aspect
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                        for z in (low[2], high[2])]) - center
    along = corners @ toward_eye
    distance = max(np.max(np.abs(corners @ right) / tan_horizontal + along),
                   np.max(np.abs(corners @ up) / tan_vertical + along))
    distance = MARGIN * max(distance, 1e-3)
    return Camera(eye=center + distance * toward_eye, target=center, fov_degrees=fov_degrees)


def body_box(model, positions) -> tuple[np.ndarray, np.ndarray]:
    """Bounding box (m) of every particle, balls with their radius, over one or many frames."""
    x = np.asarray(positions, float).reshape(-1, model.particle_count, 3)
    radius = model.arrays.radius[None, :, None]
    return np.min(x - radius, axis=(0, 1)), np.max(x + radius, axis=(0, 1))


def scene_box(model, positions) -> tuple[np.ndarray, np.ndarray]:
    """The bodies' box grown by the parts of the terrains near them (never a whole plane)."""
    low, high = body_box(model, positions)
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                        for z in (low[2], high[2])])
    size = float(np.linalg.norm(high - low))
    points = [corners]
    for terrain in model.terrains:
        points.append(_terrain_points_near(terrain, corners, size))
    points = np.concatenate(points)
    return points.min(axis=0), points.max(axis=0)


def _terrain_points_near(terrain, corners: np.ndarray, size: float) -> np.ndarray:
    if isinstance(terrain, Plane):
        n = terrain.unit_normal()
        return corners - np.outer(terrain.signed_distance(corners), n)
    center, radius = np.asarray(terrain.center, float), float(terrain.radius)
    if radius <= 2 * size:                     # small enough to show whole
        rim = np.array([radius, 0.0 if isinstance(terrain, Bowl) else radius, radius])
        return np.stack([center - radius, center + rim])
    if isinstance(terrain, Sphere):            # too big: the patch under the bodies
        offsets = corners - center
        return center + radius * offsets / np.linalg.norm(offsets, axis=1, keepdims=True)
    return corners


def camera_path(name: str, model, positions, aspect: float) -> list:
    """One camera per frame of ``positions`` (F, P, 3).

    ``auto``, ``front``, ``side`` and ``top`` stay put and frame the whole motion; ``follow``
    frames the first frame from the ``auto`` direction and then moves with the bodies' centre.
    """
    require(name in CAMERA_NAMES, "camera", name, "must be one of " + ", ".join(CAMERA_NAMES))
    positions = np.asarray(positions)
    if name != "follow":
        camera = frame_box(*scene_box(model, positions), *VIEWS[name], aspect)
        return [camera] * len(positions)
    first = frame_box(*scene_box(model, positions[0]), *VIEWS["auto"], aspect)
    centres = positions.mean(axis=1)
    shifts = centres - centres[0]
    return [Camera(eye=first.eye + s, target=first.target + s) for s in shifts]


def apply_camera(camera: Camera) -> None:
    """Point polyscope's view along ``camera`` (and orbit around its target)."""
    import polyscope as ps

    ps.set_vertical_fov_degrees(camera.fov_degrees)
    # polyscope's clip planes scale with the length scale: keep the whole view inside them
    ps.set_length_scale(float(np.linalg.norm(np.asarray(camera.eye) - camera.target)))
    ps.look_at_dir(camera.eye, camera.target, camera.up)
    ps.set_view_center_raw(camera.target)
