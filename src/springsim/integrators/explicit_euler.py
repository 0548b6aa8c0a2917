"""Explicit (forward) Euler: x' = x + h v, v' = v + h a(x, v). First order."""
from .._jit import inline_kernel, kernel, parallel_kernel
from ..forces import accelerations
from .base import KernelIntegrator, register
from ._steps import add_scaled, Motion, drive, one_stage_scratch, threaded, threaded_drive


@inline_kernel
def explicit_euler_step(model, state, scratch, h, pairs):
    x, v = state.x, state.v
    a, columns = scratch
    accelerations(model, x, v, h, a, columns)
    add_scaled(x, x, h, v)
    add_scaled(v, v, h, a)
    return pairs   # the body-body pair list: the post-step pass's to use


threaded_explicit_euler_step = threaded(explicit_euler_step)


@kernel
def advance(model, x, v, h, steps, pairs):
    return drive(explicit_euler_step, model, Motion(x, v), one_stage_scratch(x), h, steps, pairs)


@parallel_kernel
def parallel_advance(model, x, v, h, steps, pairs):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return threaded_drive(threaded_explicit_euler_step, model, Motion(x, v), one_stage_scratch(x),
                          h, steps, pairs)


@register
class ExplicitEuler(KernelIntegrator):
    name = "explicit_euler"
    adjoint = "springsim.gradients.adjoints:ExplicitEulerAdjoint"
    order = 1
    summary = "forward Euler: positions and velocities from the start-of-step state"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
