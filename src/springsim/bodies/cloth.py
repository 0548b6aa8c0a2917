"""Cloth: an N x N grid of particles, or any triangle or quad mesh (``file``), joined by
structural, shear and bend springs.

Defaults are the course framework's scene 2 (see the reference): 25 particles per edge, a 4 m x 4 m
sheet flat at y = 0 (x and z in [-2, 2]), 1 kg particles, ks = 25000 N/m and kd = 750 N s/m for
every kind, viscous drag 3.4e-4 N s/m, and the four corners pinned.

Particle (i, j) is number ``i N + j``; it lies in the cloth's local x-z plane at
``x = (j / (N - 1) - 1/2) width`` and ``z = (i / (N - 1) - 1/2) height``, then the sheet is rotated
by ``rotation_degrees`` about ``rotation_axis`` and moved to ``position`` (its centre). Springs, as
in the reference: structural +1, +N; shear +N+1, +N-1; bend +2, +2N. For N = 25 that is 1200, 1152
and 1150 springs. Cloth particles are points (contact radius 0).

With ``file``, the particles and springs come from the mesh (bodies/sheet_mesh.py), scaled by
``scale``, rotated about the file's origin and moved by ``position``; ``particles_per_edge``,
``width`` and ``height`` are then unused. Named pinnings act in the file's frame: ``"corners"``
pins the vertex nearest each corner of the mesh's bounding box in its x-z plane, ``"edge+z"``
(``"edge"``) the vertices on the box's +z face, and so on. A vertex in no face holds still.

``material`` (bodies/cloth_material.py) replaces ``particle_mass`` and the per-kind ``ks``/``kd``
by a density and stiffnesses per unit strain, for grid and mesh cloth alike. A cloth from a
``file`` with neither ``material`` nor ``particle_mass`` weighs the default material's 0.3 kg/m²
(a heavy cotton's), shared by vertex area, and has its stiffnesses too unless it sets per-kind
springs: the course's 1 kg a particle is the grid's, whose spacing it was chosen for, and would
make a 900-vertex napkin weigh 900 kg. ``pins``
(bodies/pins.py) add pinned particles by number, box or mesh group to those ``pinned`` names.
"""
import functools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import SceneError, is_finite, require, require_angle
from ..meshfiles import fan_triangles, first_file_vertex, placed, read_mesh_file
from ..sizes import BYTES_PER_PARTICLE, gigabytes, machine_memory
from ..springs import SpringKind, SpringParameters, lattice_springs
from ..surfaces import Embedding
from . import BuiltBody
from .cloth_material import ClothMaterial, lumped_masses, material_constants
from .pins import Pin, moving_pins, particle_cache, pinned_mask
from .sheet_mesh import SheetMesh, sheet_mesh
from ..collision.shapes.settings import SurfaceContact

STRUCTURAL_OFFSETS = ((0, 1), (1, 0))
SHEAR_OFFSETS = ((1, 1), (1, -1))
BEND_OFFSETS = ((0, 2), (2, 0))

# Named pinnings; "edge" is the +z edge (the last row, i = N - 1), in the cloth's local frame.
EDGES = {"edge+z": (-1, slice(None)), "edge-z": (0, slice(None)),
         "edge+x": (slice(None), -1), "edge-x": (slice(None), 0)}
PINNINGS = ("corners", "none", "edge", *EDGES)
REFERENCE_DRAG = 3.4e-4  # N s/m per particle: a = g - v c / m, as in the reference
GRID_PARTICLE_MASS = 1.0  # kg: the reference's, for the grid when particle_mass is unset


def _default_springs():
    return SpringParameters(ks=25000.0, kd=750.0)


