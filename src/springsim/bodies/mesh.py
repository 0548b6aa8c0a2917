"""A jelly body from a triangle mesh as artists have them (closed or not, in one shell or many,
with UV seams): a lattice of particles carrying the mesh, joined by the cube's springs, with the
file's own surface riding the lattice.

- The solid: the file's vertices are merged by position first (a file splits a vertex along its
  UV and normal seams), and the body fills where the generalized winding number of the surface
  says inside (lattice_fill.py), so holes, separate or overlapping shells and parts wound inside
  out fill as a person would expect; one warning line (MeshWarning) says what was unusual. Only a
  surface with no inside at all, a single open sheet, is refused (mesh_solid.py): that is a cloth.
- The lattice (lattice_fill.py): cubic cells of side ``spacing`` centred on the placed mesh's
  box; a cell is kept when the surface passes through it (a conservative voxelization) or its
  centre is inside; the particles are the kept cells' corners, joined by the cube's spring
  pattern where both ends are particles. A 4 m box at spacing 4/9 is exactly the default cube.
  ``spacing = "auto"`` picks the spacing whose lattice has about ``particles`` particles, so a
  model in millimetres or kilometres makes the same body: to three significant digits, or for a
  mesh with a flat side on its box a whole number of cells along the box's longest side (then a
  box's lattice, a cube's, has its faces on lattice planes).
- The surface (the idea of Newton's soft grid with a visual mesh and MuJoCo's trilinear
  flexcomp): each vertex of the FILE, in the file's order and seam duplicates included, is a
  fixed trilinear combination of the eight corners of the kept cell it lies in, computed once.
  Every vertex lies in a kept cell, so its weights are in [0, 1]: the vertex is a convex
  combination of its cell's corners and never leaves the lattice, however the body tumbles.
  Trilinear weights reproduce any affine map, so at t = 0 the surface is the file's to
  round-off. The exporters' point caches therefore list the file's own vertices in its order,
  and apply to the same file opened in Blender or Houdini.
- Separate parts: shells whose kept cells share no corner are separate pieces of particles with
  no spring between them; they move independently and collide with each other as two bodies
  would (contact numbers each connected piece of a body as a body of its own,
  collision/shapes/surfaces.py), while the file stays one body (one point cache).
- Contact: terrains push on the particles. A vertex being a convex combination of particles, no
  vertex goes below a plane that no particle goes below, so the body keeps no extra distance from
  terrains (its ``terrain_offsets`` are zero). The particles of cells the surface passes through
  reach up to a spacing beyond it, so the drawn surface may rest up to about a spacing above the
  floor, and dip into a curved terrain by no more than a cell's sag over its curvature. Other
  bodies (body-body contact, collision/shapes/surfaces.py) touch a mesh body through the boundary
  faces of its lattice, kept ``thickness`` apart as any surface: the faces of full cells whose
  neighbour across the face is not full, two triangles each (``collision_surface``,
  lattice_boundary). That boundary encloses the drawn surface, up to about a spacing outside it
  (on it for a box).
"""
import functools
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..collision.shapes.settings import SurfaceContact
from ..errors import SceneError, is_finite, require
from ..meshfiles import TriangleMesh, placed, read_mesh_file, validate_placement, weld
from ..surfaces import Embedding
from . import BuiltBody
from .pins import Pin, moving_pins, pinned_mask
from .cube import LatticeSprings, lattice_pattern, spring_parameters
from .lattice_fill import box_points, fill, full_cells, locate
from .mesh_solid import has_inside, unusual

# memory per lattice point of the bounding box while filling it (centres, winding numbers, flags,
# numbers), and per particle of the model (its springs, state and the integrators' work arrays)
BYTES_PER_LATTICE_POINT = 120
BYTES_PER_PARTICLE = 2000
PARTICLES = (8, 10_000_000)      # the particle budget of spacing = "auto": allowed range
AUTO_TOLERANCE = 0.1             # "about": the auto spacing's count within 10 % where it can
AUTO_TRIES = 8


class MeshWarning(UserWarning):
    """A mesh body's surface is unusual (holes, shells, parts wound inside out); it is filled."""


