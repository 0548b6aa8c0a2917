"""Body builders: each turns a plain description into particles, springs and a surface."""
from dataclasses import dataclass, field

import numpy as np

from ..springs import SpringParameters


@dataclass
class BuiltBody:
    """Particles and springs of one body, with indices local to the body."""

    positions: np.ndarray            # (n, 3) m
    velocities: np.ndarray           # (n, 3) m/s
    masses: np.ndarray               # (n,) kg
    pinned: np.ndarray               # (n,) bool: pinned particles never move
    springs: np.ndarray              # (s, 2) int32
    spring_kind: np.ndarray          # (s,) int8, a SpringKind
    spring_parameters: dict          # SpringKind -> SpringParameters
    surface: np.ndarray = field(default_factory=lambda: np.empty((0, 3), np.int32))  # triangles
    radii: np.ndarray | None = None  # (n,) m, contact radius; zero for points
    # a surface embedded in the lattice (mesh bodies): surfaces.Embedding with particle numbers
    # local to the body, and ``surface`` then holds triangles of the embedded vertices
    embedding: object = None
    # (n,) m: how far the body's surface reaches beyond each particle, kept clear of terrains
    # (mesh bodies; None: the contact radius, zero for points)
    terrain_offsets: np.ndarray | None = None
    # (c, 3) triangles of particle numbers that other bodies touch (collision/shapes/surfaces.py;
    # None: the surface, when it is not embedded)
    collision_surface: np.ndarray | None = None
    # (s, 2) each spring's (ks, kd), from a material (bodies/cloth_material.py); None: the
    # spring_parameters of its kind
    spring_constants: np.ndarray | None = None
    # a sheet is all surface (a cloth): balls touch it through its triangles in implicit_euler's
    # solve (model.sheet_arrays)
    sheet: bool = False
    # pins that move (bodies/pins.py): (particle numbers local to the body, Pin) each; their
    # particles are in ``pinned`` too
    moving_pins: list = field(default_factory=list)


__all__ = ["BuiltBody", "SpringParameters"]
