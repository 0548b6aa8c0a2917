"""The meshes an exporter writes: a piece per body surface, a sphere per ball, a mesh per terrain.

Every moving vertex is a fixed weighted sum of particles plus a fixed offset,

    vertex_v(t) = sum_k weights[v, k] * x[particles[v, k]](t) + offsets[v],

which covers a cube's or cloth's surface (one particle, weight 1), a mesh body's embedded surface
(eight particles, trilinear weights) and a ball's sphere (the centre particle plus radius times a
unit direction), so that one line computes any piece at every frame.
"""
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from ..meshfiles import is_closed
from ..terrains.display import sphere_mesh

BALL_LATITUDES, BALL_LONGITUDES = 8, 16     # a ball's sphere in a point cache: 114 vertices


@dataclass(frozen=True)
class Piece:
    name: str
    triangles: np.ndarray   # (T, 3) rows of this piece's vertices
    particles: np.ndarray   # (V, K) particle numbers
    weights: np.ndarray     # (V, K)
    offsets: np.ndarray     # (V, 3) m
    closed: bool

    @property
    def vertex_count(self) -> int:
        return len(self.particles)

    def vertices(self, positions: np.ndarray) -> np.ndarray:
        """The vertices at ``positions`` (..., P, 3): (..., V, 3)."""
        if self.particles.shape[1] == 1 and np.all(self.weights == 1.0):
            vertices = positions[..., self.particles[:, 0], :]
        else:
            vertices = np.einsum("vk,...vkc->...vc", self.weights,
                                 positions[..., self.particles, :])
        return vertices + self.offsets if np.any(self.offsets) else vertices


def body_pieces(layout, first_positions) -> list[Piece]:
    """One piece per body with surface triangles (balls and bare particle sets have none); a
    closed surface is wound to face outwards at ``first_positions`` (P, 3), as USD, Blender and
    browsers expect of a front face (counter-clockwise seen from outside)."""
    pieces = [body_piece(body) for body in layout.bodies if len(body.surface)]
    return [facing_outwards(piece, first_positions) for piece in pieces]


def facing_outwards(piece: Piece, positions) -> Piece:
    """``piece`` with its triangles reversed if they enclose a negative volume (face inwards)."""
    if not piece.closed:
        return piece
    x = piece.vertices(positions)
    a, b, c = (x[piece.triangles[:, k]] for k in range(3))
    if np.einsum("ij,ij->", a, np.cross(b, c)) >= 0:     # 6 x the enclosed volume
        return piece
    return replace(piece, triangles=np.ascontiguousarray(piece.triangles[:, ::-1]))


def body_piece(body) -> Piece:
    surface = np.asarray(body.surface, np.int64)
    if body.embedding is not None:
        particles = np.asarray(body.embedding.particles, np.int64)
        weights = np.asarray(body.embedding.weights, float)
        triangles = surface
    else:  # only the particles on the surface, in ascending order
        used, triangles = np.unique(surface, return_inverse=True)
        particles, weights = used[:, None], np.ones((len(used), 1))
        triangles = triangles.reshape(-1, 3)
    return Piece(body.name, triangles, particles, weights, np.zeros((len(particles), 3)),
                 is_closed(triangles))


def ball_pieces(layout) -> list[Piece]:
    """A UV sphere per ball, following its centre (point caches have no spheres of their own)."""
    pieces = []
    for number, (particle, radius) in enumerate(zip(layout.ball_particles, layout.ball_radii)):
        offsets, triangles = sphere_mesh((0.0, 0.0, 0.0), float(radius), BALL_LATITUDES,
                                         BALL_LONGITUDES)
        count = len(offsets)
        pieces.append(Piece(f"ball_{number}", triangles, np.full((count, 1), particle),
                            np.ones((count, 1)), offsets, True))
    return pieces


def point_pieces(layout, first_positions) -> list[Piece]:
    """Everything that moves, as meshes: the body surfaces, then a sphere per ball (the order of
    a point cache's points and of its rest mesh's vertices)."""
    return body_pieces(layout, first_positions) + ball_pieces(layout)


def stacked_vertices(pieces, positions: np.ndarray) -> np.ndarray:
    """(F, N, 3): every piece's vertices at each of ``positions`` (F, P, 3), one after another."""
    if not pieces:
        return np.empty((len(positions), 0, 3))
    return np.concatenate([piece.vertices(positions) for piece in pieces], axis=1)


def unique_names(names) -> list[str]:
    """The names, with _2, _3, ... added to repeats (prims and OBJ groups need distinct ones)."""
    seen, result = {}, []
    for name in names:
        name = name or "body"
        count = seen.get(name, 0) + 1
        seen[name] = count
        result.append(name if count == 1 else f"{name}_{count}")
    return result


# --- terrains ---------------------------------------------------------------------------------

class TerrainPiece(NamedTuple):
    """A terrain's display mesh as placed (its vertices where it starts), and the terrain,
    which says where they are at a later time (``vertices_at``) if it moves."""

    name: str
    vertices: np.ndarray
    triangles: np.ndarray
    terrain: object


def terrain_meshes(layout, positions) -> list[TerrainPiece]:
    """A TerrainPiece for every terrain whose kind has an export mesh (its ``export_mesh``:
    terrains/base.py), under the whole motion ``positions`` (F, P, 3)."""
    meshes = []
    for number, terrain in enumerate(layout.terrains):
        mesh = terrain.export_mesh(positions)
        if mesh is not None:
            name = f"terrain_{number}_{type(terrain).__name__.lower()}"
            meshes.append(TerrainPiece(name, *mesh, terrain))
    return meshes