class Lattice(NamedTuple):
    positions: np.ndarray   # (n, 3) m, particles in lattice order
    index: np.ndarray       # (lattice points) int64 particle numbers, -1 where none
    embedding: Embedding    # one row per vertex of the file, in the file's order
    spacing: float          # m: the spacing used (chosen, for "auto")
    unusual: str            # what is unusual about the surface, '' when nothing


@dataclass
class MeshBody(LatticeSprings, SurfaceContact):
    """A jelly body carrying the mesh in ``file``, scaled, rotated (degrees about
    ``rotation_axis``, about the file's origin) and moved by ``position`` (m); ``spacing`` (m)
    between lattice particles of ``particle_mass`` (kg), or "auto" for about ``particles`` of
    them; the cube's springs (LatticeSprings)."""

    file: str = ""
    spacing: float | str = "auto"
    particles: int = 2000
    scale: float = 1.0
    rotation_degrees: float = 0.0
    rotation_axis: tuple = (0.0, 1.0, 0.0)
    position: tuple = (0.0, 0.0, 0.0)
    velocity: tuple = (0.0, 0.0, 0.0)
    particle_mass: float = 1.0
    pinned: tuple = ()
    pins: list[Pin] = field(default_factory=list)   # held, moving or soft pins (bodies/pins.py)

    def validate(self, key: str) -> None:
        validate_placement(self, key)
        require(self.spacing == "auto" or (not isinstance(self.spacing, (str, bool))
                                           and is_finite(self.spacing) and self.spacing > 0),
                f"{key}.spacing", self.spacing, 'must be > 0 m, or "auto" (about `particles` '
                                                "particles)")
        low, high = PARTICLES
        require(isinstance(self.particles, (int, np.integer)) and not isinstance(self.particles, bool)
                and low <= self.particles <= high, f"{key}.particles", self.particles,
                f"must be a whole number in [{low}, {high:,}]")
        require(np.shape(self.velocity) == (3,) and is_finite(self.velocity), f"{key}.velocity",
                self.velocity, "must be three finite numbers (m/s)")
        require(is_finite(self.particle_mass) and self.particle_mass > 0,
                f"{key}.particle_mass", self.particle_mass, "must be > 0 kg")
        self.validate_springs(key)
        self.validate_surface_contact(key)
        solid = self.solid(f"{key}.file")
        require(has_inside(solid.vertices, solid.triangles), f"{key}.file", self.file,
                'has no inside: it is a single open sheet, which is a cloth (type = "cloth")')
        check_memory(solid, self.spacing, self.particles, key)
        count = len(self.lattice(key).positions)
        for index in self.pinned:
            require(0 <= index < count, f"{key}.pinned", index,
                    f"particle numbers must lie in [0, {count - 1}]")
        for p, pin in enumerate(self.pins):
            pin.validate(f"{key}.pins.{p}")
            require(not pin.group, f"{key}.pins.{p}.group", pin.group,
                    "a mesh body's particles are its lattice's, not the file's vertices: "
                    "choose them by particles = [...] or a region")
        if self.pins:
            pinned_mask(self.pins, self.lattice(key).positions, {}, f"{key}.pins")
            moving_pins(self.pins, self.lattice(key).positions, {}, key=f"{key}.pins")

    def surface_spacing(self) -> float:
        return self.lattice().spacing

    def counts(self) -> tuple[int, int]:
        """Particles, and springs at most: each lattice point starts at most the cube's
        3 structural, 10 shear, 3 bend and 3 face springs (sizes.py)."""
        particles = len(self.lattice().positions)
        return particles, 19 * particles

    def mesh(self, key: str = "file") -> TriangleMesh:
        """The file's own vertices (in its order, seam duplicates included), placed, and its
        faces as triangles (polygons split into fans)."""
        file = read_mesh_file(self.file, key)
        return placed(TriangleMesh(file.vertices, file.triangles()), self.scale,
                      self.rotation_degrees, self.rotation_axis, self.position)

    def solid(self, key: str = "file") -> TriangleMesh:
        """The placed mesh with its vertices merged by position: the surface the body fills."""
        mesh = self.mesh(key)
        size = float(np.max(np.ptp(mesh.vertices, axis=0)))
        require(size > 0, key, self.file, "has no extent: all its vertices coincide")
        welded = weld(mesh.vertices)
        return TriangleMesh(welded.vertices, welded.of_file_vertex[mesh.triangles])

    def lattice(self, key: str = "bodies.0") -> Lattice:
        """The particles and the embedded surface (module doc), built once per file version and
        settings (``validate`` has checked them); ``key`` names the body in errors."""
        self.mesh(f"{key}.file")   # a missing or unreadable file fails here, with its key
        path = Path(self.file).expanduser()
        spacing = self.spacing if self.spacing == "auto" else float(self.spacing)
        return _cached_lattice(str(path.resolve()), path.stat().st_mtime_ns, float(self.scale),
                               float(self.rotation_degrees), tuple(map(float, self.rotation_axis)),
                               tuple(map(float, self.position)), spacing, int(self.particles))

    def build(self) -> BuiltBody:
        lattice = self.lattice()
        if lattice.unusual:
            warnings.warn(f"{self.file}: {lattice.unusual}; filled where the generalized winding "
                          "number says inside", MeshWarning, stacklevel=2)
        springs, kinds = lattice_pattern(lattice.index, self)
        count = len(lattice.positions)
        pinned = np.zeros(count, bool)
        pinned[list(self.pinned)] = True
        if self.pins:
            pinned |= pinned_mask(self.pins, lattice.positions, {}, "pins")
        return BuiltBody(
            positions=lattice.positions.copy(),
            velocities=np.tile(np.asarray(self.velocity, float), (count, 1)),
            masses=np.full(count, float(self.particle_mass)),
            pinned=pinned, springs=springs, spring_kind=kinds,
            spring_parameters=spring_parameters(self),
            surface=self.mesh().triangles.astype(np.int32), embedding=lattice.embedding,
            terrain_offsets=np.zeros(count),
            collision_surface=lattice_boundary(lattice.index),
            moving_pins=moving_pins(self.pins, lattice.positions, {}))

    def summary(self) -> str:
        """The lattice in words, for the run's summary."""
        lattice = self.lattice()
        how = (f"auto, for about {self.particles:,} particles" if self.spacing == "auto"
               else "as set")
        return f"spacing {lattice.spacing:.4g} m ({how}): {len(lattice.positions):,} particles"


