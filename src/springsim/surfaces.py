"""The surfaces of bodies: what the viewer, the renderer, the NPZ and the exporters show.

A body's surface is a triangle mesh. For a cube or a cloth its vertices are particles of the
body (``BodySlice.surface`` holds global particle numbers). A body whose surface is embedded in
its particle lattice (a mesh body) has an ``Embedding``: each surface vertex is a fixed weighted
sum of up to eight particles (trilinear weights in its lattice cell), and ``BodySlice.surface``
then numbers those vertices from 0.

Balls are spheres, not triangle meshes: a Balls body's surface has their centres as vertices, no
triangles, and their contact radii in ``radii`` (a renderer or exporter draws spheres there).
"""
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np


class Embedding(NamedTuple):
    particles: np.ndarray  # (V, 8) int64, global particle numbers
    weights: np.ndarray    # (V, 8) float64, each row sums to 1


@dataclass(frozen=True)
class Surface:
    name: str
    vertices: np.ndarray   # (V, 3) m, at the given positions
    triangles: np.ndarray  # (T, 3) rows of vertices
    radii: np.ndarray | None = None   # (V,) m for balls (spheres at the vertices), else None


def body_surface(body, positions: np.ndarray, radius: np.ndarray | None = None) -> Surface:
    """``body`` (a model.BodySlice) as a triangle mesh at ``positions`` (P, 3); with the
    model's particle ``radius`` (P,), a body of balls gets their radii."""
    embedding = getattr(body, "embedding", None)
    if embedding is not None:
        vertices = np.einsum("vk,vkc->vc", embedding.weights, positions[embedding.particles])
        return Surface(body.name, vertices, np.asarray(body.surface))
    vertices = positions[body.start:body.stop]
    radii = None if radius is None else radius[body.start:body.stop]
    if radii is not None and not np.any(radii > 0):
        radii = None
    return Surface(body.name, vertices, np.asarray(body.surface) - body.start, radii)
