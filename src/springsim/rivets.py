"""Pins that follow a deforming terrain: each particle riveted to the triangle nearest to it.

A deforming mesh has no rigid frame for a pin to keep its place in, but each of its triangles
has one: its closest point to the particle (fixed barycentric weights) and the directions of its
first edge and its normal. A particle is riveted where it starts: the weights of the closest
point on its nearest triangle, and its offset from that point in the triangle's frame, so a
particle off the surface keeps its distance and side as the surface bends and turns (a triangle
with no area has no frame, and takes no rivet). A rivet holds at any distance from the surface:
a pin far from it rides on a long lever off one small triangle. At each sample of the
terrain's point cache the rivet is where those give, and the pin's path (motion.Path) runs
through those places, linear between samples (as the closest point is; the offset follows the
chord between the frames of two samples).
"""
import numpy as np

from .attachments import nearest_triangles
from .bodies.pins import followed_terrain
from .errors import require
from .motion import Path
from .terrains.deforming_surface import DeformingSurface, surface_at


def check_rivets(pins, terrains, key: str) -> None:
    """Every pin that follows a deforming terrain has a triangle with area to be riveted to at
    time 0 (``key``: the body's ``bodies.N.pins``)."""
    for p, pin in enumerate(pins):
        t = followed_terrain(pin)
        if 0 <= t < len(terrains) and terrains[t].deforms():
            surface = terrains[t].deforming_surface(f"terrains.{t}")
            require(framed_triangles(surface).size > 0, f"{key}.{p}.follow", pin.follow,
                    f"rivets each particle to its nearest triangle of terrains.{t}, but no "
                    f"triangle of its point cache ({terrains[t].animation.file}) has any area "
                    "at time 0: follow a terrain whose surface has area then, or start its "
                    "animation where it does")


def framed_triangles(surface: DeformingSurface) -> np.ndarray:
    """The triangles with area at time 0 (a triangle with none has no frame to ride in)."""
    corners = surface_at(surface, 0.0)[surface.triangles]
    return np.flatnonzero(np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                                  corners[:, 2] - corners[:, 0]), axis=1) > 0)


def riveted_paths(surface: DeformingSurface, positions: np.ndarray) -> list:
    """A Path for each of ``positions`` (n, 3; where the particles are at time 0), from its
    start to its rivet's place at each of the surface's sample times (and at time 0 itself, on
    its start, where that falls between two samples)."""
    corners = surface_at(surface, 0.0)[surface.triangles]
    usable = framed_triangles(surface)
    row, weights, _ = nearest_triangles(positions, corners[usable])
    row = usable[row]                      # a triangle with no area has no frame to ride in
    closest = np.einsum("nk,nkc->nc", weights, corners[row])
    offset = np.einsum("nij,nj->ni", triangle_frames(corners[row]), positions - closest)
    moving = surface.samples[:, surface.triangles[row]]               # (F, n, 3 corners, 3)
    placed = np.einsum("nk,fnkc->fnc", weights, moving) + \
        np.einsum("fnic,ni->fnc", triangle_frames(moving), offset)
    times, displacements = surface.times, placed - positions
    if times[0] < 0.0 < times[-1] and not np.any(times == 0.0):
        at = int(np.searchsorted(times, 0.0))
        times, displacements = np.insert(times, at, 0.0), np.insert(displacements, at, 0.0, 0)
    return [Path(times=times, displacements=displacements[:, j]) for j in range(len(positions))]


def triangle_frames(corners: np.ndarray) -> np.ndarray:
    """(..., 3, 3): each triangle's orthonormal frame as rows (its first edge's direction, the
    normal's cross that edge, the unit normal), from its corners (..., 3, 3)."""
    edge = corners[..., 1, :] - corners[..., 0, :]
    normal = unit(np.cross(edge, corners[..., 2, :] - corners[..., 0, :]))
    edge = unit(edge)
    return np.stack([edge, np.cross(normal, edge), normal], axis=-2)


def unit(vectors: np.ndarray) -> np.ndarray:
    """Each vector (..., 3) over its length; zero where it has none (a triangle that a cache
    folds flat later keeps its rivet on its closest point for that sample)."""
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 0)
