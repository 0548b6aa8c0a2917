"""Small kernels the integrators share."""
import numpy as np

from .._jit import kernel
from ..collisions import resolve_body_collisions
from ..contact import resolve_terrain_impacts

SPEED_SQUARED_LIMIT = 1e6  # the course framework's "System Unstable" threshold, m^2/s^2


@kernel
def add_scaled(out, x, alpha, y):
    """out = x + alpha * y, elementwise, with no temporary array."""
    for i in range(x.shape[0]):
        for c in range(3):
            out[i, c] = x[i, c] + alpha * y[i, c]


@kernel
def first_diverged(x, v):
    """Index of the first particle with a non-finite state or |v|^2 above the limit, else -1."""
    for i in range(v.shape[0]):
        speed_squared = v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2]
        position = x[i, 0] + x[i, 1] + x[i, 2]
        # written so that NaN fails the test: every comparison with NaN is False
        if not (speed_squared <= SPEED_SQUARED_LIMIT and np.abs(position) < np.inf):
            return i
    return -1


@kernel
def finish_step(model, x, v):
    """Everything after the integrator's update: terrain impacts, body-body collisions (balls),
    then the divergence check."""
    resolve_terrain_impacts(model, x, v)
    resolve_body_collisions(model, x, v)
    return first_diverged(x, v)
