"""Triangle meshes of the terrains (plain NumPy): what a terrain kind's ``display_mesh`` (drawn,
render/) and ``export_mesh`` (written, export/) give, and the sphere meshes of balls.

Geometry only: the renderer colours these meshes (render/colors.py) and the exporters write them,
and both import this module, never the other way round.

Planes are infinite, so what is drawn is a square patch centred near the bodies; its checker
cells are anchored to the plane's point so that the pattern stays put when the patch is moved,
and a sliding body is seen to move over it. What is exported is one square under the whole
motion (``plane_quad``).
"""
import math
from dataclasses import dataclass

import numpy as np


@dataclass
class TerrainMesh:
    """What is drawn of a terrain: triangles (wound to face the free side), how they are
    coloured, and whether the mesh follows the bodies (``recentre_distance``: it is rebuilt when
    the bodies' middle moves that far from ``center`` across ``normal``)."""

    vertices: np.ndarray
    triangles: np.ndarray
    checker: np.ndarray | None = None       # (T,) 0 or 1: which checker colour (render.colors)
    color: str = "terrain"                  # "terrain" or "bowl" (render.colors)
    cull_back: bool = False                 # hide faces seen from behind (a bowl's near wall)
    two_sided: bool = False                 # both sides lit alike (an open mesh)
    smooth: bool = True                     # smooth shading (curved) or flat (faceted)
    center: np.ndarray | None = None
    normal: np.ndarray | None = None
    recentre_distance: float | None = None

    def needs_recentring(self, near) -> bool:
        if self.recentre_distance is None:
            return False
        offset = np.asarray(near, float) - self.center
        offset -= (offset @ self.normal) * self.normal
        return bool(np.linalg.norm(offset) > self.recentre_distance)


def plane_display_mesh(point, normal, near, extent: float) -> TerrainMesh:
    """A checkered patch, with cells about a quarter of the bodies' ``extent`` (a power of 10)
    and ten times their extent across, that moves along once they leave its middle third."""
    cell = float(10.0 ** np.round(np.log10(max(extent, 1e-3) / 4)))
    half_size = max(40.0 * cell, 10.0 * extent)
    vertices, triangles, checker = plane_patch(point, normal, near, half_size, cell)
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    return TerrainMesh(vertices, triangles, checker, smooth=False, center=vertices.mean(axis=0),
                       normal=n, recentre_distance=half_size / 3)


def sphere_points_near(center, radius: float, corners: np.ndarray, size: float,
                       lower_half: bool) -> np.ndarray:
    """Points of a sphere (its lower half for a bowl) under the box with these corners and
    diagonal ``size``: the whole sphere when it is small, else the part under the box."""
    center, radius = np.asarray(center, float), float(radius)
    if radius > 2 * size:
        offsets = corners - center
        return center + radius * offsets / np.linalg.norm(offsets, axis=1, keepdims=True)
    directions = sphere_directions()
    if lower_half:
        directions = directions[directions[:, 1] <= 0]
    return center + radius * directions


def sphere_directions(count: int = 400) -> np.ndarray:
    """Nearly even unit vectors (a Fibonacci sphere), with the equator itself."""
    k = np.arange(count) + 0.5
    y = 1 - 2 * k / count
    phi = math.pi * (3 - math.sqrt(5)) * k
    ring = np.sqrt(1 - y * y)
    spiral = np.stack([ring * np.cos(phi), y, ring * np.sin(phi)], axis=1)
    angles = np.linspace(0, 2 * math.pi, 64, endpoint=False)
    equator = np.stack([np.cos(angles), np.zeros_like(angles), np.sin(angles)], axis=1)
    return np.concatenate([spiral, equator])


