"""Pulling a particle with the mouse: a damped spring from the particle to a point under the
cursor, applied between time steps (the physics kernels are not touched).

Before each step of size h the held particle's velocity gets the spring's impulse per unit mass,

    v += h (w^2 (target - x) - 2 w v),

a critically damped spring of natural angular frequency w (stiffness k = w^2 m for a particle of
mass m, so that light cloth particles and heavy balls answer alike). Applied explicitly, the
update is stable only while w h stays well below 1, so w is capped at ``0.5 / h``.
"""
import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class MouseSpring:
    stiffness_per_mass: float = 5000.0  # w^2 in 1/s^2 (N/m per kg)
    particle: int = -1                  # the held particle, -1 when none
    target: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def holding(self) -> bool:
        return self.particle >= 0

    def grab(self, particle: int, target) -> None:
        self.particle = int(particle)
        self.target = np.asarray(target, float).copy()

    def move(self, target) -> None:
        self.target = np.asarray(target, float).copy()

    def release(self) -> None:
        self.particle = -1

    def angular_frequency(self, h: float) -> float:
        return min(math.sqrt(self.stiffness_per_mass), 0.5 / h)

    def apply(self, state, model, h: float) -> None:
        """Give the held particle the spring's impulse for one step of size ``h`` (s)."""
        i = self.particle
        if i < 0 or i >= model.particle_count or model.arrays.inv_mass[i] == 0.0:
            return                      # nothing held, or a pinned particle: it cannot move
        w = self.angular_frequency(h)
        x, v = state.positions[i], state.velocities[i]
        v += h * (w * w * (self.target - x) - 2.0 * w * v)


def nearest_particle(positions: np.ndarray, point, within: float) -> int:
    """The particle closest to ``point``, or -1 if none lies within ``within`` (m)."""
    distances = np.linalg.norm(positions - np.asarray(point, float), axis=1)
    best = int(np.argmin(distances))
    return best if distances[best] <= within else -1


def point_on_drag_plane(origin, direction, anchor, normal):
    """Where the ray origin + s direction meets the plane through ``anchor`` with ``normal``
    (the plane facing the camera in which a held particle is pulled); None if it never does."""
    direction = np.asarray(direction, float)
    normal = np.asarray(normal, float)
    facing = direction @ normal
    if abs(facing) < 1e-12:
        return None
    s = (np.asarray(anchor, float) - origin) @ normal / facing
    if s <= 0:
        return None
    return np.asarray(origin, float) + s * direction
