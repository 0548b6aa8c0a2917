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

from ..pair_lists.sheet_arrays import no_sheet, unfolded_sheet_arrays
from .settings import SurfaceContact


def surface_contact_arrays(specs, built, offsets, joined=np.empty((0, 4), np.int64)) -> dict:
    """The ModelArrays entries of body-body contact (model.ModelArrays documents them).

    Contact tells bodies apart by ``particle_body``, which numbers *contact bodies*: each
    connected piece of a body (particles joined by springs or surface edges) is one, so that the
    separate parts of a mesh body, or two panels in one cloth file, collide with each other as
    two bodies would; they share their body's settings. Pieces that an attachment joins
    (``joined``: rows of particle numbers, attachments.py) are one contact body: a seam, where
    the two surfaces meet, is not a contact."""
    settings = [spec if isinstance(spec, SurfaceContact) else None for spec in specs]
    particle_body, owner = joined_contact_bodies(*contact_bodies(settings, built, offsets),
                                                 joined)
    triangles = [collision_triangles(b) + start if s is not None else np.empty((0, 3), np.int64)
                 for s, b, start in zip(settings, built, offsets)]
    body_touches = np.array([s is not None and len(t) > 0 for s, t in zip(settings, triangles)])
    touching = body_touches[owner]
    selfish = [touch and settings[b].self_collision for b, touch in zip(owner, touching)]
    if touching.sum() < 2 and not any(selfish):
        triangles, selfish = [np.empty((0, 3), np.int64)], [False]
        body_touches[:] = False
        touching[:] = False
    all_triangles = np.concatenate([t for t, touch in zip(triangles, body_touches) if touch]
                                   or [np.empty((0, 3), np.int64)])
    edges = [triangle_edges(t) for t, touch in zip(triangles, body_touches) if touch]

    def per_body(name, default):
        values = [getattr(s, name) if s is not None else default for s in settings]
        return np.array(values, dtype=type(default))[owner]

    all_edges = (np.concatenate(edges) if edges else np.empty((0, 2), np.int64)).astype(np.int64)
    # a bound particle and its triangle's corners are neighbours too: a body that collides
    # with itself does not push a seam apart
    bound = np.asarray(joined, np.int64)
    links = np.column_stack([np.repeat(bound[:, 0], 3), bound[:, 1:].ravel()])
    neighbourhood = neighbour_arrays(np.concatenate([all_edges, links]), len(particle_body))
    # one self-colliding sheet: the pair search may be spared where it lies unfolded
    sheet = (unfolded_sheet_arrays(all_triangles, len(particle_body),
                                   neighbourhood["neighbour_start"], neighbourhood["neighbours"])
             if touching.sum() == 1 and any(selfish) else no_sheet())
    thickness = np.array([s.contact_thickness() if s is not None else 0.0 for s in settings])
    return {"particle_body": particle_body,
            "surface_points": np.unique(all_triangles).astype(np.int64),
            "surface_triangles": all_triangles.astype(np.int64),
            "surface_edges": all_edges,
            **neighbourhood, **sheet,
            "body_thickness": thickness[owner],
            "body_self_collision": per_body("self_collision", False),
            "body_friction": per_body("friction", 0.0),
            "body_static_friction": per_body("static_friction", 0.0),
            "body_restitution": per_body("restitution", 0.0)}


def contact_bodies(settings, built, offsets) -> tuple[np.ndarray, np.ndarray]:
    """(P,) each particle's contact body, and (C,) the body each contact body is a piece of:
    a body that takes part in contact has one per connected piece, any other body one."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    labels, owner = [], []
    for b, (spec, body) in enumerate(zip(settings, built)):
        count = len(body.masses)
        pieces, label = 1, np.zeros(count, np.int64)
        if spec is not None and count:
            links = np.concatenate([np.asarray(body.springs, np.int64).reshape(-1, 2),
                                    triangle_edges(collision_triangles(body))])
            graph = coo_matrix((np.ones(len(links)), (links[:, 0], links[:, 1])),
                               shape=(count, count))
            pieces, label = connected_components(graph, directed=False)
        labels.append(label.astype(np.int64) + len(owner))
        owner += [b] * pieces
    particle_body = np.concatenate(labels) if labels else np.empty(0, np.int64)
    return particle_body, np.asarray(owner, np.int64)


def joined_contact_bodies(particle_body, owner, joined) -> tuple[np.ndarray, np.ndarray]:
    """``particle_body`` and ``owner`` (contact_bodies) with the contact bodies that a row of
    ``joined`` touches made one, numbered in the order of their lowest old number and owned
    by that one's body."""
    if len(joined) == 0:
        return particle_body, owner
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    pieces = particle_body[joined]                       # (A, 4) contact bodies
    first = np.repeat(pieces[:, :1], pieces.shape[1] - 1, axis=1).ravel()
    graph = coo_matrix((np.ones(len(first)), (first, pieces[:, 1:].ravel())),
                       shape=(len(owner), len(owner)))
    count, label = connected_components(graph, directed=False)   # labels by lowest member
    lowest = np.full(count, len(owner), np.int64)
    np.minimum.at(lowest, label, np.arange(len(owner)))
    return label.astype(np.int64)[particle_body], owner[lowest]


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
