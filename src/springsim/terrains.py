"""Terrains: static surfaces that particles collide with.

Each terrain has a signed distance ``phi`` (positive on the free side, in m) and a unit normal
pointing to the free side. A particle touches when ``phi`` is below the contact band ``epsilon``.

- Plane: ``phi = n . (x - p)``.
- Sphere (collide with its outside): ``phi = |x - c| - R``, normal ``(x - c)/|x - c|``.
- Bowl (the inside of a sphere): ``phi = R - |x - c|``, normal ``(c - x)/|x - c|``.

The tilted plane is a Plane with the reference's point and normal (normalized: the course
framework forgot to).
"""
from dataclasses import dataclass

import numpy as np

from .errors import require

PLANE, SPHERE, BOWL = 0, 1, 2


@dataclass
class Contact:
    """Restitution, Coulomb friction and contact band shared by every terrain kind."""

    restitution: float = 0.8
    friction: float = 0.3
    epsilon: float = 0.01

    def validate_contact(self, key: str) -> None:
        require(0 <= self.restitution <= 1, f"{key}.restitution", self.restitution,
                "must lie in [0, 1]")
        require(self.friction >= 0, f"{key}.friction", self.friction, "must be >= 0")
        require(self.epsilon > 0, f"{key}.epsilon", self.epsilon, "must be > 0 m")


@dataclass
class Plane(Contact):
    point: tuple = (0.0, -1.0, 0.0)
    normal: tuple = (0.0, 1.0, 0.0)

    kind = PLANE

    def validate(self, key: str) -> None:
        self.validate_contact(key)
        require(np.linalg.norm(self.normal) > 0, f"{key}.normal", self.normal,
                "must be a non-zero vector")

    def unit_normal(self) -> np.ndarray:
        normal = np.asarray(self.normal, float)
        return normal / np.linalg.norm(normal)

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        return (x - np.asarray(self.point, float)) @ self.unit_normal() - radius

    def packed(self):
        return np.asarray(self.point, float), self.unit_normal(), 0.0


def tilted_plane(**overrides) -> Plane:
    """The reference's tilted plane: through the origin, normal (1, 1, 0) normalized."""
    return Plane(**{"point": (0.0, 0.0, 0.0), "normal": (1.0, 1.0, 0.0), **overrides})


@dataclass
class Sphere(Contact):
    """A solid sphere; particles collide with its outside. Mass kept for the reference, unused."""

    center: tuple = (0.0, -1.0, 0.0)
    radius: float = 3.0
    mass: float = 10.0

    kind = SPHERE

    def validate(self, key: str) -> None:
        self.validate_contact(key)
        require(self.radius > 0, f"{key}.radius", self.radius, "must be > 0 m")

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        return np.linalg.norm(x - np.asarray(self.center, float), axis=-1) - self.radius - radius

    def packed(self):
        return np.asarray(self.center, float), np.zeros(3), float(self.radius)


@dataclass
class Bowl(Sphere):
    """The inside of a sphere; particles stay within it."""

    center: tuple = (2.0, 7.0, 1.0)
    radius: float = 7.0

    kind = BOWL

    def signed_distance(self, x: np.ndarray, radius=0.0) -> np.ndarray:
        return self.radius - np.linalg.norm(x - np.asarray(self.center, float), axis=-1) - radius


TERRAIN_TYPES = {"plane": Plane, "tilted_plane": tilted_plane, "sphere": Sphere, "bowl": Bowl}


def pack_terrains(terrains) -> dict:
    """Arrays the contact kernels read: one row per terrain."""
    count = len(terrains)
    packed = {"terrain_kind": np.zeros(count, np.int64),
              "terrain_point": np.zeros((count, 3)), "terrain_normal": np.zeros((count, 3)),
              "terrain_radius": np.zeros(count), "terrain_restitution": np.zeros(count),
              "terrain_friction": np.zeros(count), "terrain_epsilon": np.zeros(count)}
    for row, terrain in enumerate(terrains):
        point, normal, radius = terrain.packed()
        packed["terrain_kind"][row] = terrain.kind
        packed["terrain_point"][row] = point
        packed["terrain_normal"][row] = normal
        packed["terrain_radius"][row] = radius
        packed["terrain_restitution"][row] = terrain.restitution
        packed["terrain_friction"][row] = terrain.friction
        packed["terrain_epsilon"][row] = terrain.epsilon
    return packed
