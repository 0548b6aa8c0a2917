"""A mesh terrain that deforms: its vertices follow a point cache (animation.py), as a character
animated by an armature, shape keys or modifiers does when Blender or Houdini bakes it.

Why not the still mesh's distance grid (mesh.py): that grid takes a second to build and the
surface changes at every step. Here the kernels keep the surface itself, refitted to the time
asked for (``deform``, called by world.move_world at every step and stage): positions and
velocities interpolated from the cache, the triangles' unit normals, the angle-weighted vertex
and edge pseudonormals (Baerentzen and Aanaes), and a uniform grid of cells listing the
triangles whose box, grown by ``reach``, covers the cell. A point then asks only its own cell:
every triangle within ``reach`` of it is listed there, so the closest one found is the exact
closest triangle wherever the distance is below ``reach``; beyond, the point is free: the lookup
answers an infinite distance, as the still dispatcher does for a kind it skips (a finite answer
with a made-up normal would be, to backward Euler's look-ahead phi + h v_n < epsilon, a surface
that near, and hold back whatever falls fast). Its sign comes from the pseudonormal of the
closest feature (face, edge or vertex), which is exact for a closed mesh and gives an open one
the side its faces' normals point to, as the still mesh's libigl distances do. Contact velocity
is the closest point's, interpolated from its triangle's corners (``deformed_velocity``).

A lookup skips a listed triangle whose bounding sphere (its centroid and farthest corner,
refitted with the normals) lies farther than the closest triangle found so far: a cell lists
every triangle within reach of any of its points, dozens to hundreds where a fast limb makes
reach large, and most are far from the point asking. Each entry of a cell holds its triangle's
sphere beside its number (ENTRY values), so that the skipping reads the cell's entries in order
instead of each triangle's sphere wherever it lies in memory.
``reach`` is the larger of 4 contact bands (``epsilon``) and the farthest a vertex moves between
two samples of the cache, plus the largest offset a particle keeps from terrains (a ball's
radius): a particle the surface passes within one sample is still found, and so is a ball's
centre, which touches at its radius. The grid covers every sample's box grown by ``reach``; its
cells are at least 2 reach and at least the mean edge long, and at most MAX_CELLS of them. The
entry list is sized once from the union of each triangle's boxes at consecutive samples, which
holds every box between them (positions move linearly), so refitting never allocates. These
sizes are chosen, and the block laid out, in NumPy when the model is built
(deforming_surface.py); the kernels here refit it and look points up in it.

The data block of one deforming terrain, in the shared terrain_data (offsets from its start,
``layout``): a header (vertex, triangle, edge and sample counts, entry capacity, the time last
refitted to, reach, cell count, the grid's origin, cell size and counts), the sample times, the
samples, the triangles and their edges, then what ``deform`` writes: positions, velocities,
vertex, edge and face normals, the triangles' bounding spheres, cell starts and entries.
"""
import math

import numpy as np

from .._jit import inline_kernel, kernel
from ..geometry.closest_points import closest_on_triangle
from .base import register

HEADER = 16
ENTRY = 5          # values a cell entry holds: the triangle, its sphere's centre and radius
VERTICES, TRIANGLES, EDGES, SAMPLES, CAPACITY, LAST_TIME, REACH, CELLS = range(8)
ORIGIN, CELL, COUNTS = 8, 11, 12


@kernel
def layout(data, s):
    """Offsets of the block's parts (module doc)."""
    v, t, e = int(data[s + VERTICES]), int(data[s + TRIANGLES]), int(data[s + EDGES])
    f, c = int(data[s + SAMPLES]), int(data[s + CELLS])
    times = s + HEADER
    samples = times + f
    triangles = samples + 3 * f * v
    triangle_edges = triangles + 3 * t
    positions = triangle_edges + 3 * t
    velocities = positions + 3 * v
    vertex_normals = velocities + 3 * v
    edge_normals = vertex_normals + 3 * v
    face_normals = edge_normals + 3 * e
    spheres = face_normals + 3 * t
    cell_starts = spheres + 4 * t
    entries = cell_starts + c + 1
    return (times, samples, triangles, triangle_edges, positions, velocities, vertex_normals,
            edge_normals, face_normals, spheres, cell_starts, entries)


@kernel
def deform(data, s, t):
    """Refit the block at ``s`` to time t (s): positions, velocities, normals and cells."""
    if data[s + LAST_TIME] == t:
        return
    (times, samples, triangles, triangle_edges, positions, velocities, vertex_normals,
     edge_normals, face_normals, spheres, cell_starts, entries) = layout(data, s)
    interpolate(data, s, t, times, samples, positions, velocities)
    refit_normals(data, s, triangles, triangle_edges, positions, vertex_normals, edge_normals,
                  face_normals, spheres)
    refit_cells(data, s, triangles, positions, spheres, cell_starts, entries)
    data[s + LAST_TIME] = t