def plane_basis(normal) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors u, w spanning the plane, with u x w = normal."""
    n = np.asarray(normal, float)
    n = n / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    u = np.cross(n, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(n, u)


def plane_patch(point, normal, near, half_size: float, cell: float):
    """A square of about 2 * half_size (m) on the plane, centred at the cell nearest ``near``.

    Returns vertices (V, 3), triangles (T, 3) wound so that they face ``normal``, and a checker
    colour index (T,) of 0 or 1 per triangle.
    """
    point = np.asarray(point, float)
    u, w = plane_basis(normal)
    offset = np.asarray(near, float) - point
    # anchor the grid to whole cells from the plane's point, so the checker does not slide
    center = point + cell * (np.round(offset @ u / cell) * u + np.round(offset @ w / cell) * w)
    cells = max(1, int(math.ceil(half_size / cell)))
    steps = np.arange(-cells, cells + 1) * cell
    grid_u, grid_w = np.meshgrid(steps, steps, indexing="ij")
    vertices = center + grid_u[..., None] * u + grid_w[..., None] * w
    count = 2 * cells + 1
    index = np.arange(count * count).reshape(count, count)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    i, j = np.indices((count - 1, count - 1))
    parity = ((i + j) % 2).ravel()
    return vertices.reshape(-1, 3), triangles, np.concatenate([parity, parity])


def plane_quad(point, normal, positions):
    """(vertices, triangles) of a square of the plane under the whole motion (``positions``
    (..., 3), every particle at every frame): ten times its size, and at least 20 m."""
    points = positions.reshape(-1, 3)
    low, high = points.min(axis=0), points.max(axis=0)
    half = max(10.0 * float(np.max(high - low)), 10.0)
    centre = (low + high) / 2
    centre = centre - ((centre - np.asarray(point, float)) @ normal) * normal
    u, w = plane_basis(normal)                 # u x w = normal: counter-clockwise seen from it
    corners = [centre + half * (su * u + sw * w) for su, sw in ((-1, -1), (1, -1), (1, 1),
                                                                 (-1, 1))]
    return np.asarray(corners), np.array([[0, 1, 2], [0, 2, 3]])


def latitude_mesh(center, radius: float, polar_angles, longitudes: int = 64):
    """A sphere band between the given polar angles (radians from +y), facing outwards.

    An angle of 0 or pi closes the band with a pole.
    """
    center = np.asarray(center, float)
    theta = np.asarray(polar_angles, float)
    top_pole, bottom_pole = theta[0] <= 0.0, theta[-1] >= math.pi
    rings = theta[(theta > 0.0) & (theta < math.pi)]
    phi = np.linspace(0.0, 2 * math.pi, longitudes, endpoint=False)
    directions = np.stack([np.outer(np.sin(rings), np.cos(phi)),
                           np.outer(np.cos(rings), np.ones_like(phi)),
                           np.outer(np.sin(rings), np.sin(phi))], axis=-1)
    vertices = [center + radius * directions.reshape(-1, 3)]
    ring = np.arange(len(rings) * longitudes).reshape(len(rings), longitudes)
    a, b = ring[:-1], np.roll(ring[:-1], -1, axis=1)
    c, d = np.roll(ring[1:], -1, axis=1), ring[1:]
    triangles = [np.stack([a.ravel(), b.ravel(), c.ravel()], 1),
                 np.stack([a.ravel(), c.ravel(), d.ravel()], 1)]
    count = ring.size
    if top_pole:
        vertices.append(center + radius * np.array([[0.0, 1.0, 0.0]]))
        first = ring[0]
        triangles.append(np.stack([np.full(longitudes, count), np.roll(first, -1), first], 1))
        count += 1
    if bottom_pole:
        vertices.append(center + radius * np.array([[0.0, -1.0, 0.0]]))
        last = ring[-1]
        triangles.append(np.stack([last, np.roll(last, -1), np.full(longitudes, count)], 1))
    return np.concatenate(vertices), np.concatenate(triangles)


def sphere_mesh(center, radius: float, latitudes: int = 32, longitudes: int = 64):
    """A closed sphere, facing outwards."""
    return latitude_mesh(center, radius, np.linspace(0.0, math.pi, latitudes + 1), longitudes)


def bowl_mesh(center, radius: float, latitudes: int = 16, longitudes: int = 64):
    """The lower half of a sphere, facing inwards (towards the centre, where the bodies are).

    Drawn with back faces culled, the near wall (which faces away from the camera) disappears
    from any viewpoint while the far wall stays: the body inside is always in sight.
    """
    vertices, triangles = latitude_mesh(center, radius,
                                        np.linspace(math.pi / 2, math.pi, latitudes + 1),
                                        longitudes)
    return vertices, triangles[:, ::-1]
