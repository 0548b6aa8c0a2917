"""The still terrains the explicit methods' contact adjoint follows (contact.py), each as its
distance, its normal, the distance's gradient and the normal's derivative in the position (the
curvature, which the gradient of a contact on a curved surface needs: where a particle touches
decides which way the surface pushes it).

An open set: a terrain kind joins by a function from the terrain to its shape in SHAPES. A
terrain that moves rigidly (motion.py) is its shape where it was placed, ``Moving`` at the pose
of the force time; a terrain without a shape, or one that deforms, is not followed, and touching
it is refused (checks.py).

``curvature`` gives (dn/dx)^T, the transpose that vector-Jacobian products take; for a plane, a
sphere and a bowl dn/dx is symmetric. ``gradient`` gives grad phi, which is the normal for an
exact distance; a mesh's trilinear distance grid has a normal of its gradient's direction, and
a gradient whose length is only near 1.
"""
from typing import NamedTuple

import numpy as np

from ..motion import POSE, pose_into
from ..terrains import Bowl, MeshTerrain, Plane, Sphere
from ..terrains.mesh import trilinear as mesh_trilinear
from .clock import FORCE_TIME


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

    def gradient(self, x):
        return self.normals(x)

    def curvature(self, x):
        """(dn/dx)^T per particle (K, 3, 3); None where it is zero everywhere."""
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

    def gradient(self, x):
        return self.normals(x)

    def curvature(self, x):
        d = x - self.center
        length = np.linalg.norm(d, axis=1)
        safe = np.where(length > 0.0, length, 1.0)
        unit = d / safe[:, None]
        projector = np.eye(3) - unit[:, :, None] * unit[:, None, :]
        return (self.side * np.where(length > 0.0, 1.0 / safe, 0.0))[:, None, None] * projector


class Gridded(NamedTuple):
    """A still mesh's signed distance grid (terrains/mesh.py), trilinear in each cell as
    ``mesh_distance`` interpolates it, with the kernel's arithmetic: phi, the normal (the
    gradient's direction), the gradient, and the normal's derivative from the trilinear
    function's mixed second derivatives (it has no pure ones). Beyond the grid (free space,
    never touched) the normal points away from it and the curvature is zero."""

    origin: np.ndarray
    inverse: float          # 1 / the cell size
    values: np.ndarray      # (n0, n1, n2)

    def cells(self, x):
        """(the trilinear pieces, the offset beyond the grid in cells (K, 3))."""
        n = np.array(self.values.shape)
        u = (x - self.origin) * self.inverse
        clamped = np.minimum(np.maximum(u, 0.0), n - 1.0)
        index = np.minimum(clamped.astype(np.int64), n - 2)
        f = clamped - index
        i, j, k = index.T
        c = {(a, b, d): self.values[i + a, j + b, k + d]
             for a in (0, 1) for b in (0, 1) for d in (0, 1)}
        return trilinear(c, f[:, 0], f[:, 1], f[:, 2]), u - clamped

    def distance(self, x, offset):
        (phi, _, _), beyond = self.cells(x)
        outside = np.linalg.norm(beyond, axis=1)
        return np.where(outside > 0.0, outside / self.inverse + np.maximum(phi, 0.0), phi) \
            - offset

    def gradient(self, x):
        (_, g, _), beyond = self.cells(x)
        return np.where(np.any(beyond != 0.0, axis=1)[:, None], unit_normal(g, beyond),
                        g * self.inverse)

    def normals(self, x):
        (_, g, _), beyond = self.cells(x)
        return unit_normal(g, beyond)

    def curvature(self, x):
        """(dn/dx)^T = H (I - n n^T) / (|g| cell), H the cell's mixed second derivatives."""
        (_, g, hessian), beyond = self.cells(x)
        size = np.linalg.norm(g, axis=1)
        n = g / np.where(size > 0.0, size, 1.0)[:, None]
        projector = np.eye(3) - n[:, :, None] * n[:, None, :]
        scale = np.where((size > 0.0) & ~np.any(beyond != 0.0, axis=1),
                         self.inverse / np.where(size > 0.0, size, 1.0), 0.0)
        return scale[:, None, None] * np.einsum("kij,kjl->kil", hessian, projector)


