"""A terrain from a triangle mesh file: a closed mesh is solid inside; an open mesh (a ground, a
ramp) collides on the side its face normals point to.

The distance query is a signed distance grid, built once when the model is built, and looked up
trilinearly in the kernel, its gradient giving the normal. Why a grid and not a BVH with exact
closest points: contact asks every particle for its distance to every terrain in every stage of
every step, and a grid answers in constant time with eight neighbouring loads and no search,
where a BVH walks a tree per particle (benchmarks/mesh_terrain.py compares the contact pass
with the plane's, the lookups being done a block of particles ahead, ``look_ahead``). A grid is
exact where the distance is linear across a cell: on the flat parts of a mesh (ramps, floors,
stairs' treads) trilinear interpolation reproduces the exact distance and normal to round-off, so
a ramp gives the analytic tilted plane's outcome. Curved parts are smoothed at the scale of a
cell (``resolution`` cells along the longest side), and sharp edges are rounded off at that
scale.

The grid's values are the exact signed distances of its nodes (libigl, sign from the
angle-weighted pseudonormals of the closest feature, which is what gives an open mesh a front
side), computed only within BAND_CELLS cells of the surface; nodes farther away take the sign of
their nearest computed node and a distance grown from it (a Euclidean distance transform), which is
all contact far from the surface needs. The grid covers the mesh's box and MARGIN_CELLS cells
around it; outside the grid the terrain is free space (an open mesh is therefore solid only up to
that margin behind its surface).
"""
import functools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .._jit import inline_kernel, kernel
from ..errors import SceneError, require
from ..meshfiles import (TriangleMesh, check_triangles, is_closed, placed, read_mesh,
                         read_mesh_file, validate_placement)
from ..animation import Animation
from .base import Contact, register
from .deforming_mesh import DeformingMesh
from .deforming_surface import DeformingSurface, deforming_surface, surface_at
from .display import TerrainMesh

PROBES = 512   # a moving mesh's vertices whose travel bounds its surface's (substeps.py)

BAND_CELLS = 3          # nodes within this many cells of the surface get exact distances
MARGIN_CELLS = 4        # the grid reaches this many cells beyond the mesh's box
MAX_NODES = 8_000_000   # 64 MB of float64: the grid's size limit


@inline_kernel
def trilinear(c000, c001, c010, c011, c100, c101, c110, c111, fu, fv, fw):
    """The trilinear function of a cell's corner values c_abd at the fractions (fu, fv, fw):
    (phi, its gradient in cells gu, gv, gw, then the mixed second derivatives d2/du dv,
    d2/du dw, d2/dv dw; it has no pure ones). Scalars in the kernels; NumPy arrays through
    ``trilinear.py_func`` in the adjoint shape (``trilinear_pieces``), which so computes the
    kernel's bits."""
    c00, c01 = c000 + fu * (c100 - c000), c001 + fu * (c101 - c001)
    c10, c11 = c010 + fu * (c110 - c010), c011 + fu * (c111 - c011)
    c0, c1 = c00 + fv * (c10 - c00), c01 + fv * (c11 - c01)
    phi = c0 + fw * (c1 - c0)
    gw = c1 - c0
    gv = (c10 - c00) + fw * ((c11 - c01) - (c10 - c00))
    gu_0 = (c100 - c000) + fv * ((c110 - c010) - (c100 - c000))
    gu_1 = (c101 - c001) + fv * ((c111 - c011) - (c101 - c001))
    gu = gu_0 + fw * (gu_1 - gu_0)
    uv_0, uv_1 = (c110 - c010) - (c100 - c000), (c111 - c011) - (c101 - c001)
    return (phi, gu, gv, gw, uv_0 + fw * (uv_1 - uv_0), gu_1 - gu_0,
            (c11 - c01) - (c10 - c00))


