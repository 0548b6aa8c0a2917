"""Classical fourth-order Runge-Kutta on the whole state (x, v). Fourth order.

    k1 = f(y),  k2 = f(y + h/2 k1),  k3 = f(y + h/2 k2),  k4 = f(y + h k3)
    y' = y + h/6 (k1 + 2 k2 + 2 k3 + k4),   with y = (x, v) and f(x, v) = (v, a(x, v)).

Each stage evaluates forces on its own temporary state (x_k, v_k); the weighted sum of the
stages accumulates in (dx, dv).
"""
import numpy as np
from numba import prange

from .._jit import inline_kernel, kernel, parallel_kernel
from ..forces import accelerations, force_columns
from ..world import move_world, step_end, step_time
from .base import KernelIntegrator, register
from ._steps import Motion, drive, threaded, threaded_drive


@inline_kernel
def rk4_step(model, state, scratch, h, pairs):
    x, v = state.x, state.v
    x_k, v_k, a, dx, dv, columns = scratch
    accelerations(model, x, v, h, a, columns)      # k1 = (v, a)
    first_stage(x, v, a, x_k, v_k, dx, dv, h / 2)
    move_world(model, step_time(model) + h / 2)    # moving terrains at the stages' times
    accelerations(model, x_k, v_k, h, a, columns)  # k2 = (v_k, a)
    middle_stage(x, v, a, x_k, v_k, dx, dv, h / 2)
    accelerations(model, x_k, v_k, h, a, columns)  # k3
    middle_stage(x, v, a, x_k, v_k, dx, dv, h)
    move_world(model, step_end(model, h))
    accelerations(model, x_k, v_k, h, a, columns)  # k4
    last_stage(x, v, a, v_k, dx, dv, h)
    return pairs   # the body-body pair list: the post-step pass's to use


# The stages' sums, each in one pass over the particles: at 1,000,000 particles these passes only
# stream memory, which two cores share (benchmarks/threads.py), so fewer passes is what helps.

@inline_kernel
def first_stage(x, v, a, x_k, v_k, dx, dv, step):
    """(dx, dv) = k1 = (v, a); the next stage's state (x_k, v_k) = y + step k1."""
    for i in prange(x.shape[0]):
        for c in range(3):
            dx[i, c] = v[i, c]
            dv[i, c] = a[i, c]
            x_k[i, c] = x[i, c] + step * v[i, c]
            v_k[i, c] = v[i, c] + step * a[i, c]


@inline_kernel
def middle_stage(x, v, a, x_k, v_k, dx, dv, step):
    """(dx, dv) += 2 k, k = (v_k, a) this stage's slope; the next stage's state y + step k."""
    for i in prange(x.shape[0]):
        for c in range(3):
            slope = v_k[i, c]
            dx[i, c] += 2.0 * slope
            dv[i, c] += 2.0 * a[i, c]
            x_k[i, c] = x[i, c] + step * slope
            v_k[i, c] = v[i, c] + step * a[i, c]


@inline_kernel
def last_stage(x, v, a, v_k, dx, dv, h):
    """y += h/6 (k1 + 2 k2 + 2 k3 + k4), with k4 = (v_k, a)."""
    for i in prange(x.shape[0]):
        for c in range(3):
            x[i, c] += h / 6 * (dx[i, c] + v_k[i, c])
            v[i, c] += h / 6 * (dv[i, c] + a[i, c])


@kernel
def rk4_scratch(x):
    """x_k, v_k, a, dx, dv and the force columns."""
    return (np.empty_like(x), np.empty_like(x), np.empty_like(x), np.empty_like(x),
            np.empty_like(x), force_columns(x))


threaded_rk4_step = threaded(rk4_step)


@kernel
def advance(model, x, v, h, steps, pairs):
    return drive(rk4_step, model, Motion(x, v), rk4_scratch(x), h, steps, pairs)


@parallel_kernel
def parallel_advance(model, x, v, h, steps, pairs):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return threaded_drive(threaded_rk4_step, model, Motion(x, v), rk4_scratch(x), h, steps, pairs)


@register
class RK4(KernelIntegrator):
    name = "rk4"
    order = 4
    summary = "classical fourth-order Runge-Kutta"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