@kernel
def interpolate(data, s, t, times, samples, positions, velocities):
    """Positions and velocities at t: linear between samples, held outside them."""
    v, f = int(data[s + VERTICES]), int(data[s + SAMPLES])
    k, w, rate = 0, 0.0, 0.0
    if f > 1 and t > data[times]:
        if t >= data[times + f - 1]:
            k = f - 1
        else:
            while data[times + k + 1] <= t:
                k += 1
            span = data[times + k + 1] - data[times + k]
            w, rate = (t - data[times + k]) / span, 1.0 / span
    here = samples + 3 * v * k
    there = here + 3 * v if k < f - 1 else here
    for i in range(3 * v):
        a, b = data[here + i], data[there + i]
        data[positions + i] = a + w * (b - a)
        data[velocities + i] = (b - a) * rate


@kernel
def refit_normals(data, s, triangles, triangle_edges, positions, vertex_normals, edge_normals,
                  face_normals, spheres):
    """Unit face normals; edge normals (the sum of their faces'); angle-weighted vertex normals;
    and each triangle's bounding sphere (``bounding_sphere``), in the same pass."""
    v, t, e = int(data[s + VERTICES]), int(data[s + TRIANGLES]), int(data[s + EDGES])
    for i in range(3 * v):
        data[vertex_normals + i] = 0.0
    for i in range(3 * e):
        data[edge_normals + i] = 0.0
    for tri in range(t):
        a, b, c = (int(data[triangles + 3 * tri]), int(data[triangles + 3 * tri + 1]),
                   int(data[triangles + 3 * tri + 2]))
        corner = (a, b, c)
        n0, n1, n2 = face_normal(data, positions, a, b, c)
        data[face_normals + 3 * tri] = n0
        data[face_normals + 3 * tri + 1] = n1
        data[face_normals + 3 * tri + 2] = n2
        bounding_sphere(data, positions, a, b, c, spheres + 4 * tri)
        for k in range(3):
            edge = int(data[triangle_edges + 3 * tri + k])
            data[edge_normals + 3 * edge] += n0
            data[edge_normals + 3 * edge + 1] += n1
            data[edge_normals + 3 * edge + 2] += n2
            angle = corner_angle(data, positions, corner[k], corner[(k + 1) % 3],
                                 corner[(k + 2) % 3])
            data[vertex_normals + 3 * corner[k]] += angle * n0
            data[vertex_normals + 3 * corner[k] + 1] += angle * n1
            data[vertex_normals + 3 * corner[k] + 2] += angle * n2


@kernel
def bounding_sphere(data, positions, a, b, c, out):
    """data[out:out + 4] = the centroid of corners a, b, c and the distance to the farthest,
    grown by a part in 10^9 so that rounding never leaves a corner outside."""
    pa, pb, pc = positions + 3 * a, positions + 3 * b, positions + 3 * c
    third = 1.0 / 3.0
    c0 = (data[pa] + data[pb] + data[pc]) * third
    c1 = (data[pa + 1] + data[pb + 1] + data[pc + 1]) * third
    c2 = (data[pa + 2] + data[pb + 2] + data[pc + 2]) * third
    farthest = 0.0
    for p in (pa, pb, pc):
        d0, d1, d2 = data[p] - c0, data[p + 1] - c1, data[p + 2] - c2
        farthest = max(farthest, d0 * d0 + d1 * d1 + d2 * d2)
    data[out], data[out + 1], data[out + 2] = c0, c1, c2
    data[out + 3] = math.sqrt(farthest) * (1.0 + 1e-9)


@kernel
def difference(data, positions, a, b):
    """Vertex b's position minus vertex a's."""
    return (data[positions + 3 * b] - data[positions + 3 * a],
            data[positions + 3 * b + 1] - data[positions + 3 * a + 1],
            data[positions + 3 * b + 2] - data[positions + 3 * a + 2])


@kernel
def face_normal(data, positions, a, b, c):
    ab0, ab1, ab2 = difference(data, positions, a, b)
    ac0, ac1, ac2 = difference(data, positions, a, c)
    n0, n1, n2 = ab1 * ac2 - ab2 * ac1, ab2 * ac0 - ab0 * ac2, ab0 * ac1 - ab1 * ac0
    size = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if size == 0.0:
        return 0.0, 0.0, 0.0
    return n0 / size, n1 / size, n2 / size


