"""The soft "jelly" cube: an N x N x N lattice of particles joined by springs.

Defaults are the course framework's (see the reference): 10 particles per edge, edge 4 m, 1 kg
particles, ks = 2000 N/m and kd = 60 N s/m for every kind, and particle (i, j, k) placed at
``position + ((i, j, k) - N//2) * spacing``, which for N = 10 is the framework's off-centre start.
"""
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ..errors import is_finite, require, require_angle
from ..springs import SpringKind, SpringParameters, lattice_springs
from . import BuiltBody
from .pins import Pin, moving_pins, particle_cache, pinned_mask
from ..collision.shapes.settings import SurfaceContact

STRUCTURAL_OFFSETS = ((1, 0, 0), (0, 1, 0), (0, 0, 1))
BEND_OFFSETS = ((2, 0, 0), (0, 2, 0), (0, 0, 2))
SHEAR_OFFSETS = ((1, 1, 0), (1, -1, 0), (1, 0, 1), (1, 0, -1), (0, 1, 1), (0, 1, -1),
                 (1, 1, 1), (1, 1, -1), (1, -1, 1), (1, -1, -1))


def _default_springs():
    return SpringParameters(ks=2000.0, kd=60.0)


@dataclass
class LatticeSprings:
    """The spring tables of a lattice body (the cube's and a mesh body's): structural, shear and
    bend springs, and optional face-to-face springs."""

    structural: SpringParameters = field(default_factory=_default_springs)
    shear: SpringParameters = field(default_factory=_default_springs)
    bend: SpringParameters = field(default_factory=_default_springs)
    face_springs: bool = False
    face: SpringParameters = field(default_factory=_default_springs)

    def validate_springs(self, key: str) -> None:
        for kind in ("structural", "shear", "bend", "face"):
            getattr(self, kind).validate(f"{key}.{kind}")


@dataclass
class Cube(LatticeSprings, SurfaceContact):
    """A soft cube. Lengths in m, masses in kg, angles in degrees."""

    particles_per_edge: int = 10
    edge_length: float = 4.0
    particle_mass: float = 1.0
    position: tuple = (0.0, 9.0, 0.0)
    velocity: tuple = (0.0, 0.0, 0.0)
    rotation_degrees: float = 0.0
    rotation_axis: tuple = (1.0, 0.0, 1.0)
    pinned: tuple = ()
    pins: list[Pin] = field(default_factory=list)   # held, moving or soft pins (bodies/pins.py)

    def validate(self, key: str) -> None:
        n = self.particles_per_edge
        require(isinstance(n, int) and n >= 2, f"{key}.particles_per_edge", n,
                "needs an integer >= 2 (structural and shear springs join neighbours)")
        require(n >= 3 or not self.bend.builds, f"{key}.particles_per_edge", n,
                "needs >= 3 for bend springs, which skip one particle (or set bend ks and kd to 0)")
        # a face spring joins particle 0 to N-1: for N = 2 that is a structural spring, for
        # N = 3 a bend spring, and the same pair would be joined twice
        require(n >= 4 or not (self.face_springs and self.face.builds),
                f"{key}.particles_per_edge", n,
                "needs >= 4 for face springs (below that they duplicate structural or bend "
                "springs; or set face_springs = false)")
        require(is_finite(self.edge_length) and self.edge_length > 0, f"{key}.edge_length",
                self.edge_length, "must be > 0 m")
        require(is_finite(self.particle_mass) and self.particle_mass > 0,
                f"{key}.particle_mass", self.particle_mass, "must be > 0 kg")
        for name in ("position", "velocity", "rotation_axis"):
            value = getattr(self, name)
            require(np.shape(value) == (3,) and is_finite(value), f"{key}.{name}", value,
                    "must be three finite numbers")
        require(np.linalg.norm(self.rotation_axis) > 0, f"{key}.rotation_axis",
                self.rotation_axis, "must be a non-zero vector")
        require_angle(self.rotation_degrees, f"{key}.rotation_degrees")
        self.validate_springs(key)
        self.validate_surface_contact(key)
        count = n ** 3
        for index in self.pinned:
            require(0 <= index < count, f"{key}.pinned", index,
                    f"particle numbers must lie in [0, {count - 1}]")
        for p, pin in enumerate(self.pins):
            pin.validate(f"{key}.pins.{p}")
        if self.pins:
            pinned_mask(self.pins, self.build_positions(), {}, f"{key}.pins")
            moving_pins(self.pins, self.build_positions(), {},
                        particle_cache(self.particles_per_edge ** 3), f"{key}.pins")

    def surface_spacing(self) -> float:
        return self.edge_length / (self.particles_per_edge - 1)

    def counts(self) -> tuple[int, int]:
        """Particles and springs (at most: kinds with ks = kd = 0 build none), from N alone."""
        n = self.particles_per_edge
        springs = (3 * n * n * (n - 1)                                     # structural
                   + 6 * n * (n - 1) ** 2 + 4 * (n - 1) ** 3                # shear
                   + 3 * n * n * max(n - 2, 0)                              # bend
                   + 3 * n * n * self.face_springs)                         # face
        return n ** 3, springs

    def build_positions(self) -> np.ndarray:
        """The particles where they start (m)."""
        n = self.particles_per_edge
        spacing = self.edge_length / (n - 1)
        lattice = np.indices((n, n, n)).reshape(3, -1).T - n // 2
        offsets = lattice * spacing
        if self.rotation_degrees:
            axis = np.asarray(self.rotation_axis, float)
            rotvec = np.radians(self.rotation_degrees) * axis / np.linalg.norm(axis)
            offsets = Rotation.from_rotvec(rotvec).apply(offsets)
        return offsets + np.asarray(self.position, float)

    def build(self) -> BuiltBody:
        n = self.particles_per_edge
        index = np.arange(n ** 3, dtype=np.int32).reshape(n, n, n)
        positions = self.build_positions()

        springs, kinds = lattice_pattern(index, self)

        pinned = np.zeros(n ** 3, bool)
        pinned[list(self.pinned)] = True
        if self.pins:
            pinned |= pinned_mask(self.pins, positions, {}, "pins")
        return BuiltBody(
            positions=positions,
            velocities=np.tile(np.asarray(self.velocity, float), (n ** 3, 1)),
            masses=np.full(n ** 3, float(self.particle_mass)),
            pinned=pinned,
            springs=springs,
            spring_kind=kinds,
            spring_parameters=spring_parameters(self),
            surface=cube_surface(index),
            moving_pins=moving_pins(self.pins, positions, {}, particle_cache(n ** 3)),
        )


