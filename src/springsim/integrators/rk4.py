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
    x_k, v_k, a, dx, dv, columns, tape = scratch
    n = begin_keeping(tape, x, v)
    accelerations(model, x, v, h, a, columns)      # k1 = (v, a)
    keep(tape, n, 0, a)
    first_stage(x, v, a, x_k, v_k, dx, dv, h / 2)
    move_world(model, step_time(model) + h / 2)    # moving terrains at the stages' times
    accelerations(model, x_k, v_k, h, a, columns)  # k2 = (v_k, a)
    keep(tape, n, 1, a)
    middle_stage(x, v, a, x_k, v_k, dx, dv, h / 2)
    accelerations(model, x_k, v_k, h, a, columns)  # k3
    keep(tape, n, 2, a)
    middle_stage(x, v, a, x_k, v_k, dx, dv, h)
    move_world(model, step_end(model, h))
    accelerations(model, x_k, v_k, h, a, columns)  # k4
    keep(tape, n, 3, a)
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


# Where the gradient's tape records a run (gradients/tape.py), each step keeps its start and its
# stages' accelerations, so that the adjoint need not evaluate the forces again: ``tape`` is
# (kept (N, 4, P, 3), starts (N, 2, P, 3), the number of steps kept so far (1,)), with no rows
# in a plain run.

@inline_kernel
def begin_keeping(tape, x, v):
    """starts[n] = (x, v) for this step n, which it returns (-1 in a plain run)."""
    kept, starts, count = tape
    if kept.shape[0] == 0:
        return -1
    n = count[0]
    count[0] = n + 1
    for i in range(x.shape[0]):
        for c in range(3):
            starts[n, 0, i, c] = x[i, c]
            starts[n, 1, i, c] = v[i, c]
    return n


@inline_kernel
def keep(tape, n, k, a):
    """kept[n, k] = a, stage k's accelerations, where the run is kept (n >= 0)."""
    if n >= 0:
        kept = tape[0]
        for i in range(a.shape[0]):
            for c in range(3):
                kept[n, k, i, c] = a[i, c]


@inline_kernel
def last_stage(x, v, a, v_k, dx, dv, h):
    """y += h/6 (k1 + 2 k2 + 2 k3 + k4), with k4 = (v_k, a)."""
    for i in prange(x.shape[0]):
        for c in range(3):
            x[i, c] += h / 6 * (dx[i, c] + v_k[i, c])
            v[i, c] += h / 6 * (dv[i, c] + a[i, c])


@kernel
def rk4_scratch(x, tape):
    """x_k, v_k, a, dx, dv, the force columns and the tape (``begin_keeping``)."""
    return (np.empty_like(x), np.empty_like(x), np.empty_like(x), np.empty_like(x),
            np.empty_like(x), force_columns(x), tape)


@kernel
def no_tape():
    """The tape of a plain run: nothing kept."""
    return np.empty((0, 4, 0, 3)), np.empty((0, 2, 0, 3)), np.zeros(1, np.int64)


threaded_rk4_step = threaded(rk4_step)


@kernel
def advance(model, x, v, h, steps, pairs):
    return drive(rk4_step, model, Motion(x, v), rk4_scratch(x, no_tape()), h, steps, pairs)


@kernel
def advance_keeping(model, x, v, h, steps, pairs, kept, starts):
    """``advance`` that keeps each step's start (x, v) in starts[n] and its four stages'
    accelerations in kept[n] (begin_keeping)."""
    tape = (kept, starts, np.zeros(1, np.int64))
    return drive(rk4_step, model, Motion(x, v), rk4_scratch(x, tape), h, steps, pairs)


@parallel_kernel
def parallel_advance(model, x, v, h, steps, pairs):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return threaded_drive(threaded_rk4_step, model, Motion(x, v),
                          rk4_scratch(x, no_tape()), h, steps, pairs)


@register
class RK4(KernelIntegrator):
    name = "rk4"
    adjoint = "springsim.gradients.adjoints:RK4Adjoint"
    order = 4
    summary = "classical fourth-order Runge-Kutta"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
    keeping_kernel = staticmethod(advance_keeping)
    stages = 4
