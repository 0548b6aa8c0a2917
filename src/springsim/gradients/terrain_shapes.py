"""The still terrains the explicit methods' contact adjoint follows (contact.py), each as its
distance, its normal and the normal's derivative in the position (the curvature, which the
gradient of a contact on a curved surface needs: where a particle touches decides which way the
surface pushes it).

An open set: a terrain kind joins by a function from the terrain to its shape in SHAPES. A
terrain without one (a mesh, whose normal comes from an interpolated distance grid) is not
followed, and touching it is refused (checks.py).
"""
from typing import NamedTuple

import numpy as np

from ..terrains import Bowl, Plane, Sphere


class Flat(NamedTuple):
    """A plane: phi = n . (x - p) - offset, the same normal everywhere."""

    point: np.ndarray
    normal: np.ndarray

    def distance(self, x, offset):
        p, n = self.point, self.normal
        return ((x[:, 0] - p[0]) * n[0] + (x[:, 1] - p[1]) * n[1] + (x[:, 2] - p[2]) * n[2]
                - offset)

    def normals(self, x):
        return np.broadcast_to(self.normal, x.shape)

    def curvature(self, x):
        """dn/dx per particle (K, 3, 3), symmetric; None where it is zero everywhere."""
        return None


class Round(NamedTuple):
    """A sphere's outside (side +1, terrains/sphere.py) or inside (side -1, a bowl):
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

    def curvature(self, x):
        d = x - self.center
        length = np.linalg.norm(d, axis=1)
        safe = np.where(length > 0.0, length, 1.0)
        unit = d / safe[:, None]
        projector = np.eye(3) - unit[:, :, None] * unit[:, None, :]
        return (self.side * np.where(length > 0.0, 1.0 / safe, 0.0))[:, None, None] * projector


def flat(terrain, row):
    return Flat(row[0:3].copy(), row[3:6].copy())


def sphere(terrain, row):
    return Round(row[0:3].copy(), float(row[3]), 1.0)


def bowl(terrain, row):
    return Round(row[0:3].copy(), float(row[3]), -1.0)


SHAPES = {Plane: flat, Sphere: sphere, Bowl: bowl}


def shape_of(terrain, row):
    """The shape of a still terrain (``row``: its model.terrain_parameters), or None."""
    make = SHAPES.get(type(terrain))
    return None if make is None else make(terrain, row)