@kernel
def mesh_distance(row, data, x0, x1, x2):
    """row: the grid's origin (0-2), cell size (3), node counts (4-6), first value in data (7)
    and 1 / cell size (8); data holds the node values, z fastest."""
    cell, n0, n1, n2, start = row[3], int(row[4]), int(row[5]), int(row[6]), int(row[7])
    # position in cells, clamped into the grid
    u, v, w = (x0 - row[0]) * row[8], (x1 - row[1]) * row[8], (x2 - row[2]) * row[8]
    cu, cv, cw = min(max(u, 0.0), n0 - 1.0), min(max(v, 0.0), n1 - 1.0), min(max(w, 0.0), n2 - 1.0)
    i, j, k = min(int(cu), n0 - 2), min(int(cv), n1 - 2), min(int(cw), n2 - 2)
    fu, fv, fw = cu - i, cv - j, cw - k
    # unsigned indices: Numba then skips its negative-index checks (eight per lookup)
    one = np.uint64(1)
    base = np.uint64(start + (i * n1 + j) * n2 + k)
    di, dj = np.uint64(n1 * n2), np.uint64(n2)
    c000, c001 = data[base], data[base + one]
    c010, c011 = data[base + dj], data[base + dj + one]
    c100, c101 = data[base + di], data[base + di + one]
    c110, c111 = data[base + di + dj], data[base + di + dj + one]
    # trilinear interpolation, and its gradient (per cell) as the normal
    phi, gu, gv, gw = trilinear(c000, c001, c010, c011, c100, c101, c110, c111, fu, fv, fw)[:4]
    du, dv, dw = u - cu, v - cv, w - cw
    if du != 0.0 or dv != 0.0 or dw != 0.0:
        # beyond the grid: free space, the normal pointing away from the grid
        outside = math.sqrt(du * du + dv * dv + dw * dw)
        return outside * cell + max(phi, 0.0), du / outside, dv / outside, dw / outside
    size = math.sqrt(gu * gu + gv * gv + gw * gw)
    if size == 0.0:
        return phi, 0.0, 1.0, 0.0
    inverse = 1.0 / size
    return phi, gu * inverse, gv * inverse, gw * inverse


@dataclass
class DistanceGrid:
    """Signed distances (m) at the nodes origin + cell * (i, j, k)."""

    origin: np.ndarray
    cell: float
    values: np.ndarray   # (n0, n1, n2)

    def row(self, data_start: int) -> list:
        return [*self.origin, self.cell, *self.values.shape, float(data_start), 1.0 / self.cell]

    def lookup(self, x: np.ndarray) -> np.ndarray:
        """The kernel's phi for points (n, 3), in NumPy."""
        n = np.array(self.values.shape)
        u = (np.atleast_2d(x) - self.origin) / self.cell
        clamped = np.clip(u, 0.0, n - 1.0)
        index = np.minimum(clamped.astype(np.int64), n - 2)
        f = clamped - index
        phi = np.zeros(len(u))
        for corner in np.ndindex(2, 2, 2):
            weight = np.prod(np.where(corner, f, 1.0 - f), axis=1)
            i, j, k = (index + corner).T
            phi += weight * self.values[i, j, k]
        outside = np.linalg.norm(u - clamped, axis=1)
        return np.where(outside > 0.0, outside * self.cell + np.maximum(phi, 0.0), phi)


def distance_grid(mesh: TriangleMesh, resolution: int, key: str) -> DistanceGrid:
    """The signed distance grid of a mesh (module doc)."""
    import igl
    from scipy.ndimage import distance_transform_edt

    low, high = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    cell = float(np.max(high - low)) / resolution
    counts = np.ceil((high - low) / cell).astype(np.int64) + 2 * MARGIN_CELLS + 1
    nodes = int(np.prod(counts))
    require(nodes <= MAX_NODES, f"{key}.resolution", resolution,
            f"gives a distance grid of {nodes:,} nodes, more than {MAX_NODES:,}; try <= "
            f"{int(resolution * (MAX_NODES / nodes) ** (1 / 3))}")
    origin = low - MARGIN_CELLS * cell
    axes = [origin[a] + cell * np.arange(counts[a]) for a in range(3)]
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    band = BAND_CELLS * cell
    values = igl.signed_distance(points, mesh.vertices, mesh.triangles,
                                 sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL,
                                 lower_bound=-band, upper_bound=band)[0].reshape(counts)
    far = ~np.isfinite(values) | (np.abs(values) >= band)
    if far.all():
        raise SceneError(key, mesh.vertices.shape, "gives no grid node near its surface")
    grown, nearest = distance_transform_edt(far, return_indices=True)
    near_values = values[tuple(nearest)]
    values = np.where(far, np.sign(near_values) * (np.abs(near_values) + grown * cell), values)
    return DistanceGrid(origin, cell, np.ascontiguousarray(values))