@dataclass
class Cloth(SurfaceContact):
    """A cloth sheet. Lengths in m, masses in kg, angles in degrees, drag in N s/m."""

    particles_per_edge: int = 25
    width: float = 4.0                     # along the local x axis
    height: float = 4.0                    # along the local z axis
    particle_mass: float | None = None     # kg; unset: GRID_PARTICLE_MASS, or with a file the
                                           # default material (module doc)
    position: tuple = (0.0, 0.0, 0.0)      # centre of the sheet
    velocity: tuple = (0.0, 0.0, 0.0)
    rotation_degrees: float = 0.0
    rotation_axis: tuple = (1.0, 0.0, 0.0)
    structural: SpringParameters = field(default_factory=_default_springs)
    shear: SpringParameters = field(default_factory=_default_springs)
    bend: SpringParameters = field(default_factory=_default_springs)
    pinned: str | list = "corners"         # a name in PINNINGS or a list of particle numbers
    drag: float = REFERENCE_DRAG           # added to the scene's drag on every particle
    thickness: float | None = None         # m, kept between this cloth and other surfaces;
                                           # unset: default_thickness()
    self_collision: bool = True            # the cloth does not pass through itself
    file: str = ""                         # a triangle or quad mesh; unset: the N x N grid
    scale: float = 1.0                     # on the file's coordinates
    material: ClothMaterial | None = None  # unset: particle_mass and per-kind ks, kd
    pins: list[Pin] = field(default_factory=list)   # more pinned particles (bodies/pins.py)

    def __post_init__(self):
        # the grid's mass is the course's from the start, so that it reads, writes out and
        # differentiates as a number; a file cloth's stays unset (its material's, module doc)
        if self.particle_mass is None and not self.file:
            self.particle_mass = GRID_PARTICLE_MASS

    def validate(self, key: str) -> None:
        self._validate_shape(key)
        if self.particle_mass is not None:
            require(_positive(self.particle_mass), f"{key}.particle_mass", self.particle_mass,
                    "must be > 0 kg")
        require(is_finite(self.drag) and self.drag >= 0, f"{key}.drag", self.drag,
                "must be >= 0 N s/m")
        for name in ("position", "velocity", "rotation_axis"):
            value = getattr(self, name)
            require(np.shape(value) == (3,) and is_finite(value), f"{key}.{name}", value,
                    "must be three finite numbers")
        require(np.linalg.norm(self.rotation_axis) > 0, f"{key}.rotation_axis",
                self.rotation_axis, "must be a non-zero vector")
        require_angle(self.rotation_degrees, f"{key}.rotation_degrees")
        for kind in ("structural", "shear", "bend"):
            getattr(self, kind).validate(f"{key}.{kind}")
        if self.material is not None:
            self.material.validate(f"{key}.material")
        self._validate_pinned(key)
        for p, pin in enumerate(self.pins):
            pin.validate(f"{key}.pins.{p}")
        if self.pins:
            pinned_mask(self.pins, self.particle_positions(), self._groups(), f"{key}.pins")
            moving_pins(self.pins, self.particle_positions(), self._groups(), self._cache_points,
                        f"{key}.pins")
        self.validate_surface_contact(key)

    def _validate_shape(self, key: str) -> None:
        if self.file:
            require(_positive(self.scale), f"{key}.scale", self.scale,
                    "must be > 0 (a factor on the file's coordinates)")
            _check_memory(self._file_vertex_count(f"{key}.file"), f"{key}.file", self.file)
            return
        n = self.particles_per_edge
        require(isinstance(n, int) and n >= 2, f"{key}.particles_per_edge", n,
                "needs an integer >= 2 (structural and shear springs join neighbours)")
        require(n >= 3 or not self.bend.builds, f"{key}.particles_per_edge", n,
                "needs >= 3 for bend springs, which skip one particle (or set bend ks and kd to 0)")
        for name in ("width", "height"):
            value = getattr(self, name)
            require(_positive(value), f"{key}.{name}", value, "must be > 0 m")

    def _validate_pinned(self, key: str) -> None:
        if isinstance(self.pinned, str):
            require(self.pinned in PINNINGS, f"{key}.pinned", self.pinned,
                    "must be one of " + ", ".join(PINNINGS) + " or a list of particle numbers")
            return
        count = self.counts()[0]
        require(isinstance(self.pinned, (list, tuple)), f"{key}.pinned", self.pinned,
                "must be one of " + ", ".join(PINNINGS) + " or a list of particle numbers")
        for index in self.pinned:
            whole = isinstance(index, (int, np.integer)) and not isinstance(index, bool)
            require(whole and 0 <= index < count, f"{key}.pinned", index,
                    f"particle numbers must be whole numbers in [0, {count - 1}]")

    def surface_spacing(self) -> float:
        """The grid's spacing; for a mesh, its shorter edges' length (the 5th percentile)."""
        if not self.file:
            return min(self.width, self.height) / (self.particles_per_edge - 1)
        positions = self.rest_positions()
        edges = self.sheet().springs[SpringKind.STRUCTURAL]
        lengths = np.linalg.norm(positions[edges[:, 0]] - positions[edges[:, 1]], axis=1)
        return float(np.percentile(lengths, 5)) if len(lengths) else 1.0

    def default_thickness(self) -> float:
        """2 cm, or a quarter of the particle spacing where that is less. Why: a self-colliding
        cloth's contacts reach its thickness and its pair search twice that beyond (SKIN in
        collision/pipeline.py); kept under the spacing, a flat cloth lists no pair of its own
        (a 100 x 100, 4 m cloth at 2 cm listed 200,000 and searched 7 times longer)."""
        return min(0.02, 0.25 * self.surface_spacing())

    def counts(self) -> tuple[int, int]:
        """Particles and springs (at most: kinds with ks = kd = 0 build none), from N alone or
        from the mesh file."""
        if self.file:
            sheet = self.sheet()
            return len(sheet.positions), sum(len(pairs) for pairs in sheet.springs.values())
        n = self.particles_per_edge
        return n * n, 2 * n * (n - 1) + 2 * (n - 1) ** 2 + 2 * n * max(n - 2, 0)

    def build(self) -> BuiltBody:
        positions = self.particle_positions()
        faces = self.faces()
        springs, kinds = self._springs(faces, len(positions))
        count = len(positions)
        masses = self._particle_masses(faces, count)
        constants = None
        material = self.effective_material()
        if material is not None:
            masses = lumped_masses(self.rest_positions(), faces, material.density)
            constants = material_constants(material, self.rest_positions(), faces, springs,
                                           kinds)
        pinned = self.pinned_mask()
        moving = []
        if self.pins:
            pinned |= pinned_mask(self.pins, positions, self._groups(), "pins")
            moving = moving_pins(self.pins, positions, self._groups(), self._cache_points)
        in_no_face = np.bincount(faces[faces >= 0], minlength=count) == 0
        pinned |= in_no_face             # it has no spring to move with
        masses[in_no_face] = self._stray_mass(masses[~in_no_face])
        triangles = fan_triangles(faces).astype(np.int32)
        surface, embedding, collision_surface = triangles, None, None
        if self.file and self._has_seams():
            surface, embedding, collision_surface = self._file_surface(), self._seam_embedding(), \
                triangles
        return BuiltBody(
            positions=positions,
            velocities=np.tile(np.asarray(self.velocity, float), (count, 1)),
            masses=masses, pinned=pinned, springs=springs, spring_kind=kinds,
            spring_parameters={SpringKind.STRUCTURAL: self.structural,
                               SpringKind.SHEAR: self.shear, SpringKind.BEND: self.bend},
            surface=surface, radii=np.zeros(count), embedding=embedding,
            collision_surface=collision_surface, spring_constants=constants, sheet=True,
            moving_pins=moving)

    def _springs(self, faces, count):
        """(S, 2) springs and (S,) kinds, kind by kind; kinds with ks = kd = 0 build none
        (with a material: a zero stiffness and damping)."""
        if self.file:
            by_kind = self.sheet().springs
        else:
            n = self.particles_per_edge
            index = np.arange(n * n, dtype=np.int32).reshape(n, n)
            by_kind = {kind: np.concatenate([lattice_springs(index, offset)
                                             for offset in offsets])
                       for kind, offsets in ((SpringKind.STRUCTURAL, STRUCTURAL_OFFSETS),
                                             (SpringKind.SHEAR, SHEAR_OFFSETS),
                                             (SpringKind.BEND, BEND_OFFSETS))}
        springs, kinds = [], []
        material = self.effective_material()
        for kind, pairs in by_kind.items():
            if material is not None:
                builds = any(material.per_kind(kind))
            else:
                builds = getattr(self, SpringKind(kind).label).builds
            if builds and len(pairs):
                springs.append(pairs.astype(np.int32))
                kinds.append(np.full(len(pairs), kind, np.int8))
        if not springs:
            return np.empty((0, 2), np.int32), np.empty(0, np.int8)
        return np.concatenate(springs), np.concatenate(kinds)

    def effective_material(self) -> ClothMaterial | None:
        """``material``; for a file cloth that sets none of it, ``particle_mass`` and the
        per-kind springs, the default material (module doc); None: per-kind springs."""
        if self.material is None and self.file and self.particle_mass is None \
                and not self._sets_springs():
            return ClothMaterial()
        return self.material

    def _sets_springs(self) -> bool:
        return any(getattr(self, kind) != _default_springs()
                   for kind in ("structural", "shear", "bend"))

    def _particle_masses(self, faces: np.ndarray, count: int) -> np.ndarray:
        """Each particle's mass without a material: ``particle_mass``, or for a file cloth that
        leaves it unset the default material's areal density shared by vertex area (its springs
        the per-kind ones it sets)."""
        if self.file and self.particle_mass is None:
            return lumped_masses(self.rest_positions(), faces, ClothMaterial().density)
        return np.full(count, self.mass_per_particle())

    def _stray_mass(self, in_faces: np.ndarray) -> float:
        """The mass of a vertex in no face (held still: no spring moves it): ``particle_mass``
        where given, else what the vertices in faces weigh on average (not the grid's 1 kg in a
        cloth of grams)."""
        if self.particle_mass is not None or len(in_faces) == 0:
            return self.mass_per_particle()
        return float(in_faces.mean())

    def mass_per_particle(self) -> float:
        """kg of each particle without a material (and of a vertex in no face)."""
        return GRID_PARTICLE_MASS if self.particle_mass is None else float(self.particle_mass)

    def faces(self) -> np.ndarray:
        """(F, K) the sheet's faces as rows of particle numbers (the grid's cells as quads)."""
        if self.file:
            return self.sheet().faces
        n = self.particles_per_edge
        index = np.arange(n * n).reshape(n, n)
        return np.stack([index[:-1, :-1].ravel(), index[1:, :-1].ravel(),
                         index[1:, 1:].ravel(), index[:-1, 1:].ravel()], axis=1)

    def particle_positions(self) -> np.ndarray:
        """(P, 3) positions in m: for the grid, particle i N + j at row i (local z) and column j
        (local x); for a mesh, its welded vertices, placed."""
        if self.file:
            sheet = self.sheet()
            return placed(_as_triangle_mesh(sheet.positions), self.scale, self.rotation_degrees,
                          self.rotation_axis, self.position).vertices
        n = self.particles_per_edge
        fraction = np.linspace(-0.5, 0.5, n)
        row, column = np.meshgrid(fraction, fraction, indexing="ij")
        local = np.stack([column.ravel() * self.width, np.zeros(n * n),
                          row.ravel() * self.height], axis=1)
        if self.rotation_degrees:
            axis = np.asarray(self.rotation_axis, float)
            rotvec = np.radians(self.rotation_degrees) * axis / np.linalg.norm(axis)
            local = Rotation.from_rotvec(rotvec).apply(local)
        return local + np.asarray(self.position, float)

    def rest_positions(self) -> np.ndarray:
        """The particles scaled but neither turned nor moved: the frame named pinnings and the
        material's areas use (areas and lengths do not change when placed)."""
        if self.file:
            return float(self.scale) * self.sheet().positions
        return self.particle_positions()

    def pinned_mask(self) -> np.ndarray:
        if self.file:
            return self._named_mesh_pins()
        n = self.particles_per_edge
        grid = np.zeros((n, n), bool)
        if isinstance(self.pinned, str):
            if self.pinned == "corners":
                grid[0, 0] = grid[0, -1] = grid[-1, 0] = grid[-1, -1] = True
            elif self.pinned != "none":
                grid[EDGES["edge+z" if self.pinned == "edge" else self.pinned]] = True
            return grid.ravel()
        mask = grid.ravel()
        mask[list(self.pinned)] = True
        return mask

    # --- a mesh file's sheet -----------------------------------------------------------------

    def sheet(self) -> SheetMesh:
        """The welded mesh of ``file`` (bodies/sheet_mesh.py), built once per file version."""
        read_mesh_file(self.file, "file")     # a missing or unreadable file fails here
        path = Path(self.file).expanduser().resolve()
        status = path.stat()
        return _cached_sheet(str(path), status.st_mtime_ns, status.st_size)

    def _cache_points(self, points: np.ndarray, key: str, file: str) -> np.ndarray:
        """A pin animation's samples (F, V, 3) as the particles (F, P, 3): a grid's particles
        as they are; a file's vertices placed as the cloth is, each particle taking its first
        file vertex."""
        if not self.file:
            return particle_cache(self.particles_per_edge ** 2)(points, key, file)
        count = self._file_vertex_count(key)
        require(points.shape[1] == count, f"{key}.file", file,
                f"moves {points.shape[1]} points, but the cloth's file has {count} vertices")
        first = first_file_vertex(self.sheet().of_file_vertex)
        return np.stack([placed(_as_triangle_mesh(frame[first]), self.scale,
                                self.rotation_degrees, self.rotation_axis,
                                self.position).vertices for frame in points])

    def _file_vertex_count(self, key: str) -> int:
        return len(read_mesh_file(self.file, key).vertices)

    def _has_seams(self) -> bool:
        mapping = self.sheet().of_file_vertex
        return not np.array_equal(mapping, np.arange(len(mapping)))

    def _file_surface(self) -> np.ndarray:
        """The file's own faces as triangles of its own vertices: what exporters write, so that
        a point cache applies to the file as the artist has it (seam duplicates included)."""
        return self.sheet().file_triangles.astype(np.int32)

    def _seam_embedding(self) -> Embedding:
        """Each file vertex follows its welded particle (a one-hot embedding)."""
        particle = self.sheet().of_file_vertex
        particles = np.repeat(particle[:, None], 8, axis=1)
        weights = np.zeros((len(particle), 8))
        weights[:, 0] = 1.0
        return Embedding(particles, weights)

    def _named_mesh_pins(self) -> np.ndarray:
        """``pinned`` on a mesh, in the file's frame (module doc)."""
        local = self.rest_positions()
        mask = np.zeros(len(local), bool)
        if isinstance(self.pinned, (list, tuple)):
            mask[list(self.pinned)] = True
            return mask
        low, high = local.min(axis=0), local.max(axis=0)
        tolerance = 1e-6 * float(np.max(high - low))
        if self.pinned == "corners":
            for x in (low[0], high[0]):
                for z in (low[2], high[2]):
                    distance = np.hypot(local[:, 0] - x, local[:, 2] - z)
                    mask[np.argmin(distance)] = True
        elif self.pinned != "none":
            name = "edge+z" if self.pinned == "edge" else self.pinned
            axis = 0 if name[-1] == "x" else 2
            bound = high[axis] if name[-2] == "+" else low[axis]
            mask |= np.abs(local[:, axis] - bound) <= tolerance
        return mask

    def _groups(self) -> dict:
        """The mesh file's named groups of particles, for ``pins``."""
        return self.sheet().groups if self.file else {}


@functools.lru_cache(maxsize=8)
def _cached_sheet(path: str, mtime_ns: int, size: int) -> SheetMesh:
    return sheet_mesh(read_mesh_file(path, "file"))


def _as_triangle_mesh(vertices):
    from ..meshfiles import TriangleMesh
    return TriangleMesh(vertices, np.empty((0, 3), np.int64))


def _check_memory(vertices: int, key: str, file: str) -> None:
    """Refuse a mesh whose cloth the machine could not hold, from its vertex count alone."""
    memory = machine_memory()
    needed = BYTES_PER_PARTICLE * 8 * vertices      # particles, and about 7 springs each
    if memory is not None and needed > 0.75 * memory:
        raise SceneError(key, file, f"has {vertices:,} vertices, about {gigabytes(needed)} to "
                                    f"simulate as a cloth; this machine has "
                                    f"{gigabytes(memory)} of memory")


def _positive(value) -> bool:
    return is_finite(value) and float(value) > 0
