"""Pins that follow a deforming terrain: each particle riveted to the triangle nearest to it.

A deforming mesh has no rigid frame for a pin to keep its place in, but each of its triangles
has one: its closest point to the particle (fixed barycentric weights) and the directions of its
first edge and its normal. A particle is riveted where it starts: the weights of the closest
point on its nearest triangle, and its offset from that point in the triangle's frame, so a
particle off the surface keeps its distance and side as the surface bends and turns (a
degenerate triangle has no frame: a rivet on it keeps to the closest point). At each
sample of the terrain's point cache the rivet is where those give, and the pin's path
(motion.Path) runs through those places, linear between samples as the surface itself is.
"""
import numpy as np

from .attachments import nearest_triangles
from .motion import Path
from .terrains.deforming_mesh import DeformingSurface, surface_at


def riveted_paths(surface: DeformingSurface, positions: np.ndarray) -> list:
    """A Path for each of ``positions`` (n, 3; where the particles are at time 0), from its
    start to its rivet's place at each of the surface's sample times."""
    corners = surface_at(surface, 0.0)[surface.triangles]
    row, weights, _ = nearest_triangles(positions, corners)
    closest = np.einsum("nk,nkc->nc", weights, corners[row])
    offset = np.einsum("nij,nj->ni", triangle_frames(corners[row]), positions - closest)
    moving = surface.samples[:, surface.triangles[row]]               # (F, n, 3 corners, 3)
    placed = np.einsum("nk,fnkc->fnc", weights, moving) + \
        np.einsum("fnic,ni->fnc", triangle_frames(moving), offset)
    return [Path(times=surface.times, displacements=placed[:, j] - positions[j])
            for j in range(len(positions))]


def triangle_frames(corners: np.ndarray) -> np.ndarray:
    """(..., 3, 3): each triangle's orthonormal frame as rows (its first edge's direction, the
    normal's cross that edge, the unit normal), from its corners (..., 3, 3)."""
    edge = corners[..., 1, :] - corners[..., 0, :]
    normal = unit(np.cross(edge, corners[..., 2, :] - corners[..., 0, :]))
    edge = unit(edge)
    return np.stack([edge, np.cross(normal, edge), normal], axis=-2)


def unit(vectors: np.ndarray) -> np.ndarray:
    """Each vector (..., 3) over its length; zero where it has none (a degenerate triangle,
    whose rivet then keeps no offset from its closest point)."""
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)
