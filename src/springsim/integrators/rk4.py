"""Classical fourth-order Runge-Kutta on the whole state (x, v). Fourth order.

    k1 = f(y),  k2 = f(y + h/2 k1),  k3 = f(y + h/2 k2),  k4 = f(y + h k3)
    y' = y + h/6 (k1 + 2 k2 + 2 k3 + k4),   with y = (x, v) and f(x, v) = (v, a(x, v)).

Each stage evaluates forces on its own temporary state (x_k, v_k); the weighted sum of the
stages accumulates in (dx, dv).
"""
import numpy as np

from .._jit import inline_kernel, kernel, parallel_kernel
from ..forces import accelerations, force_columns
from . import KernelIntegrator, register
from ._steps import add_scaled, drive


@inline_kernel
def rk4_step(model, state, scratch, h):
    x, v = state
    x_k, v_k, a, dx, dv, columns = scratch
    accelerations(model, x, v, h, a, columns)      # k1 = (v, a)
    dx[:] = v
    dv[:] = a
    add_scaled(x_k, x, h / 2, v)
    add_scaled(v_k, v, h / 2, a)
    accelerations(model, x_k, v_k, h, a, columns)  # k2 = (v_k, a)
    add_scaled(dx, dx, 2.0, v_k)
    add_scaled(dv, dv, 2.0, a)
    add_scaled(x_k, x, h / 2, v_k)
    add_scaled(v_k, v, h / 2, a)
    accelerations(model, x_k, v_k, h, a, columns)  # k3
    add_scaled(dx, dx, 2.0, v_k)
    add_scaled(dv, dv, 2.0, a)
    add_scaled(x_k, x, h, v_k)
    add_scaled(v_k, v, h, a)
    accelerations(model, x_k, v_k, h, a, columns)  # k4
    add_scaled(dx, dx, 1.0, v_k)
    add_scaled(dv, dv, 1.0, a)
    add_scaled(x, x, h / 6, dx)
    add_scaled(v, v, h / 6, dv)


@kernel
def rk4_scratch(x):
    """x_k, v_k, a, dx, dv and the force columns."""
    return (np.empty_like(x), np.empty_like(x), np.empty_like(x), np.empty_like(x),
            np.empty_like(x), force_columns(x))


@kernel
def advance(model, x, v, h, steps):
    return drive(rk4_step, model, (x, v), rk4_scratch(x), h, steps)


@parallel_kernel
def parallel_advance(model, x, v, h, steps):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return drive(rk4_step, model, (x, v), rk4_scratch(x), h, steps)


@register
class RK4(KernelIntegrator):
    name = "rk4"
    order = 4
    summary = "classical fourth-order Runge-Kutta"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
