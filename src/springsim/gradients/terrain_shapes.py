"""The terrains as the explicit methods' contact adjoint follows them (contact.py), each as its
distance, its normal, the distance's gradient and the normal's derivative in the position (the
curvature, which the gradient of a contact on a curved surface needs: where a particle touches
decides which way the surface pushes it).

A still terrain's shape is its kind's own (``adjoint_shape``, defined in the kind's file:
terrains/plane.Flat, terrains/sphere.Round for spheres and bowls, terrains/mesh.Gridded), so
that a kind is one file. A terrain that moves rigidly (motion.py) is its shape where it was
placed, ``Moving`` at the pose of the force time; a mesh that deforms is ``Deforming``, its
surface where its point cache has it then; a terrain without a shape is not followed, and
touching it is refused (checks.py). A shape whose surface moves also gives its velocity at each
point and that velocity's vector-Jacobian product in the point (``velocity``, ``velocity_vjp``).

``curvature`` gives (dn/dx)^T, the transpose that vector-Jacobian products take; for a plane, a
sphere and a bowl dn/dx is symmetric. ``gradient`` gives grad phi, which is the normal for an
exact distance; a mesh's trilinear distance grid has a normal of its gradient's direction, and
a gradient whose length is only near 1.
"""
from typing import NamedTuple

import numpy as np

from ..motion import POSE, pose_into
from .clock import FORCE_TIME

STRAIGHT_UP = np.array([0.0, 1.0, 0.0])   # the normal the kernels give a point they cannot place


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

    def velocity_vjp(self, x, u_bar):
        """(du/dx)^T u_bar = [w]x^T u_bar = -w x u_bar, the same at every point x."""
        return -np.cross(self.pose()[18:21], u_bar)


class Closest(NamedTuple):
    """Each point's closest point on a deforming surface, as deformed_distance finds it."""

    corners: np.ndarray     # (K, 3) the closest triangle's vertex numbers
    weights: np.ndarray     # (K, 3) the closest point's barycentric weights
    sign: np.ndarray        # (K,) +1 outside, -1 inside (the closest feature's pseudonormal)
    distance: np.ndarray    # (K,) m, unsigned
    normal: np.ndarray      # (K, 3) sign (x - closest) / distance


class Deforming:
    """A mesh terrain that deforms (terrains/deforming_mesh.py): its surface where the point
    cache has it at the force time (``deform``'s interpolation, read from ``clock`` at every
    call), and each point's closest point on it, whose triangle libigl's tree finds and whose
    weights the contact code's closest_on_triangle gives, as the kernels' lookup does.

    phi = sign |x - p| and n = sign (x - p) / |x - p|, p the closest point, so grad phi = n and
    dn/dx = sign (I - n n^T)(I - D) / |x - p|, D the projector onto the closest feature: the
    face's plane (dn/dx = 0), an edge's line, or nothing at a corner. The surface moves at
    u = sum_k w_k u_k, its corners' velocities; du/dx = sum_k u_k (grad w_k)^T, the weights'
    gradients within the feature.

    The kernels' grid sees a point only within ``reach`` of the surface (centre distance,
    terrains/deforming_mesh.py): backward Euler's lookup answers infinity beyond it (``seen``);
    the explicit methods' contact never looks that far."""

    def __init__(self, surface, clock, reach=np.inf):
        self.surface = surface
        self.clock = clock
        self.reach = reach
        self.memo = {}   # the last time's surface and the last points' closest points

    def state(self):
        """(positions, velocities) (V, 3) at the force time: deforming_mesh.interpolate."""
        t = float(self.clock[FORCE_TIME])
        if self.memo.get("time") != t:
            self.memo.clear()
            self.memo["time"], self.memo["state"] = t, interpolate(self.surface, t)
        return self.memo["state"]

    def closest(self, x) -> Closest:
        import igl

        from ..attachments import closest_points_on

        positions, _ = self.state()
        key = x.tobytes()
        if self.memo.get("points") != key:
            triangles = self.surface.triangles
            x = np.ascontiguousarray(x, float)
            signed, row, _, pseudonormal = igl.signed_distance(
                x, positions, triangles, sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)
            row = np.asarray(row, np.int64)
            weights, distance = closest_points_on(x, positions[triangles], row)
            corners = triangles[row]
            sign = np.where(signed < 0.0, -1.0, 1.0)
            d = x - np.einsum("kj,kjc->kc", weights, positions[corners])
            normal = on_surface_normals(sign, d, distance, pseudonormal)
            self.memo["points"] = key
            self.memo["closest"] = Closest(corners, weights, sign, distance, normal)
        return self.memo["closest"]

    def distance(self, x, offset):
        found = self.closest(x)
        return found.sign * found.distance - offset

    def seen(self, x):
        """(K,) whether the kernels' lookup finds the surface from each point."""
        return self.closest(x).distance ** 2 < self.reach ** 2

    def normals(self, x):
        return self.closest(x).normal

    def gradient(self, x):
        return self.normals(x)

    def curvature(self, x):
        """Zero over a face (exactly, not as the rounding of (I - n n^T) n n^T)."""
        found = self.closest(x)
        n = found.normal
        across = np.eye(3) - n[:, :, None] * n[:, None, :]
        along = feature_projector(self.state()[0], found)
        scale = np.where((found.distance > 1e-12) & (found.weights != 0.0).any(axis=1)
                         & (found.weights == 0.0).any(axis=1),
                         found.sign / np.where(found.distance > 1e-12, found.distance, 1.0), 0.0)
        return scale[:, None, None] * np.einsum("kij,kjl->kil", across, np.eye(3) - along)

    def velocity(self, x):
        found = self.closest(x)
        return np.einsum("kj,kjc->kc", found.weights, self.state()[1][found.corners])

    def velocity_vjp(self, x, u_bar):
        """sum_k (u_k . u_bar) grad w_k."""
        found = self.closest(x)
        positions, velocities = self.state()
        share = np.einsum("kjc,kc->kj", velocities[found.corners], u_bar)
        return np.einsum("kj,kjc->kc", share, weight_gradients(positions, found))


