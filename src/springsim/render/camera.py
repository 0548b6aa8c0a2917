"""Cameras that frame a cloud of points (the named cameras a video uses are in follow.py).

Directions are given as azimuth (degrees from +z towards +x) and elevation (degrees above the
horizontal plane, y up). A camera looks at the middle of a cloud of points from just far enough
that every point lies inside the picture.
"""
import math
from dataclasses import dataclass

import numpy as np


FOV_DEGREES = 40.0
MARGIN = 1.08
VIEWS = {"auto": (35.0, 25.0), "front": (0.0, 8.0), "side": (90.0, 8.0), "top": (0.0, 88.0)}


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

    def shifted(self, pixels_right: float, height: int) -> "Camera":
        """The same view moved sideways so that the target appears ``pixels_right`` px right
        of the picture's centre (to keep a scene clear of a panel on the left)."""
        right, _, _ = self.basis()
        distance = float(np.linalg.norm(np.asarray(self.target) - self.eye))
        metres_per_pixel = 2 * distance * math.tan(math.radians(self.fov_degrees) / 2) / height
        move = -pixels_right * metres_per_pixel * right
        return Camera(eye=self.eye + move, target=self.target + move, up=self.up,
                      fov_degrees=self.fov_degrees)

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


def frame_points(points, azimuth: float, elevation: float, aspect: float,
                 fov_degrees: float = FOV_DEGREES) -> Camera:
    """The camera that sees every point from (azimuth, elevation), as close as it can."""
    return frame_along(points, view_direction(azimuth, elevation), aspect, fov_degrees)


def frame_along(points, toward_eye, aspect: float, fov_degrees: float = FOV_DEGREES) -> Camera:
    """The camera that sees every point looking against ``toward_eye`` (a unit vector from the
    target to the eye), as close as it can.

    It looks at the middle of the points' extent across the view; a point at offset p from
    there appears at (p.right, p.up) over a depth of D - p.d, with d the unit vector towards the
    eye, and fits when |p.right| <= (D - p.d) tan(half width angle), and likewise upwards: the
    least distance D that fits every point follows.
    """
    points = np.asarray(points, float).reshape(-1, 3)
    toward_eye = np.asarray(toward_eye, float)
    right, up, _ = Camera(eye=toward_eye, target=np.zeros(3)).basis()
    axes = np.stack([right, up, toward_eye])
    local = points @ axes.T
    center = ((local.min(axis=0) + local.max(axis=0)) / 2) @ axes
    offsets = points - center
    along = offsets @ toward_eye
    tan_vertical = math.tan(math.radians(fov_degrees) / 2)
    tan_horizontal = tan_vertical * aspect
    distance = max(np.max(np.abs(offsets @ right) / tan_horizontal + along),
                   np.max(np.abs(offsets @ up) / tan_vertical + along))
    distance = MARGIN * max(distance, 1e-3)
    return Camera(eye=center + distance * toward_eye, target=center, fov_degrees=fov_degrees)


def body_points(model, positions, most: int = 20_000) -> np.ndarray:
    """Particles of one frame (P, 3) or many (F, P, 3), thinned to about ``most`` points; a ball
    adds the six points where its surface meets the axes through its centre."""
    x = np.asarray(positions, float).reshape(-1, model.particle_count, 3)
    radius = model.arrays.radius
    balls = np.flatnonzero(radius > 0)
    stride = max(1, x.shape[0] * x.shape[1] // most)
    points = [x.reshape(-1, 3)[::stride]]
    for axis in np.concatenate([np.eye(3), -np.eye(3)]):
        points.append((x[:, balls] + radius[balls, None] * axis).reshape(-1, 3))
    return np.concatenate(points)


def scene_points(model, positions) -> np.ndarray:
    """The bodies' points and the parts of the terrains near them (never a whole plane)."""
    bodies = body_points(model, positions)
    low, high = bodies.min(axis=0), bodies.max(axis=0)
    corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                        for z in (low[2], high[2])])
    size = float(np.linalg.norm(high - low))
    near = [terrain.points_near(corners, size) for terrain in model.terrains]
    return np.concatenate([bodies, *near])


def apply_camera(camera: Camera) -> None:
    """Point polyscope's view along ``camera`` (and orbit around its target)."""
    import polyscope as ps

    ps.set_vertical_fov_degrees(camera.fov_degrees)
    # polyscope's clip planes scale with the length scale: keep the whole view inside them
    ps.set_length_scale(float(np.linalg.norm(np.asarray(camera.eye) - camera.target)))
    ps.look_at_dir(camera.eye, camera.target, camera.up)
    ps.set_view_center_raw(camera.target)
