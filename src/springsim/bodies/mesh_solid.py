"""What a real mesh says about its solid: whether it has an inside at all, and what about it is
unusual (holes, separate shells, parts wound inside out), for one warning line.

A body is filled where the generalized winding number says inside (lattice_fill.py), which
copes with all of these; only a surface with no inside at all (a single open sheet: a plane, a
cloth, a shallow dish) cannot be a body. The test: just off the surface, on its inner side, the
winding number of a closed surface is 1; that of an open sheet stays below about 1/2 on both
sides (exactly 1/2 next to an infinite plane). A mesh has an inside when, beside some of its
triangles, it reaches ``INSIDE`` or more in size.
"""
from typing import NamedTuple

import numpy as np

INSIDE = 0.75            # winding number just off the surface that says "this side is inside"
PROBES = 4096            # triangles probed at most (evenly spread over the file's order)
PROBE_OFFSET = 1e-4      # of the mesh's size: how far off a triangle a probe lies


class Unusual(NamedTuple):
    hole_edges: int          # edges of one triangle only: the rims of holes
    nonmanifold_edges: int   # edges of three or more triangles
    misoriented_edges: int   # edges two triangles run the same way (neighbours wound apart)
    shells: int              # connected pieces of the surface
    inside_out: int          # closed shells whose normals point inwards

    def description(self) -> str:
        """'' for a closed, consistently wound single shell; else what is unusual, in words."""
        words = []
        if self.hole_edges:
            words.append(f"open ({self.hole_edges} edges on the rims of holes)")
        if self.shells > 1:
            words.append(f"{self.shells} separate shells")
        if self.inside_out:
            words.append(f"{self.inside_out} shell{'s' if self.inside_out > 1 else ''} wound "
                         "inside out")
        if self.nonmanifold_edges:
            words.append(f"{self.nonmanifold_edges} edges shared by three or more triangles")
        if self.misoriented_edges:
            words.append(f"{self.misoriented_edges} edges between triangles wound apart")
        return ", ".join(words)


def unusual(vertices: np.ndarray, triangles: np.ndarray) -> Unusual:
    """The oddities of a welded surface (vertices merged by position: welding first, so that UV
    and normal seams are not holes)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    directed = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    edges, inverse, counts = np.unique(undirected, axis=0, return_inverse=True,
                                       return_counts=True)
    inverse = inverse.ravel()
    balance = np.bincount(inverse, np.where(directed[:, 0] < directed[:, 1], 1.0, -1.0))
    # shells: triangles joined through shared edges (a graph of triangles and edges), so that
    # parts that only touch at a vertex (eyes in their sockets) are separate shells
    t, e = len(triangles), len(edges)
    owner = np.tile(np.arange(t), 3)
    graph = coo_matrix((np.ones(3 * t), (owner, t + inverse)), shape=(t + e, t + e))
    _, label = connected_components(graph, directed=False)
    shells, shell_of_triangle = np.unique(label[:t], return_inverse=True)
    edge_shell = np.searchsorted(shells, label[t:])
    # a shell is closed when none of its edges is on a hole; its signed volume then says
    # whether its normals point out
    open_shell = np.zeros(len(shells), bool)
    open_shell[edge_shell[counts == 1]] = True
    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    volume = np.bincount(shell_of_triangle.ravel(), np.einsum("ij,ij->i", a, np.cross(b, c)),
                         minlength=len(shells))
    return Unusual(hole_edges=int(np.count_nonzero(counts == 1)),
                   nonmanifold_edges=int(np.count_nonzero(counts > 2)),
                   misoriented_edges=int(np.count_nonzero((counts == 2) & (balance != 0))),
                   shells=len(shells),
                   inside_out=int(np.count_nonzero(~open_shell & (volume < 0))))


def has_inside(vertices: np.ndarray, triangles: np.ndarray) -> bool:
    """Whether the surface encloses anything (module doc): probes just off both sides of up to
    PROBES triangles."""
    from .lattice_fill import winding_numbers

    a, b, c = (vertices[triangles[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    length = np.linalg.norm(normal, axis=1)
    usable = np.flatnonzero(length > 0)
    if usable.size == 0:
        return False
    usable = usable[np.linspace(0, usable.size - 1, min(PROBES, usable.size)).astype(np.int64)]
    size = float(np.max(np.ptp(vertices, axis=0)))
    # no farther off than a small share of the triangle itself, so the probe sees it as a plane
    offset = np.minimum(PROBE_OFFSET * size, 0.1 * np.sqrt(length[usable]))[:, None]
    centre = (a[usable] + b[usable] + c[usable]) / 3
    unit = normal[usable] / length[usable, None]
    probes = np.concatenate([centre + offset * unit, centre - offset * unit])
    return bool(np.max(np.abs(winding_numbers(vertices, triangles, probes))) >= INSIDE)
