"""A solid sphere; particles collide with its outside: ``phi = |x - c| - R``, normal
``(x - c)/|x - c|``."""
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from ..errors import is_finite, require
from .base import Contact, register
from .display import TerrainMesh, sphere_mesh, sphere_points_near


@kernel
def outward(row, x0, x1, x2):
    """Distance from the centre (row 0-2) and the unit vector away from it."""
    dx, dy, dz = x0 - row[0], x1 - row[1], x2 - row[2]
    r = math.sqrt(dx * dx + dy * dy + dz * dz)
    if r == 0.0:
        return r, 0.0, 1.0, 0.0   # at the very centre any direction will do
    return r, dx / r, dy / r, dz / r


@kernel
def sphere_distance(row, data, x0, x1, x2):
    """row: the centre (0-2) and the radius (3)."""
    r, nx, ny, nz = outward(row, x0, x1, x2)
    return r - row[3], nx, ny, nz


@dataclass
class Sphere(Contact):
    """A solid sphere; particles collide with its outside. Mass kept for the reference, unused."""

    center: tuple = (0.0, -1.0, 0.0)
    radius: float = 3.0
    mass: float = 10.0

    distance_kernel = sphere_distance

    def anchor(self) -> tuple:
        return tuple(self.center)   # what a motion turns it about by default

    def thickness(self) -> float:
        return 2.0 * float(self.radius)

    def motion_probes(self) -> np.ndarray:
        """The centre and 14 points of the surface: the axes' ends and the cube diagonals'."""
        axes = np.vstack([np.eye(3), -np.eye(3),
                          np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1)
                                    for z in (-1, 1)]) / math.sqrt(3)])
        centre = np.asarray(self.center, float)
        return np.vstack([centre, centre + float(self.radius) * axes])

    def validate(self, key: str) -> None:
        self.validate_contact(key)
        require(np.shape(self.center) == (3,) and is_finite(self.center), f"{key}.center",
                self.center, "must be three finite numbers (m)")
        require(is_finite(self.radius) and self.radius > 0, f"{key}.radius", self.radius,
                "must be > 0 m")

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        return np.linalg.norm(x - np.asarray(self.center, float), axis=-1) - self.radius - radius

    def pack(self, data_start: int, largest_offset: float = 0.0):
        return [*np.asarray(self.center, float), float(self.radius)], np.empty(0)

    def adjoint_shape(self, row) -> "Round":
        return Round(row[0:3].copy(), float(row[3]), 1.0)

    def display_mesh(self, near, extent: float):
        return TerrainMesh(*sphere_mesh(self.center, self.radius))

    def export_mesh(self, positions):
        return sphere_mesh(self.center, self.radius)

    def points_near(self, corners: np.ndarray, size: float) -> np.ndarray:
        return sphere_points_near(self.center, self.radius, corners, size, lower_half=False)

    def menu_name(self) -> str:
        return "sphere"


class Round(NamedTuple):
    """A sphere's adjoint shape, its outside (side +1) or inside (side -1, a bowl):
    phi = side (|x - c| - R) - offset, n = side (x - c) / |x - c|, and at the very centre
    n = side (0, 1, 0), as the kernels choose."""

    center: np.ndarray
    radius: float
    side: float

    def distance(self, x, offset):
        return self.side * (np.linalg.norm(x - self.center, axis=1) - self.radius) - offset

    def normals(self, x):
        d = x - self.center
        length = np.linalg.norm(d, axis=1)
        unit = np.where(length[:, None] > 0.0, d / np.where(length > 0.0, length, 1.0)[:, None],
                        np.array([0.0, 1.0, 0.0]))
        return self.side * unit

    def gradient(self, x):
        return self.normals(x)

    def curvature(self, x):
        d = x - self.center
        length = np.linalg.norm(d, axis=1)
        safe = np.where(length > 0.0, length, 1.0)
        unit = d / safe[:, None]
        projector = np.eye(3) - unit[:, :, None] * unit[:, None, :]
        return (self.side * np.where(length > 0.0, 1.0 / safe, 0.0))[:, None, None] * projector


register(Sphere, {"sphere": Sphere}, order=1)