def available_memory() -> int:
    """Bytes this machine can still give (MemAvailable), or its physical memory."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def check_memory(solid: TriangleMesh, spacing, particles: int, key: str) -> None:
    """Refuse a lattice that would not fit in half the memory available, estimated before
    building it: the box's lattice points while filling, and the particles (the enclosed volume
    over a cell, plus a layer of cells over the surface; at most the box's points)."""
    allowed = available_memory() / 2
    if spacing == "auto":   # the box is filled at about `particles` points a try
        need = particles * (BYTES_PER_LATTICE_POINT + BYTES_PER_PARTICLE)
        require(need <= allowed, f"{key}.particles", particles,
                f"needs about {need / 2**30:.1f} GiB, more than half the "
                f"{2 * allowed / 2**30:.1f} GiB this machine has free; try "
                f"<= {int(allowed / (BYTES_PER_LATTICE_POINT + BYTES_PER_PARTICLE)):,}")
        return
    points = box_points(solid.vertices, spacing)
    a, b, c = (solid.vertices[solid.triangles[:, k]] for k in range(3))
    volume = abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum())) / 6
    area = 0.5 * float(np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())
    count = min(points, volume / spacing ** 3 + 2 * area / spacing ** 2)
    need = points * BYTES_PER_LATTICE_POINT + count * BYTES_PER_PARTICLE
    if need > allowed:
        larger = spacing * (need / allowed) ** (1 / 3)
        raise SceneError(f"{key}.spacing", spacing,
                         f"gives about {count:,.0f} particles ({points:,.0f} lattice points to "
                         f"fill), about {need / 2**30:.1f} GiB, more than half the "
                         f"{2 * allowed / 2**30:.1f} GiB this machine has free; try "
                         f'>= {larger:.3g}, or "auto"')


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


@functools.lru_cache(maxsize=8)
def _cached_lattice(path, mtime_ns, scale, rotation_degrees, rotation_axis, position, spacing,
                    particles):
    body = MeshBody(file=path, scale=scale, rotation_degrees=rotation_degrees,
                    rotation_axis=rotation_axis, position=position)
    return build_lattice(body.mesh(), body.solid(), spacing, particles)


