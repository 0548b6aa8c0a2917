"""Explicit midpoint (RK2): take the derivative at a temporary half-step state. Second order.

    x_mid = x + h/2 v,      v_mid = v + h/2 a(x, v)
    x'    = x + h v_mid,    v'    = v + h a(x_mid, v_mid)
"""
from .._jit import inline_kernel, kernel, parallel_kernel
from ..forces import accelerations
from ..world import move_world, step_time
from .base import KernelIntegrator, register
from ._steps import add_scaled, Motion, drive, two_stage_scratch, threaded, threaded_drive


@inline_kernel
def midpoint_step(model, state, scratch, h, pairs):
    x, v = state.x, state.v
    a, x_mid, v_mid, columns = scratch
    accelerations(model, x, v, h, a, columns)
    add_scaled(x_mid, x, h / 2, v)
    add_scaled(v_mid, v, h / 2, a)
    move_world(model, step_time(model) + h / 2)   # moving terrains where the stage is
    accelerations(model, x_mid, v_mid, h, a, columns)
    add_scaled(x, x, h, v_mid)
    add_scaled(v, v, h, a)
    return pairs   # the body-body pair list: the post-step pass's to use


threaded_midpoint_step = threaded(midpoint_step)


@kernel
def advance(model, x, v, h, steps, pairs):
    return drive(midpoint_step, model, Motion(x, v), two_stage_scratch(x), h, steps, pairs)


@parallel_kernel
def parallel_advance(model, x, v, h, steps, pairs):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return threaded_drive(threaded_midpoint_step, model, Motion(x, v), two_stage_scratch(x), h,
                          steps, pairs)


@register
class Midpoint(KernelIntegrator):
    name = "midpoint"
    adjoint = "springsim.gradients.adjoints:MidpointAdjoint"
    order = 2
    summary = "explicit midpoint (RK2): derivative at a half-step state"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