def lattice_pattern(index: np.ndarray, body) -> tuple[np.ndarray, np.ndarray]:
    """The cube's springs between the sites of a 3-D lattice: (S, 2) int32 particle numbers and
    their (S,) SpringKind. ``index`` maps lattice coordinates to particle numbers, -1 where the
    lattice has no particle (a mesh body's outside); a spring needs both ends, and a bend spring
    its middle site too (else it would bridge a gap between two parts). ``body`` holds the
    spring tables (structural, shear, bend, face_springs, face). A full lattice gives the
    cube's springs."""
    groups = [(SpringKind.STRUCTURAL, STRUCTURAL_OFFSETS, body.structural),
              (SpringKind.SHEAR, SHEAR_OFFSETS, body.shear),
              (SpringKind.BEND, BEND_OFFSETS, body.bend)]
    springs, kinds = [], []
    for kind, kind_offsets, params in groups:
        if not params.builds:
            continue
        for offset in kind_offsets:
            pairs = lattice_springs(index, offset)
            present = np.all(pairs >= 0, axis=1)
            if kind == SpringKind.BEND:
                present &= middle_sites(index, offset) >= 0
            springs.append(pairs[present])
            kinds.append(kind)
    if body.face_springs and body.face.builds:
        pairs = face_to_face_springs(index)
        springs.append(pairs[np.all(pairs >= 0, axis=1)])
        kinds.append(SpringKind.FACE)
    kinds = [np.full(len(pairs), kind, np.int8) for pairs, kind in zip(springs, kinds)]
    return (np.concatenate(springs) if springs else np.empty((0, 2), np.int32),
            np.concatenate(kinds) if kinds else np.empty(0, np.int8))


def middle_sites(index: np.ndarray, offset: tuple[int, ...]) -> np.ndarray:
    """The site halfway along each pair ``lattice_springs(index, offset)`` gives (offsets of
    even, non-negative steps, as the bend springs')."""
    middle = []
    for axis, step in enumerate(offset):
        size = index.shape[axis]
        middle.append(slice(step // 2, size - step + step // 2))
    return index[tuple(middle)].ravel()


def spring_parameters(body) -> dict:
    return {SpringKind.STRUCTURAL: body.structural, SpringKind.SHEAR: body.shear,
            SpringKind.BEND: body.bend, SpringKind.FACE: body.face}


def face_to_face_springs(index: np.ndarray) -> np.ndarray:
    """Long springs from each face particle to the one on the opposite face (0 to N-1)."""
    # rows shorter than 4 would join sites that structural or bend springs already join
    return np.concatenate([np.empty((0, 2), np.int32)] + [
        lattice_springs(index, tuple(index.shape[axis] - 1 if a == axis else 0 for a in range(3)))
        for axis in range(3) if index.shape[axis] >= 4])


def cube_surface(index: np.ndarray) -> np.ndarray:
    """Triangles of the six outer faces, wound so that normals point out of the cube."""
    faces = [index[0, :, :], index[-1, :, :].T, index[:, 0, :].T, index[:, -1, :],
             index[:, :, 0], index[:, :, -1].T]
    return np.concatenate([grid_triangles(face) for face in faces])


def grid_triangles(grid: np.ndarray) -> np.ndarray:
    """Two triangles per cell of a 2-D grid of particle numbers."""
    a, b = grid[:-1, :-1].ravel(), grid[1:, :-1].ravel()
    c, d = grid[1:, 1:].ravel(), grid[:-1, 1:].ravel()
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int32)