@kernel
def corner_angle(data, positions, a, b, c):
    """The triangle's angle at corner a (radians)."""
    u0, u1, u2 = difference(data, positions, a, b)
    w0, w1, w2 = difference(data, positions, a, c)
    c0, c1, c2 = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0
    return math.atan2(math.sqrt(c0 * c0 + c1 * c1 + c2 * c2), u0 * w0 + u1 * w1 + u2 * w2)


@kernel
def cell_range(data, s, axis, low, high):
    """The cells first..last along ``axis`` that low..high grown by reach covers, clamped to
    the grid (last < first where it misses the grid)."""
    reach, cell = data[s + REACH], data[s + CELL]
    n, origin = int(data[s + COUNTS + axis]), data[s + ORIGIN + axis]
    return (max(int(math.floor((low - reach - origin) / cell)), 0),
            min(int(math.floor((high + reach - origin) / cell)), n - 1))


@kernel
def refit_cells(data, s, triangles, positions, spheres, cell_starts, entries):
    """List each triangle in the cells its box grown by reach covers, with its bounding sphere
    (refit_normals' spheres: module doc); triangles in ascending order within a cell."""
    t, cells = int(data[s + TRIANGLES]), int(data[s + CELLS])
    n1, n2 = int(data[s + COUNTS + 1]), int(data[s + COUNTS + 2])
    capacity = int(data[s + CAPACITY])
    for c in range(cells + 1):
        data[cell_starts + c] = 0.0
    low, high = np.empty(3), np.empty(3)
    for sweep in range(2):   # count, then fill
        if sweep == 1:
            total = 0.0
            for c in range(cells):
                count = data[cell_starts + c]
                data[cell_starts + c] = total
                total += count
            data[cell_starts + cells] = total
        for tri in range(t):
            triangle_box(data, triangles, positions, tri, low, high)
            i0, i1 = cell_range(data, s, 0, low[0], high[0])
            j0, j1 = cell_range(data, s, 1, low[1], high[1])
            k0, k1 = cell_range(data, s, 2, low[2], high[2])
            for i in range(i0, i1 + 1):
                for j in range(j0, j1 + 1):
                    for k in range(k0, k1 + 1):
                        c = (i * n1 + j) * n2 + k
                        if sweep == 0:
                            data[cell_starts + c] += 1.0
                        else:
                            slot = int(data[cell_starts + c])
                            if slot < capacity:
                                write_entry(data, entries + ENTRY * slot, tri, spheres)
                            data[cell_starts + c] = slot + 1
    for c in range(cells, 0, -1):   # each cell's end is the next one's start
        data[cell_starts + c] = data[cell_starts + c - 1]
    data[cell_starts] = 0.0


@inline_kernel
def write_entry(data, at, tri, spheres):
    """A cell entry at ``at``: the triangle's number, then its bounding sphere (module doc)."""
    data[at] = tri
    for k in range(4):
        data[at + 1 + k] = data[spheres + 4 * tri + k]


@kernel
def triangle_box(data, triangles, positions, tri, low, high):
    for axis in range(3):
        low[axis], high[axis] = np.inf, -np.inf
    for k in range(3):
        corner = int(data[triangles + 3 * tri + k])
        for axis in range(3):
            x = data[positions + 3 * corner + axis]
            low[axis], high[axis] = min(low[axis], x), max(high[axis], x)


@kernel
def closest_triangle(data, s, x0, x1, x2):
    """(squared distance, triangle, barycentric weights) of the point of the surface closest to
    x among the triangles listed in x's cell; triangle -1 when none is within reach. A triangle
    whose bounding sphere is farther than the best so far is skipped (module doc)."""
    reach = data[s + REACH]
    best, found, w0, w1, w2 = reach * reach, -1, 0.0, 0.0, 0.0
    bound = reach   # sqrt(best)
    cell = data[s + CELL]
    index = 0
    for axis in range(3):
        coordinate = (x0, x1, x2)[axis]
        n = int(data[s + COUNTS + axis])
        i = int(math.floor((coordinate - data[s + ORIGIN + axis]) / cell))
        if i < 0 or i >= n:
            return best, -1, w0, w1, w2
        index = index * n + i
    (times, samples, triangles, triangle_edges, positions, velocities, vertex_normals,
     edge_normals, face_normals, spheres, cell_starts, entries) = layout(data, s)
    for e in range(int(data[cell_starts + index]), int(data[cell_starts + index + 1])):
        entry = entries + ENTRY * e
        g0, g1, g2 = x0 - data[entry + 1], x1 - data[entry + 2], x2 - data[entry + 3]
        far = bound + data[entry + 4]
        if g0 * g0 + g1 * g1 + g2 * g2 > far * far:
            continue
        tri = int(data[entry])
        a, b, c = (int(data[triangles + 3 * tri]), int(data[triangles + 3 * tri + 1]),
                   int(data[triangles + 3 * tri + 2]))
        corners = ((data[positions + 3 * a], data[positions + 3 * a + 1],
                    data[positions + 3 * a + 2]),
                   (data[positions + 3 * b], data[positions + 3 * b + 1],
                    data[positions + 3 * b + 2]),
                   (data[positions + 3 * c], data[positions + 3 * c + 1],
                    data[positions + 3 * c + 2]))
        u0, u1, u2 = closest_on_triangle((x0, x1, x2), corners)
        d0 = x0 - (u0 * corners[0][0] + u1 * corners[1][0] + u2 * corners[2][0])
        d1 = x1 - (u0 * corners[0][1] + u1 * corners[1][1] + u2 * corners[2][1])
        d2 = x2 - (u0 * corners[0][2] + u1 * corners[1][2] + u2 * corners[2][2])
        squared = d0 * d0 + d1 * d1 + d2 * d2
        if squared < best:
            best, found, w0, w1, w2 = squared, tri, u0, u1, u2
            bound = math.sqrt(best)
    return best, found, w0, w1, w2


