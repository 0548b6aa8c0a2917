"""Cloth: an N x N grid of particles joined by structural, shear and bend springs.

Defaults are the course framework's scene 2 (see the reference): 25 particles per edge, a 4 m x 4 m
sheet flat at y = 0 (x and z in [-2, 2]), 1 kg particles, ks = 25000 N/m and kd = 750 N s/m for
every kind, viscous drag 3.4e-4 N s/m, and the four corners pinned.

Particle (i, j) is number ``i N + j``; it lies in the cloth's local x-z plane at
``x = (j / (N - 1) - 1/2) width`` and ``z = (i / (N - 1) - 1/2) height``, then the sheet is rotated
by ``rotation_degrees`` about ``rotation_axis`` and moved to ``position`` (its centre). Springs, as
in the reference: structural +1, +N; shear +N+1, +N-1; bend +2, +2N. For N = 25 that is 1200, 1152
and 1150 springs. Cloth particles are points (contact radius 0).
"""
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import is_finite, require, require_angle
from ..springs import SpringKind, SpringParameters, lattice_springs
from . import BuiltBody
from .cube import grid_triangles
from ..collision.shapes.settings import SurfaceContact

STRUCTURAL_OFFSETS = ((0, 1), (1, 0))
SHEAR_OFFSETS = ((1, 1), (1, -1))
BEND_OFFSETS = ((0, 2), (2, 0))

# Named pinnings; "edge" is the +z edge (the last row, i = N - 1), in the cloth's local frame.
EDGES = {"edge+z": (-1, slice(None)), "edge-z": (0, slice(None)),
         "edge+x": (slice(None), -1), "edge-x": (slice(None), 0)}
PINNINGS = ("corners", "none", "edge", *EDGES)
REFERENCE_DRAG = 3.4e-4  # N s/m per particle: a = g - v c / m, as in the reference


def _default_springs():
    return SpringParameters(ks=25000.0, kd=750.0)


@dataclass
class Cloth(SurfaceContact):
    """A cloth sheet. Lengths in m, masses in kg, angles in degrees, drag in N s/m."""

    particles_per_edge: int = 25
    width: float = 4.0                     # along the local x axis
    height: float = 4.0                    # along the local z axis
    particle_mass: float = 1.0
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

    def validate(self, key: str) -> None:
        n = self.particles_per_edge
        require(isinstance(n, int) and n >= 2, f"{key}.particles_per_edge", n,
                "needs an integer >= 2 (structural and shear springs join neighbours)")
        require(n >= 3 or not self.bend.builds, f"{key}.particles_per_edge", n,
                "needs >= 3 for bend springs, which skip one particle (or set bend ks and kd to 0)")
        for name in ("width", "height", "particle_mass"):
            value = getattr(self, name)
            require(_positive(value), f"{key}.{name}", value,
                    "must be > 0 " + ("kg" if name == "particle_mass" else "m"))
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
        self._validate_pinned(key)
        self.validate_surface_contact(key)

    def _validate_pinned(self, key: str) -> None:
        if isinstance(self.pinned, str):
            require(self.pinned in PINNINGS, f"{key}.pinned", self.pinned,
                    "must be one of " + ", ".join(PINNINGS) + " or a list of particle numbers")
            return
        count = self.particles_per_edge ** 2
        require(isinstance(self.pinned, (list, tuple)), f"{key}.pinned", self.pinned,
                "must be one of " + ", ".join(PINNINGS) + " or a list of particle numbers")
        for index in self.pinned:
            whole = isinstance(index, (int, np.integer)) and not isinstance(index, bool)
            require(whole and 0 <= index < count, f"{key}.pinned", index,
                    f"particle numbers must be whole numbers in [0, {count - 1}]")

    def surface_spacing(self) -> float:
        return min(self.width, self.height) / (self.particles_per_edge - 1)

    def default_thickness(self) -> float:
        """2 cm, or a quarter of the particle spacing where that is less. Why: a self-colliding
        cloth's contacts reach its thickness and its pair search twice that beyond (SKIN in
        collision/pipeline.py); kept under the spacing, a flat cloth lists no pair of its own
        (a 100 x 100, 4 m cloth at 2 cm listed 200,000 and searched 7 times longer)."""
        return min(0.02, 0.25 * self.surface_spacing())

    def counts(self) -> tuple[int, int]:
        """Particles and springs (at most: kinds with ks = kd = 0 build none), from N alone."""
        n = self.particles_per_edge
        return n * n, 2 * n * (n - 1) + 2 * (n - 1) ** 2 + 2 * n * max(n - 2, 0)

    def build(self) -> BuiltBody:
        n = self.particles_per_edge
        index = np.arange(n * n, dtype=np.int32).reshape(n, n)
        springs, kinds = [], []
        for kind, offsets, params in ((SpringKind.STRUCTURAL, STRUCTURAL_OFFSETS, self.structural),
                                      (SpringKind.SHEAR, SHEAR_OFFSETS, self.shear),
                                      (SpringKind.BEND, BEND_OFFSETS, self.bend)):
            if not params.builds:
                continue
            for offset in offsets:
                pairs = lattice_springs(index, offset)
                springs.append(pairs)
                kinds.append(np.full(len(pairs), kind, np.int8))
        return BuiltBody(
            positions=self.particle_positions(),
            velocities=np.tile(np.asarray(self.velocity, float), (n * n, 1)),
            masses=np.full(n * n, float(self.particle_mass)),
            pinned=self.pinned_mask(),
            springs=np.concatenate(springs) if springs else np.empty((0, 2), np.int32),
            spring_kind=np.concatenate(kinds) if kinds else np.empty(0, np.int8),
            spring_parameters={SpringKind.STRUCTURAL: self.structural,
                               SpringKind.SHEAR: self.shear, SpringKind.BEND: self.bend},
            surface=grid_triangles(index),
            radii=np.zeros(n * n),
        )

    def particle_positions(self) -> np.ndarray:
        """(N^2, 3) positions in m, particle i N + j at row i (local z) and column j (local x)."""
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

    def pinned_mask(self) -> np.ndarray:
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


def _positive(value) -> bool:
    return is_finite(value) and float(value) > 0