@dataclass
class MeshTerrain(Contact):
    """A terrain read from ``file``, scaled, rotated (degrees about ``rotation_axis``, about the
    file's origin) and moved by ``position`` (m); ``resolution``: distance grid cells along its
    longest side."""

    file: str = ""
    scale: float = 1.0
    rotation_degrees: float = 0.0
    rotation_axis: tuple = (0.0, 1.0, 0.0)
    position: tuple = (0.0, 0.0, 0.0)
    resolution: int = 128
    animation: Animation | None = None   # a point cache it deforms by (deforming_mesh.py)

    distance_kernel = mesh_distance
    # a long lookup: contact does it a block of particles ahead (collision/response/terrain.py)
    look_ahead = True

    def anchor(self) -> tuple:
        return tuple(self.position)   # what a motion turns it about by default

    def thickness(self) -> float:
        """A closed mesh's smallest box side (a stand-in for its thinnest part); an open one
        pushes what is behind it back to the side its normals face, as a half-space does: inf."""
        mesh = self.mesh()
        if not is_closed(mesh.triangles):
            return math.inf
        return float(np.ptp(mesh.vertices, axis=0).min())

    def motion_probes(self) -> np.ndarray:
        vertices = self.mesh().vertices
        return vertices[::max(1, len(vertices) // PROBES)]

    def validate(self, key: str) -> None:
        self.validate_contact(key)
        validate_placement(self, key)
        require(isinstance(self.resolution, int) and 8 <= self.resolution <= 1024,
                f"{key}.resolution", self.resolution, "must be a whole number in [8, 1024]")
        check_triangles(self.mesh(f"{key}.file"), f"{key}.file", self.file)
        if self.animation is not None:
            require(self.motion is None, f"{key}.animation", self.animation.file,
                    "a mesh terrain moves by a motion or deforms by an animation, not both")
            self.animation.validate(f"{key}.animation")
            self.deforming_surface(key)   # the cache's point count against the file's

    def packed_kind(self) -> int:
        return DeformingMesh.kind if self.animation is not None else self.kind

    def deforms(self) -> bool:
        return self.animation is not None

    def deforming_surface(self, key: str = "terrain") -> DeformingSurface:
        """The surface its animation drives, placed as the mesh is (kept per file versions and
        settings: validation, packing and drawing ask for it)."""
        # what can be wrong fails here, named by ``key``; the surface is then kept whatever
        # key asks (validation and packing ask with different ones)
        vertices = read_mesh_file(self.file, f"{key}.file").vertices
        self.animation.check_points(len(vertices), f"{key}.animation",
                                    f"the mesh file {self.file}")
        path = Path(self.file).expanduser()
        versions = [(str(path.resolve()), path.stat().st_mtime_ns),
                    (self.animation.file, self.animation.version())]
        return _cached_surface(*versions, float(self.animation.fps),
                               float(self.animation.start), float(self.scale),
                               float(self.rotation_degrees), tuple(map(float, self.rotation_axis)),
                               tuple(map(float, self.position)), float(self.epsilon))

    def moves(self) -> bool:
        return self.motion is not None or self.animation is not None

    def vertices_at(self, vertices, t: float) -> np.ndarray:
        if self.animation is None:
            return super().vertices_at(vertices, t)
        return surface_at(self.deforming_surface(), t)   # its display mesh is the surface

    def mesh(self, key: str = "file") -> TriangleMesh:
        """The mesh as placed in the scene."""
        return placed(read_mesh(self.file, key), self.scale, self.rotation_degrees,
                      self.rotation_axis, self.position)

    def grid(self) -> DistanceGrid:
        """The distance grid, built once per file version and settings (kept for reuse)."""
        self.mesh()   # a missing or unreadable file fails here, with its key
        stat = Path(self.file).expanduser().stat()
        return _cached_grid(str(Path(self.file).expanduser().resolve()), stat.st_mtime_ns,
                            float(self.scale), float(self.rotation_degrees),
                            tuple(map(float, self.rotation_axis)), tuple(map(float, self.position)),
                            self.resolution)

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        if self.animation is not None:   # at time 0, exactly (libigl)
            import igl

            surface = self.deforming_surface()
            return igl.signed_distance(np.atleast_2d(np.asarray(x, float)),
                                       surface_at(surface, 0.0), surface.triangles,
                                       sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0] \
                - radius
        return self.grid().lookup(x) - radius

    def pack(self, data_start: int, largest_offset: float = 0.0):
        if self.animation is not None:
            return self.deforming_surface().block(data_start, largest_offset)
        grid = self.grid()
        return grid.row(data_start), grid.values

    def adjoint_shape(self, row) -> "Gridded":
        """The still mesh's grid (a deforming one's shape is gradients/terrain_shapes.Deforming);
        row: DistanceGrid.row, whose values the cached grid holds."""
        return Gridded(row[0:3].copy(), float(row[8]), self.grid().values)

    def display_mesh(self, near, extent: float):
        if self.animation is not None:
            surface = self.deforming_surface()
            return TerrainMesh(surface_at(surface, 0.0), surface.triangles, two_sided=True)
        mesh = self.mesh()
        return TerrainMesh(mesh.vertices, mesh.triangles, two_sided=True)

    def export_mesh(self, positions):
        shape = self.display_mesh(None, 0.0)   # the mesh itself, wherever the bodies are
        return shape.vertices, shape.triangles

    def points_near(self, corners: np.ndarray, size: float) -> np.ndarray:
        """The mesh's vertices under the bodies' box (grown by its size), or its box's corners
        when none is."""
        vertices = self.mesh().vertices
        low, high = corners.min(axis=0) - size, corners.max(axis=0) + size
        inside = vertices[np.all((vertices >= low) & (vertices <= high), axis=1)]
        if len(inside):
            return inside[::max(1, len(inside) // 2000)]
        box_low, box_high = vertices.min(axis=0), vertices.max(axis=0)
        return np.array([[x, y, z] for x in (box_low[0], box_high[0])
                         for y in (box_low[1], box_high[1]) for z in (box_low[2], box_high[2])])


class Gridded(NamedTuple):
    """A still mesh's adjoint shape: its signed distance grid, trilinear in each cell as
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
        return trilinear_pieces(c, f[:, 0], f[:, 1], f[:, 2]), u - clamped

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


def trilinear_pieces(c, fu, fv, fw):
    """(phi, its gradient in cells (K, 3), its second derivatives (K, 3, 3)) of the trilinear
    function with corner values c[(a, b, d)] at the fractions (fu, fv, fw): the kernel's own
    arithmetic (``trilinear``), on arrays."""
    phi, gu, gv, gw, uv, uw, vw = trilinear.py_func(
        c[0, 0, 0], c[0, 0, 1], c[0, 1, 0], c[0, 1, 1], c[1, 0, 0], c[1, 0, 1], c[1, 1, 0],
        c[1, 1, 1], fu, fv, fw)
    zero = np.zeros_like(phi)
    hessian = np.stack([np.stack([zero, uv, uw], -1), np.stack([uv, zero, vw], -1),
                        np.stack([uw, vw, zero], -1)], -2)
    return phi, np.stack([gu, gv, gw], -1), hessian


@functools.lru_cache(maxsize=8)
def _cached_surface(mesh_version, cache_version, fps, start, scale, rotation_degrees,
                    rotation_axis, position, epsilon):
    def place(points):
        return placed(TriangleMesh(points, np.zeros((0, 3), np.int64)), scale, rotation_degrees,
                      rotation_axis, position).vertices

    animation = Animation(cache_version[0], fps, start)
    return deforming_surface(mesh_version[0], animation, place, epsilon)


@functools.lru_cache(maxsize=8)
def _cached_grid(path, mtime_ns, scale, rotation_degrees, rotation_axis, position, resolution):
    mesh = placed(read_mesh(path, "file"), scale, rotation_degrees, rotation_axis, position)
    return distance_grid(mesh, resolution, "file")


register(MeshTerrain, {"mesh": MeshTerrain}, order=3)
