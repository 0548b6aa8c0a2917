"""The fixed arrays of the unfolded-sheet proof (unfolded_sheet.py), built once with the model
(collision/shapes/surfaces.py): whether the self-colliding surface is one consistently
oriented disk, its boundary edges, each particle's ring edges (the edges of U(p), the triangles
with a corner in N[p], that have no end in N[p]), and the particles with a boundary corner in
U(p). The proof that reads them at every step is in unfolded_sheet.py; this is the part that
looks at the mesh only, never at positions.
"""
import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..._jit import kernel
from ..broad_phase.surfaces import joined


def no_sheet() -> dict:
    """The model arrays of a surface that is not one self-colliding disk: no proof tried."""
    return {"sheet_ring_start": np.zeros(1, np.int64),
            "sheet_ring_edges": np.empty((0, 2), np.int32),
            "sheet_boundary": np.empty((0, 2), np.int64),
            "sheet_near_boundary": np.empty(0, np.int64)}


def unfolded_sheet_arrays(triangles, particle_count, neighbour_start, neighbours) -> dict:
    """The ring edges, boundary edges and particles near the boundary (module doc) of the
    surface ``triangles`` if it is one consistently oriented disk, else ``no_sheet``."""
    triangles = np.asarray(triangles, np.int64)
    if len(triangles) == 0 or not is_disk(triangles, particle_count):
        return no_sheet()
    boundary = boundary_edges(triangles, particle_count)
    on_boundary = np.zeros(particle_count, np.bool_)
    on_boundary[boundary.ravel()] = True
    triangle_start, particle_triangles = triangles_of_particles(triangles, particle_count)
    ring_start, ring_edges, near = ring_arrays(triangles, triangle_start, particle_triangles,
                                               neighbour_start, neighbours, on_boundary)
    return {"sheet_ring_start": ring_start, "sheet_ring_edges": ring_edges,
            "sheet_boundary": boundary, "sheet_near_boundary": np.flatnonzero(near)}


def directed_keys(triangles, particle_count):
    """Each triangle's three directed edges (a to b, b to c, c to a) as a b-numbered key."""
    tails = triangles.ravel()
    heads = triangles[:, [1, 2, 0]].ravel()
    return tails * particle_count + heads, tails, heads


def boundary_edges(triangles, particle_count):
    """The directed edges whose reverse no triangle has: the sheet's boundary."""
    keys, tails, heads = directed_keys(triangles, particle_count)
    lonely = ~sorted_holds(np.sort(keys), heads * particle_count + tails)
    return np.stack([tails[lonely], heads[lonely]], axis=1)


def sorted_holds(sorted_keys, keys):
    """Which of ``keys`` are in ``sorted_keys`` (np.isin hashes, which costs more here)."""
    at = np.minimum(np.searchsorted(sorted_keys, keys), len(sorted_keys) - 1)
    return sorted_keys[at] == keys


def distinct_count(keys) -> int:
    """How many different values ``keys`` holds (a sort: np.unique hashes, slower here)."""
    ordered = np.sort(keys)
    return int(len(ordered) > 0) + int(np.count_nonzero(np.diff(ordered)))


