"""A jelly body from a closed triangle mesh: a lattice of particles filling the mesh, joined by
the cube's springs, with the mesh's own surface riding the lattice.

- The lattice: points at the placed mesh's bounding-box minimum corner plus whole multiples of
  ``spacing``, kept when inside the mesh (a point within 1e-6 x spacing of the surface counts as
  inside, so that a box's faces keep their points). Particles are numbered in lattice order (x
  slowest, z fastest), as the cube's are, and joined by the cube's spring pattern where both ends
  are kept: a 4 m box at spacing 4/9 is exactly the default cube.
- The surface (the idea of Newton's soft grid with a visual mesh and MuJoCo's trilinear
  flexcomp): each vertex of the mesh is a fixed trilinear combination of the eight corners of a
  full lattice cell (all eight corners kept), computed once. A vertex in a full cell uses it; the
  others (the surface passes through cells that are partly outside) use the nearest full cell,
  with the weights extended beyond it. Trilinear weights reproduce any affine map, so at t = 0
  the surface is the input mesh to round-off either way. A vertex farther than one spacing from
  every full cell lies in a part too thin for the lattice; a warning says how many.
- Contact: terrains push on the particles, and the surface reaches up to about a spacing beyond
  the outer ones. Each particle therefore keeps a terrain at the distance of the farthest surface
  vertex for which it is the nearest corner of its cell (its ``terrain_offsets``), as a ball keeps
  its radius: every vertex lies within that distance of a particle that stays that far from the
  terrain, so no vertex of a body at rest goes below it. Where the surface passes through the
  particles (a box), the offsets are zero. Other bodies (body-body contact,
  collision/shapes/surfaces.py) touch a mesh body through the boundary faces of its lattice, kept
  ``thickness`` apart as any surface: the faces of full cells whose neighbour across the face is
  not full, two triangles each (``collision_surface``, lattice_boundary). That boundary lies within
  about a spacing inside the drawn surface (on it for a box), so another body may be seen to sink
  up to about a spacing into the drawn mesh. Particles that are a corner of no full cell (thin
  parts, and some points just inside a curved surface) are on no such face: they are not touched by
  other bodies.
"""
import functools
import os
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SceneError, is_finite, require
from ..meshfiles import check_closed, placed, read_mesh, validate_placement
from ..surfaces import Embedding
from . import BuiltBody
from .cube import LatticeSprings, lattice_pattern, spring_parameters
from ..collision.shapes.settings import SurfaceContact

INSIDE_TOLERANCE = 1e-6   # of the spacing: a lattice point this close to the surface is inside
# memory per lattice point of the bounding box while testing it (positions, distances, closest
# points), and per particle of the model (its springs, state and the integrators' work arrays)
BYTES_PER_LATTICE_POINT = 120
BYTES_PER_PARTICLE = 2000


class ThinPartsWarning(UserWarning):
    """Some vertices of a mesh body lie in parts too thin for its lattice."""


