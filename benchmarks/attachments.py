"""How long an attachment takes to find its triangles: each of 2,500 points just outside a
sphere of 81,920 triangles (a cape's particles against a fine body) bound to its nearest
triangle by attachments.nearest_triangles (libigl's AABB tree), against a search of every
point-triangle pair (timed on 100 points and scaled by 25), with the largest difference between
their distances.

    .venv/bin/python benchmarks/attachments.py
"""
import time

import numpy as np
import trimesh
from numba import njit

from springsim.attachments import nearest_triangles
from springsim.geometry.closest_points import closest_on_triangle


@njit
def every_pair(points, corners):
    """Each point's nearest triangle and distance, by trying every triangle."""
    count = points.shape[0]
    row, gap = np.zeros(count, np.int64), np.full(count, np.inf)
    for i in range(count):
        p = points[i]
        for t in range(corners.shape[0]):
            wa, wb, wc = closest_on_triangle(p, corners[t])
            d = 0.0
            for c in range(3):
                q = wa * corners[t, 0, c] + wb * corners[t, 1, c] + wc * corners[t, 2, c]
                d += (p[c] - q) ** 2
            if d < gap[i]:
                row[i], gap[i] = t, d
    return row, np.sqrt(gap)


def main() -> None:
    sphere = trimesh.creation.icosphere(subdivisions=6, radius=1.0)
    corners = np.ascontiguousarray(sphere.vertices[sphere.faces], float)
    points = np.random.default_rng(0).normal(size=(2500, 3))
    points *= (1.02 / np.linalg.norm(points, axis=1))[:, None]
    nearest_triangles(points[:10], corners)   # compiled
    every_pair(points[:2], corners[:10])
    start = time.perf_counter()
    _, _, gap = nearest_triangles(points, corners)
    tree = time.perf_counter() - start
    start = time.perf_counter()
    _, pair_gap = every_pair(points[:100], corners)
    pairs = (time.perf_counter() - start) * 25
    print(f"{len(points)} points, {len(corners)} triangles: tree {tree:.3f} s, every pair "
          f"{pairs:.1f} s; distances differ by at most {np.abs(gap[:100] - pair_gap).max():.1e} m")


if __name__ == "__main__":
    main()