def unit_normal(g, beyond):
    """mesh_distance's normal: g / |g| ((0, 1, 0) where g is zero), or away from the grid
    beyond it."""
    size = np.linalg.norm(g, axis=1)
    n = np.where(size[:, None] > 0.0, g / np.where(size > 0.0, size, 1.0)[:, None],
                 np.array([0.0, 1.0, 0.0]))
    outside = np.linalg.norm(beyond, axis=1)
    away = beyond / np.where(outside > 0.0, outside, 1.0)[:, None]
    return np.where(outside[:, None] > 0.0, away, n)


def trilinear(c, fu, fv, fw):
    """(phi, its gradient in cells (K, 3), its second derivatives (K, 3, 3)) of the trilinear
    function with corner values c[(a, b, d)] at the fractions (fu, fv, fw): the kernel's own
    arithmetic (terrains/mesh.trilinear), on arrays."""
    phi, gu, gv, gw, uv, uw, vw = mesh_trilinear.py_func(
        c[0, 0, 0], c[0, 0, 1], c[0, 1, 0], c[0, 1, 1], c[1, 0, 0], c[1, 0, 1], c[1, 1, 0],
        c[1, 1, 1], fu, fv, fw)
    zero = np.zeros_like(phi)
    hessian = np.stack([np.stack([zero, uv, uw], -1), np.stack([uv, zero, vw], -1),
                        np.stack([uw, vw, zero], -1)], -2)
    return phi, np.stack([gu, gv, gw], -1), hessian


def flat(terrain, row):
    return Flat(row[0:3].copy(), row[3:6].copy())


def sphere(terrain, row):
    return Round(row[0:3].copy(), float(row[3]), 1.0)


def bowl(terrain, row):
    return Round(row[0:3].copy(), float(row[3]), -1.0)


def gridded(terrain, row):
    """row: terrains/mesh.DistanceGrid.row, whose values the terrain's cached grid holds."""
    return Gridded(row[0:3].copy(), float(row[8]), terrain.grid().values)


SHAPES = {Plane: flat, Sphere: sphere, Bowl: bowl, MeshTerrain: gridded}


def shape_of(terrain, row):
    """The shape of a still terrain (``row``: its model.terrain_parameters), or None."""
    make = SHAPES.get(type(terrain))
    return None if make is None else make(terrain, row)


class Moving(NamedTuple):
    """A terrain moving rigidly: ``shape`` where the scene placed it, looked up at the pose its
    motion (row ``motion`` of the motion tables) has at the force time, read from ``clock`` at
    every call as world.terrain_at reads the model's: l = R^T (x - c) + pivot, n = R m(l),
    (dn/dx)^T = R C(l) R^T. Its surface moves at u = c' + w x (x - c)
    (world.surface_velocity), so du/dx = [w]x."""

    shape: object
    motion: int
    motion_info: np.ndarray
    motion_keys: np.ndarray
    clock: np.ndarray

    def pose(self):
        out = np.empty(POSE)
        pose_into(self.motion_info, self.motion_keys, self.motion, self.clock[FORCE_TIME], out)
        return out

    def local(self, x):
        """(the points in the placed frame, R)."""
        p = self.pose()
        rotation = p[0:9].reshape(3, 3)
        return (x - p[9:12]) @ rotation + p[12:15], rotation

    def distance(self, x, offset):
        return self.shape.distance(self.local(x)[0], offset)

    def normals(self, x):
        at, rotation = self.local(x)
        return self.shape.normals(at) @ rotation.T

    def gradient(self, x):
        at, rotation = self.local(x)
        return self.shape.gradient(at) @ rotation.T

    def curvature(self, x):
        at, rotation = self.local(x)
        inner = self.shape.curvature(at)
        return None if inner is None else rotation @ inner @ rotation.T

    def velocity(self, x):
        p = self.pose()
        return p[15:18] + np.cross(p[18:21], x - p[9:12])

    def velocity_vjp(self, u_bar):
        """(du/dx)^T u_bar = [w]x^T u_bar = -w x u_bar."""
        return -np.cross(self.pose()[18:21], u_bar)


def surface_velocity(shape, x):
    """The terrain's surface velocity at each point (K, 3), or None for a still one."""
    return shape.velocity(x) if isinstance(shape, Moving) else None
