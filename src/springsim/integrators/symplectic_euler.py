"""Symplectic (semi-implicit) Euler: v' = v + h a(x, v), then x' = x + h v'. First order."""
from .._jit import inline_kernel, kernel, parallel_kernel
from ..forces import accelerations
from .base import KernelIntegrator, register
from ._steps import add_scaled, Motion, drive, one_stage_scratch, threaded, threaded_drive


@inline_kernel
def symplectic_euler_step(model, state, scratch, h, pairs):
    x, v = state.x, state.v
    a, columns = scratch
    accelerations(model, x, v, h, a, columns)
    add_scaled(v, v, h, a)
    add_scaled(x, x, h, v)
    return pairs   # the body-body pair list: the post-step pass's to use


threaded_symplectic_euler_step = threaded(symplectic_euler_step)


@kernel
def advance(model, x, v, h, steps, pairs):
    return drive(symplectic_euler_step, model, Motion(x, v), one_stage_scratch(x), h, steps, pairs)


@parallel_kernel
def parallel_advance(model, x, v, h, steps, pairs):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return threaded_drive(threaded_symplectic_euler_step, model, Motion(x, v), one_stage_scratch(x),
                          h, steps, pairs)


@register
class SymplecticEuler(KernelIntegrator):
    name = "symplectic_euler"
    adjoint = "springsim.gradients.adjoints:SymplecticEulerAdjoint"
    order = 1
    summary = "semi-implicit Euler: new velocity first, then positions with it"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
