"""The plane ``phi = n . (x - p)``, and the reference's tilted plane (a Plane through the origin
with normal (1, 1, 0), normalized: the course framework forgot to)."""
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from ..errors import is_finite, require
from .base import Contact, register
from .display import plane_display_mesh, plane_quad


@kernel
def plane_distance(row, data, x0, x1, x2):
    """row: the point (0-2) and the unit normal (3-5)."""
    nx, ny, nz = row[3], row[4], row[5]
    return (x0 - row[0]) * nx + (x1 - row[1]) * ny + (x2 - row[2]) * nz, nx, ny, nz


@dataclass
class Plane(Contact):
    point: tuple = (0.0, -1.0, 0.0)
    normal: tuple = (0.0, 1.0, 0.0)

    distance_kernel = plane_distance

    def anchor(self) -> tuple:
        return tuple(self.point)   # what a motion turns it about by default

    def validate(self, key: str) -> None:
        self.validate_contact(key)
        require(np.shape(self.point) == (3,) and is_finite(self.point), f"{key}.point",
                self.point, "must be three finite numbers (m)")
        require(np.shape(self.normal) == (3,) and is_finite(self.normal)
                and np.linalg.norm(self.normal) > 0, f"{key}.normal", self.normal,
                "must be a non-zero vector")

    def unit_normal(self) -> np.ndarray:
        normal = np.asarray(self.normal, float)
        return normal / np.linalg.norm(normal)

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        return (x - np.asarray(self.point, float)) @ self.unit_normal() - radius

    def pack(self, data_start: int, largest_offset: float = 0.0):
        return [*np.asarray(self.point, float), *self.unit_normal()], np.empty(0)

    def adjoint_shape(self, row) -> "Flat":
        return Flat(row[0:3].copy(), row[3:6].copy())

    def display_mesh(self, near, extent: float):
        """A checkered square patch under the bodies, moved along when they leave its middle
        (a plane is infinite)."""
        return plane_display_mesh(self.point, self.unit_normal(), near, extent)

    def export_mesh(self, positions):
        """One square under the whole motion (display.plane_quad)."""
        return plane_quad(self.point, self.unit_normal(), positions)

    def points_near(self, corners: np.ndarray, size: float) -> np.ndarray:
        return corners - np.outer(self.signed_distance(corners), self.unit_normal())

    def menu_name(self) -> str:
        """The viewer's terrain button this plane is (the course framework's two planes)."""
        return "plane" if self.unit_normal()[1] > 0.999 else "tilted plane"


class Flat(NamedTuple):
    """A plane's adjoint shape: phi = n . (x - p) - offset, the same normal everywhere."""

    point: np.ndarray
    normal: np.ndarray

    def distance(self, x, offset):
        p, n = self.point, self.normal
        return ((x[:, 0] - p[0]) * n[0] + (x[:, 1] - p[1]) * n[1] + (x[:, 2] - p[2]) * n[2]
                - offset)

    def normals(self, x):
        return np.broadcast_to(self.normal, x.shape)

    def least_distance(self, x, offset, free):
        """The least distance of a free particle, in one compiled pass (a bound for the
        adjoint's far test, gradients/contact.reach, where distance's rounding does not
        matter)."""
        return least_height(x, self.normal, offset, free) - float(self.point @ self.normal)

    def gradient(self, x):
        return self.normals(x)

    def curvature(self, x):
        """(dn/dx)^T per particle (K, 3, 3); None where it is zero everywhere."""
        return None


@kernel
def least_height(x, normal, offset, free):
    """The least n . x - offset of a free particle (inf where none is free)."""
    least = math.inf
    for i in range(x.shape[0]):
        if free[i]:
            height = x[i, 0] * normal[0] + x[i, 1] * normal[1] + x[i, 2] * normal[2] - offset[i]
            least = min(least, height)
    return least


def tilted_plane(**overrides) -> Plane:
    """The reference's tilted plane: through the origin, normal (1, 1, 0) normalized."""
    return Plane(**{"point": (0.0, 0.0, 0.0), "normal": (1.0, 1.0, 0.0), **overrides})


register(Plane, {"plane": Plane, "tilted_plane": tilted_plane}, order=0)