def is_disk(triangles, particle_count) -> bool:
    """Whether the triangles form one disk, oriented alike: every directed edge once (each
    edge in at most two triangles, which run it opposite ways), connected, a boundary,
    every particle's triangles one fan, and Euler characteristic V - E + F = 1 (a connected
    orientable surface with boundary and characteristic 1 has genus 0 and one boundary)."""
    keys, tails, heads = directed_keys(triangles, particle_count)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    if np.any(np.diff(sorted_keys) == 0):
        return False
    used = np.flatnonzero(np.bincount(triangles.ravel(), minlength=particle_count))
    undirected = distinct_count(np.minimum(tails, heads) * particle_count
                                + np.maximum(tails, heads))
    if len(used) - undirected + len(triangles) != 1:
        return False
    if np.all(sorted_holds(sorted_keys, heads * particle_count + tails)):
        return False   # no boundary: closed
    graph = coo_matrix((np.ones(len(tails)), (tails, heads)),
                       shape=(particle_count, particle_count))
    labels = connected_components(graph, directed=False)[1]
    if np.any(labels[used] != labels[used[0]]):
        return False
    return one_fan_each(triangles, sorted_keys, order // 3, particle_count)


@kernel
def one_fan_each(triangles, sorted_keys, key_triangle, particle_count):
    """Whether each particle's triangles form one fan: from triangle (v, a, b) the next about v
    is the one with the directed edge v to b; walking on from a triangle with no previous one
    (or any, about an inner particle) must reach them all."""
    corners = triangles.shape[0] * 3
    following = np.full(corners, -1, np.int64)
    has_previous = np.zeros(corners, np.bool_)
    for c in range(corners):
        t, i = c // 3, c % 3
        v, b = triangles[t, i], triangles[t, (i + 2) % 3]
        k = np.searchsorted(sorted_keys, v * particle_count + b)
        if k < sorted_keys.shape[0] and sorted_keys[k] == v * particle_count + b:
            u = key_triangle[k]
            for j in range(3):
                if triangles[u, j] == v:
                    following[c] = 3 * u + j
                    has_previous[3 * u + j] = True
    count = np.zeros(particle_count, np.int64)
    start = np.full(particle_count, -1, np.int64)
    for c in range(corners):
        v = triangles[c // 3, c % 3]
        count[v] += 1
        if start[v] < 0 or not has_previous[c]:
            start[v] = c
    for v in range(particle_count):
        if count[v] == 0:
            continue
        walked, c = 1, following[start[v]]
        while c >= 0 and c != start[v] and walked <= count[v]:
            walked, c = walked + 1, following[c]
        if walked != count[v]:
            return False
    return True


def triangles_of_particles(triangles, particle_count):
    """Each particle's triangles (CSR: start (P + 1,), triangle rows)."""
    corners = triangles.ravel()
    order = np.argsort(corners, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(corners, minlength=particle_count))])
    return start.astype(np.int64), (order // 3).astype(np.int64)


@kernel
def ring_arrays(triangles, triangle_start, particle_triangles, neighbour_start, neighbours,
                on_boundary):
    """Each particle's ring edges (CSR: start (P + 1,), (R, 2) particle pairs) and whether a
    triangle of U(p) has a boundary corner (module doc)."""
    particles = triangle_start.shape[0] - 1
    ring_start = np.zeros(particles + 1, np.int64)
    near = np.zeros(particles, np.bool_)
    # ~12 a particle on a grid cloth; int32: half the memory
    ring_edges = np.empty((16 * particles + 64, 2), np.int32)
    scratch = np.empty((64, 2), np.int32)
    for p in range(particles):
        count = ring_of(p, triangles, triangle_start, particle_triangles, neighbour_start,
                        neighbours, on_boundary, near, scratch)
        if count > scratch.shape[0]:   # a particle of many triangles: now the count is known
            scratch = np.empty((2 * count, 2), np.int32)
            count = ring_of(p, triangles, triangle_start, particle_triangles, neighbour_start,
                            neighbours, on_boundary, near, scratch)
        if ring_start[p] + count > ring_edges.shape[0]:
            grown = np.empty((2 * (ring_start[p] + count), 2), np.int32)
            grown[:ring_start[p]] = ring_edges[:ring_start[p]]
            ring_edges = grown
        ring_edges[ring_start[p]:ring_start[p] + count] = scratch[:count]
        ring_start[p + 1] = ring_start[p] + count
    return ring_start, ring_edges[:ring_start[particles]].copy(), near


@kernel
def ring_of(p, triangles, triangle_start, particle_triangles, neighbour_start, neighbours,
            on_boundary, near, out):
    """Count p's ring edges, each once, writing them to ``out`` while it has room (past that,
    repeats are not seen: the count is then an upper bound)."""
    count = 0
    for k in range(neighbour_start[p] - 1, neighbour_start[p + 1]):
        q = p if k < neighbour_start[p] else neighbours[k]
        for m in range(triangle_start[q], triangle_start[q + 1]):
            t = particle_triangles[m]
            if seen_before(t, p, k, m, triangles, triangle_start, particle_triangles,
                           neighbour_start, neighbours):
                continue
            for i in range(3):
                near[p] = near[p] or on_boundary[triangles[t, i]]
                r, s = triangles[t, i], triangles[t, (i + 1) % 3]
                if in_closed_neighbourhood(p, r, neighbour_start, neighbours) \
                        or in_closed_neighbourhood(p, s, neighbour_start, neighbours):
                    continue
                if not listed(min(r, s), max(r, s), out, count):
                    if count < out.shape[0]:
                        out[count, 0], out[count, 1] = min(r, s), max(r, s)
                    count += 1
    return count


@kernel
def seen_before(t, p, k, m, triangles, triangle_start, particle_triangles, neighbour_start,
                neighbours):
    """Whether triangle t (met as row m of particle q's, q = p or neighbours[k]) was met from
    an earlier particle of N[p]: each triangle of U(p) is read once."""
    for earlier in range(neighbour_start[p] - 1, k):
        q = p if earlier < neighbour_start[p] else neighbours[earlier]
        for i in range(3):
            if triangles[t, i] == q:
                return True
    return False


@kernel
def listed(r, s, out, count):
    """Whether the edge (r, s) is among the first ``count`` rows of ``out`` (where written)."""
    for k in range(min(count, out.shape[0])):
        if out[k, 0] == r and out[k, 1] == s:
            return True
    return False


@kernel
def in_closed_neighbourhood(p, q, neighbour_start, neighbours):
    """Whether q is p or one of its neighbours (broad_phase/surfaces.joined)."""
    return p == q or joined(neighbour_start, neighbours, p, q)
