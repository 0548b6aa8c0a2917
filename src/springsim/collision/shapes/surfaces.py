"""The shapes that touch in body-body contact, gathered from the bodies when the model is built.

Every body with a surface (collision/shapes/settings.py.SurfaceContact) gives
- its collision triangles: its surface, or for a mesh body (whose drawn surface rides the
  lattice) the boundary faces of its lattice (``BuiltBody.collision_surface``);
- as points, the particles at their corners (a cube's interior particles never touch first);
- the edges of its triangles, for edge-edge contact (two edges cross where no corner pokes
  through: the edges of two cubes' faces, a cloth folding over its own edge).
The arrays are empty when no pair can touch (one body that does not collide with itself, or
bodies without surfaces): then the contact pass costs nothing.
"""
import numpy as np

from ..pair_lists.unfolded_sheet import no_sheet, unfolded_sheet_arrays
from .settings import SurfaceContact


def surface_contact_arrays(specs, built, offsets) -> dict:
    """The ModelArrays entries of body-body contact (model.ModelArrays documents them)."""
    particle_body = np.repeat(np.arange(len(built), dtype=np.int64), np.diff(offsets))
    settings = [spec if isinstance(spec, SurfaceContact) else None for spec in specs]
    triangles = [collision_triangles(b) + start if s is not None else np.empty((0, 3), np.int64)
                 for s, b, start in zip(settings, built, offsets)]
    touching = [s is not None and len(t) > 0 for s, t in zip(settings, triangles)]
    selfish = [touch and s.self_collision for s, touch in zip(settings, touching)]
    if sum(touching) < 2 and not any(selfish):
        triangles, selfish = [np.empty((0, 3), np.int64)], [False]
        touching = [False] * len(built)
    all_triangles = np.concatenate([t for t, touch in zip(triangles, touching) if touch]
                                   or [np.empty((0, 3), np.int64)])
    edges = [triangle_edges(t) for t, touch in zip(triangles, touching) if touch]

    def per_body(name, default):
        return np.array([getattr(s, name) if s is not None else default for s in settings],
                        dtype=type(default))

    all_edges = (np.concatenate(edges) if edges else np.empty((0, 2), np.int64)).astype(np.int64)
    neighbourhood = neighbour_arrays(all_edges, len(particle_body))
    # one self-colliding sheet: the pair search may be spared where it lies unfolded
    sheet = (unfolded_sheet_arrays(all_triangles, len(particle_body),
                                   neighbourhood["neighbour_start"], neighbourhood["neighbours"])
             if sum(touching) == 1 and any(selfish) else no_sheet())
    return {"particle_body": particle_body,
            "surface_points": np.unique(all_triangles).astype(np.int64),
            "surface_triangles": all_triangles.astype(np.int64),
            "surface_edges": all_edges,
            **neighbourhood, **sheet,
            "body_thickness": np.array([s.contact_thickness() if s is not None else 0.0
                                        for s in settings]),
            "body_self_collision": per_body("self_collision", False),
            "body_friction": per_body("friction", 0.0),
            "body_static_friction": per_body("static_friction", 0.0),
            "body_restitution": per_body("restitution", 0.0)}


def neighbour_arrays(edges: np.ndarray, particle_count: int) -> dict:
    """Each particle's neighbours along surface edges (CSR, ascending): a body's self-contact
    leaves out pairs of neighbours. Why: on a flat cloth the boxes of a triangle and of the
    particles around it overlap, and testing those pairs every step cost 10 times the step;
    two neighbours never come closer than their spring and bend springs let them."""
    both = np.concatenate([edges, edges[:, ::-1]])
    both = both[np.lexsort((both[:, 1], both[:, 0]))]
    counts = np.bincount(both[:, 0], minlength=particle_count)
    return {"neighbour_start": np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            "neighbours": both[:, 1].astype(np.int64)}


def collision_triangles(built) -> np.ndarray:
    """A body's collision triangles in its own particle numbers."""
    surface = getattr(built, "collision_surface", None)
    if surface is None:
        surface = built.surface if built.embedding is None else np.empty((0, 3))
    return np.asarray(surface, np.int64).reshape(-1, 3)


def triangle_edges(triangles: np.ndarray) -> np.ndarray:
    """The distinct edges (lower, higher particle number) of the triangles, sorted."""
    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return np.unique(np.sort(edges, axis=1), axis=0)
