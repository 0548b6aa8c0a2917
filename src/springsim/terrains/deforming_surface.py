"""What a deforming mesh terrain packs (deforming_mesh.py, whose docstring says why and how):
the mesh and its point cache read, placed and welded (``deforming_surface``), and the data block
its kernels refit and look up, laid out in NumPy once when the model is built
(``DeformingSurface.block``): its reach, its grid and the entry capacity that keeps refitting
from allocating.
"""
from dataclasses import dataclass

import numpy as np

from ..animation import Animation, interpolated_points
from ..meshfiles import fan_triangles, first_file_vertex, read_mesh_file, weld
from .deforming_mesh import (CAPACITY, CELL, CELLS, COUNTS, EDGES, ENTRY, HEADER, LAST_TIME,
                             ORIGIN, REACH, SAMPLES, TRIANGLES, VERTICES)

MAX_CELLS = 64 ** 3
BAND_REACH = 4.0   # reach in contact bands (epsilon), at the least


@dataclass
class DeformingSurface:
    """What a deforming mesh terrain packs: its welded triangles and samples (placed in the
    scene), and its contact band."""

    triangles: np.ndarray   # (T, 3) welded vertex numbers
    times: np.ndarray       # (F,) s
    samples: np.ndarray     # (F, V, 3) m
    epsilon: float

    def edges(self) -> tuple[np.ndarray, np.ndarray]:
        """(E, 2) edges and (T, 3) each triangle's edge k (corners k, k + 1)."""
        pairs = np.sort(np.stack([self.triangles, np.roll(self.triangles, -1, axis=1)],
                                 axis=-1).reshape(-1, 2), axis=1)
        edges, which = np.unique(pairs, axis=0, return_inverse=True)
        return edges, which.reshape(-1, 3)

    def reach(self, largest_offset: float = 0.0) -> float:
        moved = np.linalg.norm(np.diff(self.samples, axis=0), axis=2).max() \
            if len(self.samples) > 1 else 0.0
        return max(BAND_REACH * self.epsilon, float(moved)) + largest_offset

    def grid(self, reach: float):
        """(origin, cell size, counts) covering every sample's box grown by reach."""
        low = self.samples.min(axis=(0, 1)) - reach
        high = self.samples.max(axis=(0, 1)) + reach
        corners = self.samples[0][self.triangles]
        mean_edge = float(np.mean(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)))
        cell = max(2.0 * reach, mean_edge, float(np.max(high - low)) / 1e6)
        while np.prod(np.floor((high - low) / cell) + 1) > MAX_CELLS:
            cell *= 1.25
        return low, cell, (np.floor((high - low) / cell) + 1).astype(np.int64)

    def capacity(self, origin, cell, counts, reach) -> int:
        """Entries enough for the cells of every triangle's box at any time (module doc)."""
        most = np.zeros(len(self.triangles), np.int64)
        for k in range(max(len(self.samples) - 1, 1)):
            pair = self.samples[k:k + 2][:, self.triangles]           # (2 or 1, T, 3, 3)
            low = pair.min(axis=(0, 2)) - reach
            high = pair.max(axis=(0, 2)) + reach
            first = np.maximum(np.floor((low - origin) / cell), 0)
            last = np.minimum(np.floor((high - origin) / cell), counts - 1)
            most = np.maximum(most, np.prod(np.maximum(last - first + 1, 0), axis=1)
                              .astype(np.int64))
        return int(most.sum())

    def block(self, data_start: int, largest_offset: float = 0.0) -> tuple[list, np.ndarray]:
        """(the terrain's parameter row, its data block) (module doc); ``largest_offset``: the
        most any particle keeps from a terrain (m), a ball's radius."""
        edges, triangle_edges = self.edges()
        reach = self.reach(largest_offset)
        origin, cell, counts = self.grid(reach)
        cells = int(np.prod(counts))
        capacity = self.capacity(origin, cell, counts, reach)
        count = self.samples.shape[1]
        header = np.zeros(HEADER)
        header[[VERTICES, TRIANGLES, EDGES, SAMPLES, CAPACITY, LAST_TIME, REACH, CELLS]] = [
            count, len(self.triangles), len(edges), len(self.times), capacity, np.nan, reach,
            cells]
        header[ORIGIN:ORIGIN + 3], header[CELL], header[COUNTS:COUNTS + 3] = origin, cell, counts
        written = np.zeros(3 * count * 3 + 3 * len(edges) + 7 * len(self.triangles)
                           + cells + 1 + ENTRY * capacity)
        block = np.concatenate([header, self.times, self.samples.ravel(),
                                self.triangles.ravel().astype(float),
                                triangle_edges.ravel().astype(float), written])
        return [float(data_start)], block


def deforming_surface(file: str, animation: Animation, place, epsilon: float) -> DeformingSurface:
    """The surface of mesh ``file`` driven by ``animation`` (its vertices, in the file's order
    and frame, as many as the file has: the caller checks), placed by ``place`` ((n, 3) file
    points -> scene points) and welded."""
    mesh = read_mesh_file(file, "file")
    cache = animation.cache("animation.file")
    welded = weld(mesh.vertices)
    first = first_file_vertex(welded.of_file_vertex)
    samples = np.stack([place(points[first]) for points in cache.points])
    triangles = welded.of_file_vertex[fan_triangles(mesh.faces)]
    return DeformingSurface(triangles, cache.times, samples, float(epsilon))


def surface_at(surface: DeformingSurface, t: float) -> np.ndarray:
    """The surface's vertices (V, 3) at time t, in NumPy (for drawing and tests)."""
    from ..animation import PointCache

    return interpolated_points(PointCache(surface.times, surface.samples), t)[0]
