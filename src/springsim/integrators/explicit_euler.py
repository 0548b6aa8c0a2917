"""Explicit (forward) Euler: x' = x + h v, v' = v + h a(x, v). First order."""
import numpy as np

from .._jit import kernel
from ..forces import accelerations, force_columns
from . import KernelIntegrator, register
from ._steps import add_scaled, finish_step


@kernel
def explicit_euler_step(model, x, v, h, a, columns):
    accelerations(model, x, v, h, a, columns)
    add_scaled(x, x, h, v)
    add_scaled(v, v, h, a)


@kernel
def advance(model, x, v, h, steps):
    a = np.empty_like(x)
    columns = force_columns(x)
    for step in range(steps):
        explicit_euler_step(model, x, v, h, a, columns)
        particle = finish_step(model, x, v)
        if particle >= 0:
            return step + 1, particle
    return steps, -1


@register
class ExplicitEuler(KernelIntegrator):
    name = "explicit_euler"
    order = 1
    summary = "forward Euler: positions and velocities from the start-of-step state"
    kernel = staticmethod(advance)