@kernel
def deformed_distance(row, data, x0, x1, x2):
    """Signed distance (m) to the surface as last refitted, and its unit normal; infinity and
    straight up where nothing is within reach. row[0]: the block's start in data."""
    s = int(row[0])
    squared, tri, w0, w1, w2 = closest_triangle(data, s, x0, x1, x2)
    if tri < 0:
        return math.inf, 0.0, 1.0, 0.0
    (times, samples, triangles, triangle_edges, positions, velocities, vertex_normals,
     edge_normals, face_normals, spheres, cell_starts, entries) = layout(data, s)
    p0 = p1 = p2 = 0.0
    for k, w in enumerate((w0, w1, w2)):
        corner = int(data[triangles + 3 * tri + k])
        p0 += w * data[positions + 3 * corner]
        p1 += w * data[positions + 3 * corner + 1]
        p2 += w * data[positions + 3 * corner + 2]
    # the closest feature's pseudonormal: a corner (two weights zero), an edge (one), the face
    if (w1 == 0.0 and w2 == 0.0) or (w0 == 0.0 and w2 == 0.0) or (w0 == 0.0 and w1 == 0.0):
        k = 0 if w0 > 0.0 else (1 if w1 > 0.0 else 2)
        base = vertex_normals + 3 * int(data[triangles + 3 * tri + k])
    elif w0 == 0.0 or w1 == 0.0 or w2 == 0.0:
        k = 0 if w2 == 0.0 else (1 if w0 == 0.0 else 2)   # edge k joins corners k and k + 1
        base = edge_normals + 3 * int(data[triangle_edges + 3 * tri + k])
    else:
        base = face_normals + 3 * tri
    m0, m1, m2 = data[base], data[base + 1], data[base + 2]
    d0, d1, d2 = x0 - p0, x1 - p1, x2 - p2
    sign = 1.0 if d0 * m0 + d1 * m1 + d2 * m2 >= 0.0 else -1.0
    distance = math.sqrt(squared)
    if distance > 1e-12:
        return sign * distance, sign * d0 / distance, sign * d1 / distance, sign * d2 / distance
    size = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    if size == 0.0:
        return 0.0, 0.0, 1.0, 0.0
    return 0.0, m0 / size, m1 / size, m2 / size


@kernel
def deformed_velocity(data, s, x0, x1, x2):
    """Velocity (m/s) of the surface's closest point to x: its triangle's corners' velocities,
    interpolated; zero where nothing is within reach."""
    squared, tri, w0, w1, w2 = closest_triangle(data, s, x0, x1, x2)
    if tri < 0:
        return 0.0, 0.0, 0.0
    (times, samples, triangles, triangle_edges, positions, velocities, vertex_normals,
     edge_normals, face_normals, spheres, cell_starts, entries) = layout(data, s)
    u0 = u1 = u2 = 0.0
    for k, w in enumerate((w0, w1, w2)):
        corner = int(data[triangles + 3 * tri + k])
        u0 += w * data[velocities + 3 * corner]
        u1 += w * data[velocities + 3 * corner + 1]
        u2 += w * data[velocities + 3 * corner + 2]
    return u0, u1, u2


class DeformingMesh:
    """The kind a mesh terrain with an ``animation`` packs as (mesh.py): it has no scene type
    of its own."""

    distance_kernel = deformed_distance
    look_ahead = True
    never_still = True   # never looked up as a still terrain (dispatch.still_terrain_distance)


register(DeformingMesh, {}, order=4)