def build_lattice(mesh: TriangleMesh, solid: TriangleMesh, spacing, particles: int) -> Lattice:
    """The particles carrying ``solid`` (the welded surface) and the embedding of ``mesh`` (the
    file's vertices) in them (module doc)."""
    if spacing == "auto":
        spacing, filled = auto_spacing(solid, particles)
    else:
        filled = fill(solid.vertices, solid.triangles, float(spacing))
    embedding = embed(mesh.vertices, filled)
    return Lattice(filled.positions, filled.index, embedding, float(spacing),
                   unusual(solid.vertices, solid.triangles).description())


def auto_spacing(solid: TriangleMesh, particles: int):
    """(spacing, filled lattice): the spacing whose lattice has closest to ``particles``
    particles among a few tries (AUTO_TRIES, stopping within AUTO_TOLERANCE), to three
    significant digits; for a mesh with a flat side on its box, a whole number of cells along
    the box's longest side. Why whole: the lattice is centred on the box, so a side that is no
    whole number of cells sticks out by part of a cell at both ends, and the body, which touches
    terrains with its particles, then rests that far above the floor (a 1 m cube at 0.0901 m
    stood 4 cm above it); a cube's every side fits. A curved side fits no lattice, and whole
    cells would only make the count jump (from one to the next by more than AUTO_TOLERANCE).
    The count goes as the volume over s^3 plus the surface over s^2: each try follows the slope
    of log count over log spacing measured between the last two."""
    low, high = solid.vertices.min(axis=0), solid.vertices.max(axis=0)
    longest = float((high - low).max())
    extent = np.maximum(high - low, 1e-3 * longest)          # a flat mesh still has a box
    first = float(np.prod(extent) / particles) ** (1 / 3)
    if has_flat_side(solid, low, high):
        return _closest_lattice(solid, particles, first,
                                lambda s: longest / max(1, round(longest / s)))
    return _closest_lattice(solid, particles, first, lambda s: float(f"{s:.3g}"))


def has_flat_side(solid: TriangleMesh, low: np.ndarray, high: np.ndarray) -> bool:
    """Whether a triangle of ``solid`` lies in a face of its box ``low``-``high``."""
    tolerance = 1e-9 * float((high - low).max())
    for bound in (low, high):
        on = np.abs(solid.vertices - bound) <= tolerance        # (V, 3) per axis
        if on[solid.triangles].all(axis=1).any():
            return True
    return False


def _closest_lattice(solid: TriangleMesh, particles: int, spacing: float, rounded):
    """auto_spacing's search from ``spacing``, each try's spacing ``rounded``."""
    tried = {}
    slope = -2.5
    for _ in range(AUTO_TRIES):
        spacing = rounded(spacing)
        if spacing in tried:
            break
        filled = fill(solid.vertices, solid.triangles, spacing)
        tried[spacing] = filled
        count = len(filled.positions)
        if abs(count / particles - 1) <= AUTO_TOLERANCE:
            break
        if len(tried) >= 2:
            (s0, f0), (s1, f1) = list(tried.items())[-2:]
            if s0 != s1 and len(f0.positions) != len(f1.positions):
                measured = (math.log(len(f1.positions) / len(f0.positions))
                            / math.log(s1 / s0))
                slope = min(max(measured, -3.5), -1.5)
        spacing *= (particles / count) ** (1 / slope)
    best = min(tried, key=lambda s: (abs(math.log(len(tried[s].positions) / particles)), s))
    return best, tried[best]


def embed(vertices: np.ndarray, filled) -> Embedding:
    """Each vertex's kept cell and its trilinear weights there (module doc)."""
    grid = filled.grid
    cell, _ = locate(vertices, filled.kept, grid)   # found for every vertex (fill)
    f = (vertices - grid.origin) / grid.spacing - cell
    particles, weights = [], []
    for corner in np.ndindex(2, 2, 2):
        site = cell + corner
        particles.append(filled.index[tuple(site.T)])
        weights.append(np.prod(np.where(corner, f, 1.0 - f), axis=1))
    return Embedding(np.stack(particles, axis=1), np.stack(weights, axis=1))