@dataclass
class MeshBody(LatticeSprings, SurfaceContact):
    """A jelly body filling the closed mesh in ``file``, scaled, rotated (degrees about
    ``rotation_axis``, about the file's origin) and moved by ``position`` (m); ``spacing`` (m)
    between lattice particles of ``particle_mass`` (kg); the cube's springs (LatticeSprings)."""

    file: str = ""
    spacing: float = 0.5
    scale: float = 1.0
    rotation_degrees: float = 0.0
    rotation_axis: tuple = (0.0, 1.0, 0.0)
    position: tuple = (0.0, 0.0, 0.0)
    velocity: tuple = (0.0, 0.0, 0.0)
    particle_mass: float = 1.0
    pinned: tuple = ()

    def validate(self, key: str) -> None:
        validate_placement(self, key)
        require(is_finite(self.spacing) and self.spacing > 0, f"{key}.spacing", self.spacing,
                "must be > 0 m")
        require(np.shape(self.velocity) == (3,) and is_finite(self.velocity), f"{key}.velocity",
                self.velocity, "must be three finite numbers (m/s)")
        require(is_finite(self.particle_mass) and self.particle_mass > 0,
                f"{key}.particle_mass", self.particle_mass, "must be > 0 kg")
        self.validate_springs(key)
        self.validate_surface_contact(key)
        mesh = self.mesh(f"{key}.file")
        volume = check_closed(mesh, f"{key}.file", self.file)
        check_memory(mesh, volume, self.spacing, f"{key}.spacing")
        count = len(self.lattice(f"{key}.spacing")[0])
        for index in self.pinned:
            require(0 <= index < count, f"{key}.pinned", index,
                    f"particle numbers must lie in [0, {count - 1}]")

    def surface_spacing(self) -> float:
        return self.spacing

    def counts(self) -> tuple[int, int]:
        """Particles, and springs at most: each lattice point starts at most the cube's
        3 structural, 10 shear, 3 bend and 3 face springs (sizes.py)."""
        particles = len(self.lattice()[0])
        return particles, 19 * particles

    def mesh(self, key: str = "file"):
        return placed(read_mesh(self.file, key), self.scale, self.rotation_degrees,
                      self.rotation_axis, self.position)

    def lattice(self, key: str = "spacing"):
        """(positions (n, 3), index (lattice shape) of particle numbers or -1, embedding,
        number of thin-part vertices), built once per file version and settings."""
        self.mesh()   # a missing or unreadable file fails here, with its key
        path = Path(self.file).expanduser()
        return _cached_lattice(str(path.resolve()), path.stat().st_mtime_ns, float(self.scale),
                               float(self.rotation_degrees), tuple(map(float, self.rotation_axis)),
                               tuple(map(float, self.position)), float(self.spacing), key)

    def build(self) -> BuiltBody:
        positions, index, embedding, thin = self.lattice()
        if thin:
            warnings.warn(f"{self.file}: {thin} of {len(embedding.weights)} vertices lie in parts "
                          f"thinner than the lattice (spacing {self.spacing:g} m) and ride the "
                          "nearest full cell; a smaller spacing fills those parts",
                          ThinPartsWarning, stacklevel=2)
        springs, kinds = lattice_pattern(index, self)
        count = len(positions)
        vertices = self.mesh().vertices
        pinned = np.zeros(count, bool)
        pinned[list(self.pinned)] = True
        return BuiltBody(
            positions=positions.copy(),
            velocities=np.tile(np.asarray(self.velocity, float), (count, 1)),
            masses=np.full(count, float(self.particle_mass)),
            pinned=pinned, springs=springs, spring_kind=kinds,
            spring_parameters=spring_parameters(self),
            surface=self.mesh().triangles.astype(np.int32), embedding=embedding,
            terrain_offsets=surface_offsets(vertices, positions, embedding, self.spacing),
            collision_surface=lattice_boundary(index))


def lattice_counts(vertices: np.ndarray, spacing: float) -> np.ndarray:
    """Lattice points along each axis of the mesh's box (the last one within the tolerance)."""
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    return np.floor(extent / spacing + INSIDE_TOLERANCE).astype(np.int64) + 1


