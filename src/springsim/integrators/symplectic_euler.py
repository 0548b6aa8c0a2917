"""Symplectic (semi-implicit) Euler: v' = v + h a(x, v), then x' = x + h v'. First order."""
import numpy as np

from .._jit import kernel
from ..forces import accelerations, force_columns
from . import KernelIntegrator, register
from ._steps import add_scaled, finish_step


@kernel
def symplectic_euler_step(model, x, v, h, a, columns):
    accelerations(model, x, v, h, a, columns)
    add_scaled(v, v, h, a)
    add_scaled(x, x, h, v)


@kernel
def advance(model, x, v, h, steps):
    a = np.empty_like(x)
    columns = force_columns(x)
    for step in range(steps):
        symplectic_euler_step(model, x, v, h, a, columns)
        particle = finish_step(model, x, v)
        if particle >= 0:
            return step + 1, particle
    return steps, -1


@register
class SymplecticEuler(KernelIntegrator):
    name = "symplectic_euler"
    order = 1
    summary = "semi-implicit Euler: new velocity first, then positions with it"
    kernel = staticmethod(advance)
