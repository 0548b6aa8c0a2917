"""The plane ``phi = n . (x - p)``, and the reference's tilted plane (a Plane through the origin
with normal (1, 1, 0), normalized: the course framework forgot to)."""
from dataclasses import dataclass

import numpy as np

from .._jit import kernel
from ..errors import is_finite, require
from .base import Contact, register


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

    def display_mesh(self, near, extent: float):
        """A checkered square patch under the bodies, moved along when they leave its middle
        (a plane is infinite)."""
        from ..render.terrain_meshes import plane_display_mesh

        return plane_display_mesh(self.point, self.unit_normal(), near, extent)

    def points_near(self, corners: np.ndarray, size: float) -> np.ndarray:
        return corners - np.outer(self.signed_distance(corners), self.unit_normal())

    def menu_name(self) -> str:
        """The viewer's terrain button this plane is (the course framework's two planes)."""
        return "plane" if self.unit_normal()[1] > 0.999 else "tilted plane"


def tilted_plane(**overrides) -> Plane:
    """The reference's tilted plane: through the origin, normal (1, 1, 0) normalized."""
    return Plane(**{"point": (0.0, 0.0, 0.0), "normal": (1.0, 1.0, 0.0), **overrides})


register(Plane, {"plane": Plane, "tilted_plane": tilted_plane}, order=0)