def available_memory() -> int:
    """Bytes this machine can still give (MemAvailable), or its physical memory."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_memory(mesh, volume: float, spacing: float, key: str) -> None:
    """Refuse a spacing whose lattice (estimated from the box and the volume, before building)
    would not fit in half the memory available."""
    box_points = float(np.prod(lattice_counts(mesh.vertices, spacing).astype(float)))
    particles = volume / spacing ** 3
    need = box_points * BYTES_PER_LATTICE_POINT + particles * BYTES_PER_PARTICLE
    allowed = available_memory() / 2
    if need > allowed:
        larger = spacing * (need / allowed) ** (1 / 3)
        raise SceneError(key, spacing,
                         f"gives about {particles:,.0f} particles ({box_points:,.0f} lattice "
                         f"points to test), about {need / 2**30:.1f} GiB, more than half the "
                         f"{2 * allowed / 2**30:.1f} GiB this machine has free; try "
                         f">= {larger:.3g}")


@functools.lru_cache(maxsize=8)
def _cached_lattice(path, mtime_ns, scale, rotation_degrees, rotation_axis, position, spacing,
                    key):
    mesh = placed(read_mesh(path, "file"), scale, rotation_degrees, rotation_axis, position)
    return build_lattice(mesh, spacing, key)


def build_lattice(mesh, spacing: float, key: str):
    """The particles inside ``mesh`` and its embedded surface (module doc)."""
    import igl

    low = mesh.vertices.min(axis=0)
    counts = lattice_counts(mesh.vertices, spacing)
    sites = np.indices(counts).reshape(3, -1).T
    points = low + sites * spacing
    distance = igl.signed_distance(points, mesh.vertices, mesh.triangles,
                                   sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0]
    inside = distance <= INSIDE_TOLERANCE * spacing
    suggestion = f"try <= {float(np.min(mesh.vertices.max(axis=0) - low)) / 4:.3g}"
    require(inside.any(), key, spacing, f"is too large for the mesh: no lattice point lies "
                                        f"inside it; {suggestion}")
    index = np.full(len(points), -1, np.int64)
    index[inside] = np.arange(np.count_nonzero(inside))
    index = index.reshape(counts)
    full = full_cells(index)
    require(len(full) > 0, key, spacing, "is too large for the mesh: no lattice cell lies "
                                         f"wholly inside it, to carry its surface; {suggestion}")
    embedding, thin = embed(mesh.vertices, low, spacing, index, full)
    return points[inside], index, embedding, thin


def surface_offsets(vertices, positions, embedding: Embedding, spacing: float) -> np.ndarray:
    """(n,) m: for each particle, the distance to the farthest vertex whose nearest cell corner
    it is (module doc); distances below round-off are zero."""
    corner = embedding.particles[np.arange(len(vertices)), np.argmax(embedding.weights, axis=1)]
    distance = np.linalg.norm(vertices - positions[corner], axis=1)
    offsets = np.zeros(len(positions))
    np.maximum.at(offsets, corner, distance)
    offsets[offsets < 1e-9 * spacing] = 0.0
    return offsets


def full_cells(index: np.ndarray) -> np.ndarray:
    """(C, 3) lattice coordinates of the cells whose eight corners are all particles."""
    kept = index >= 0
    full = np.ones(tuple(n - 1 for n in index.shape), bool)
    for a, b, c in np.ndindex(2, 2, 2):
        full &= kept[a:a + full.shape[0], b:b + full.shape[1], c:c + full.shape[2]]
    return np.argwhere(full)


def lattice_boundary(index: np.ndarray) -> np.ndarray:
    """(c, 3) int32 triangles of particle numbers: the faces of full cells whose neighbour across
    the face is not full (or lies beyond the lattice), each once, split along a diagonal into two
    triangles wound so that normals point out of the full cells (contact is two-sided, but the
    winding is consistent). A face between two full cells is inside the body and left out.

    A particle that is a corner of no full cell (a thin part: a point inside the mesh whose
    neighbours are not) is on no triangle: other bodies do not touch it, though it still pulls on
    its neighbours through its springs and touches terrains. The boundary faces of the full
    cells enclose every full cell, so this only loses features thinner than one spacing."""
    shape = tuple(n - 1 for n in index.shape)
    is_full = np.zeros(tuple(n + 2 for n in shape), bool)    # a margin of empty cells
    is_full[(slice(1, -1),) * 3][tuple(full_cells(index).T)] = True
    inner = is_full[1:-1, 1:-1, 1:-1]
    triangles = []
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3       # right-handed (axis, u, v)
        for side in (0, 1):
            step = [slice(1, -1)] * 3
            step[axis] = slice(2 * side, 2 * side + shape[axis])   # the neighbour across
            cells = np.argwhere(inner & ~is_full[tuple(step)])
            corners = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                offset = np.zeros(3, np.int64)
                offset[axis], offset[u], offset[v] = side, du, dv
                corners.append(index[tuple((cells + offset).T)])
            a, b, c, d = corners if side else corners[::-1]   # counter-clockwise seen outside
            triangles += [np.stack([a, b, c], 1), np.stack([a, c, d], 1)]
    return np.concatenate(triangles).astype(np.int32)


def embed(vertices, low, spacing: float, index, full) -> tuple[Embedding, int]:
    """Each vertex's full cell and its trilinear weights there (module doc), and how many
    vertices lie farther than one spacing from every full cell."""
    from scipy.spatial import cKDTree

    local = (vertices - low) / spacing
    cell = np.clip(np.floor(local).astype(np.int64), 0, np.array(index.shape) - 2)
    is_full = np.zeros(tuple(n - 1 for n in index.shape), bool)
    is_full[tuple(full.T)] = True
    elsewhere = ~is_full[tuple(cell.T)]
    thin = 0
    if elsewhere.any():
        distance, nearest = cKDTree(full + 0.5).query(local[elsewhere])
        cell[elsewhere] = full[nearest]
        # a vertex at the centre's distance d from a cell's centre is d - sqrt(3)/2 from it at most
        thin = int(np.count_nonzero(distance - np.sqrt(3) / 2 > 1.0))
    f = local - cell
    particles, weights = [], []
    for corner in np.ndindex(2, 2, 2):
        site = cell + corner
        particles.append(index[tuple(site.T)])
        weights.append(np.prod(np.where(corner, f, 1.0 - f), axis=1))
    return Embedding(np.stack(particles, axis=1), np.stack(weights, axis=1)), thin