def on_surface_normals(sign, d, distance, pseudonormal):
    """sign d / |d|, d from the closest point; on the surface (|d| <= 1e-12) the closest
    feature's pseudonormal, and straight up where that has no length, as the kernel's
    (deforming_mesh.deformed_distance)."""
    away = distance > 1e-12
    size = np.linalg.norm(pseudonormal, axis=1)
    on = np.where(size[:, None] > 0.0, pseudonormal / np.where(size > 0.0, size, 1.0)[:, None],
                  STRAIGHT_UP)
    return np.where(away[:, None], sign[:, None] * d / np.where(away, distance, 1.0)[:, None],
                    on)


def interpolate(surface, t):
    """The surface's (positions, velocities) at t, as deforming_mesh.interpolate computes them:
    linear between samples, held outside them."""
    times, samples = surface.times, surface.samples
    if len(times) == 1 or not t > times[0]:
        return samples[0], np.zeros_like(samples[0])
    if t >= times[-1]:
        return samples[-1], np.zeros_like(samples[-1])
    k = int(np.searchsorted(times, t, side="right")) - 1
    span = times[k + 1] - times[k]
    w, rate = (t - times[k]) / span, 1.0 / span
    here, there = samples[k], samples[k + 1]
    return here + w * (there - here), (there - here) * rate


def feature_projector(positions, found: Closest):
    """(K, 3, 3) the projector onto each closest point's edge line, zero at a corner (and on a
    face, whose curvature is zero anyway): a feature's weights are the nonzero ones."""
    corners = positions[found.corners]                          # (K, 3, 3)
    inside = found.weights != 0.0
    count = inside.sum(axis=1)
    out = np.zeros((len(count), 3, 3))
    edge = count == 2
    if edge.any():
        e = edge_vectors(corners[edge], inside[edge])
        e /= np.linalg.norm(e, axis=1)[:, None]
        out[edge] = e[:, :, None] * e[:, None, :]
    return out


def edge_vectors(corners, inside):
    """(K, 3) from the first to the second corner of each point's edge (its nonzero weights)."""
    order = np.argsort(~inside, axis=1, kind="stable")[:, :2]   # the two corners, in order
    rows = np.arange(len(corners))
    return corners[rows, order[:, 1]] - corners[rows, order[:, 0]]


def weight_gradients(positions, found: Closest):
    """(K, 3, 3) grad w_k of each closest point's weights in the point: on a face the
    barycentric gradients m x (opposite edge) / |2 area| of its projection, on an edge
    -+e / |e|^2 for its two corners, zero at a corner."""
    corners = positions[found.corners]
    inside = found.weights != 0.0
    count = inside.sum(axis=1)
    out = np.zeros((len(count), 3, 3))
    face = count == 3
    if face.any():
        c = corners[face]
        m = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
        size = np.linalg.norm(m, axis=1)[:, None]
        unit = m / size
        for k in range(3):
            opposite = c[:, (k + 2) % 3] - c[:, (k + 1) % 3]
            out[face, k] = np.cross(unit, opposite) / size
    edge = np.nonzero(count == 2)[0]
    if len(edge):
        e = edge_vectors(corners[edge], inside[edge])
        e /= np.einsum("kc,kc->k", e, e)[:, None]
        order = np.argsort(~inside[edge], axis=1, kind="stable")[:, :2]
        out[edge, order[:, 0]] = -e
        out[edge, order[:, 1]] = e
    return out


def surface_velocity(shape, x):
    """The terrain's surface velocity at each point (K, 3), or None for a still one."""
    return shape.velocity(x) if hasattr(shape, "velocity") else None
