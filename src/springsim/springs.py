"""Spring kinds and the spring table of a model.

A spring joins particles ``a`` and ``b`` with a rest length. Its stiffness ``ks`` (N/m) and damping
``kd`` (N s/m) are not stored per spring: each spring points into a small table of parameter groups
(one per distinct ks and kd), which keeps a million-particle cube's 15.7 million springs in memory.
"""
import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from ._jit import kernel
from .errors import is_finite, require


class SpringKind(IntEnum):
    STRUCTURAL = 0
    SHEAR = 1
    BEND = 2
    FACE = 3  # long springs from a face to the opposite face of a cube

    @property
    def label(self) -> str:
        return self.name.lower()


SPRING_KIND_NAMES = tuple(kind.label for kind in SpringKind)


@dataclass(frozen=True)
class SpringParameters:
    """Stiffness ks (N/m) and damping kd (N s/m) of one kind of spring."""

    ks: float
    kd: float

    @property
    def builds(self) -> bool:
        """Whether a body builds springs of this kind (ks and kd both zero: none)."""
        return self.ks > 0 or self.kd > 0

    def validate(self, key: str) -> None:
        require(is_finite(self.ks) and self.ks >= 0, f"{key}.ks", self.ks, "must be >= 0 N/m")
        require(is_finite(self.kd) and self.kd >= 0, f"{key}.kd", self.kd, "must be >= 0 N s/m")


@kernel
def spring_force_factor(dx, dy, dz, dvx, dvy, dvz, rest_length, ks, kd):
    """The spring and damper force on a is this factor times d, for d = x_a - x_b and
    dv = v_a - v_b. With the unit vector l = d / |d|,
        f_a = (-ks (|d| - r) - kd dv . l) l = (-ks (|d| - r) - kd dv . l) / |d| * d,
    and f_b = -f_a. Coincident particles have no direction, and no force."""
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    inverse_length = 1.0 / length if length > 0.0 else 0.0
    closing_speed = (dvx * dx + dvy * dy + dvz * dz) * inverse_length
    return (-ks * (length - rest_length) - kd * closing_speed) * inverse_length


def lattice_springs(index: np.ndarray, offset: tuple[int, ...]) -> np.ndarray:
    """Springs from every lattice site to the site ``offset`` away, where that site exists.

    ``index`` maps lattice coordinates to particle numbers (a 2-D or 3-D integer array). Each spring
    is produced once, from the site that owns the link ("positive half" of the neighbourhood).
    """
    source = [slice(None)] * index.ndim
    target = [slice(None)] * index.ndim
    for axis, step in enumerate(offset):
        size = index.shape[axis]
        if abs(step) >= size:
            return np.empty((0, 2), dtype=np.int32)
        if step >= 0:
            source[axis] = slice(0, size - step)
            target[axis] = slice(step, size)
        else:
            source[axis] = slice(-step, size)
            target[axis] = slice(0, size + step)
    a = index[tuple(source)].ravel()
    b = index[tuple(target)].ravel()
    return np.stack([a, b], axis=1).astype(np.int32)
