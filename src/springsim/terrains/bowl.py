"""The inside of a sphere; particles stay within it: ``phi = R - |x - c|``, normal
``(c - x)/|x - c|``."""
import math
from dataclasses import dataclass

import numpy as np

from .._jit import kernel
from .base import register
from .display import TerrainMesh, bowl_mesh, sphere_points_near
from .sphere import Round, Sphere, outward


@kernel
def bowl_distance(row, data, x0, x1, x2):
    """row: the centre (0-2) and the radius (3)."""
    r, nx, ny, nz = outward(row, x0, x1, x2)
    return row[3] - r, -nx, -ny, -nz


@dataclass
class Bowl(Sphere):
    """The inside of a sphere; particles stay within it."""

    center: tuple = (2.0, 7.0, 1.0)
    radius: float = 7.0

    distance_kernel = bowl_distance

    def thickness(self) -> float:
        return math.inf   # its wall has no far side: particles stay inside

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        return self.radius - np.linalg.norm(x - np.asarray(self.center, float), axis=-1) - radius

    def adjoint_shape(self, row) -> Round:
        return Round(row[0:3].copy(), float(row[3]), -1.0)

    def display_mesh(self, near, extent: float):
        """The lower half, facing the centre, back faces culled: the near wall disappears from
        any viewpoint and the body inside stays in sight."""
        return TerrainMesh(*bowl_mesh(self.center, self.radius), color="bowl", cull_back=True)

    def export_mesh(self, positions):
        return bowl_mesh(self.center, self.radius)

    def points_near(self, corners: np.ndarray, size: float) -> np.ndarray:
        return sphere_points_near(self.center, self.radius, corners, size, lower_half=True)

    def menu_name(self) -> str:
        return "bowl"


register(Bowl, {"bowl": Bowl}, order=2)
