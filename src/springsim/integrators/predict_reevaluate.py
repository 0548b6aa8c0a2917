"""The seeds' "implicit Euler", under a name that says what it does: predict with an explicit
Euler step, re-evaluate the derivative there, and step from the start with it.

    x_p = x + h v,      v_p = v + h a(x, v)
    x'  = x + h v_p,    v'  = v + h a(x_p, v_p)

Every derivative it takes is known at the start of the step, so it is an explicit method (first
order), not backward Euler; on the course framework's cube its stable range is about half of
explicit Euler's. Kept to compare with the course framework; ``implicit_euler`` is the real thing.

Terrain contact in the re-evaluation (collision/response/terrain.py) is found at the predicted
positions x_p but stops the velocity the update changes, v, not v_p: its reaction and static
friction are the accelerations that stop a velocity within the step, and v' = v + h a. Stopping v_p
instead (as plain ``accelerations(x_p, v_p)`` would) leaves a resting particle's v' = v - v_p = v,
since the prediction already stopped v_p: a phantom sliding velocity that never decays while
x' = x + h v_p stays put (up to 28 mm/s on the jelly cube at rest on the plane).
"""
from .._jit import inline_kernel, kernel, parallel_kernel
from ..collision.response.terrain import apply_contact_forces
from ..forces import accelerations, free_accelerations
from ..world import move_world, step_end
from .base import KernelIntegrator, register
from ._steps import add_scaled, Motion, drive, two_stage_scratch, threaded, threaded_drive


@kernel
def reevaluated_accelerations(model, x_p, v_p, v, h, a, columns):
    """a at the prediction (x_p, v_p), with terrain contact stopping v, which the update
    changes (module doc)."""
    free_accelerations(model, x_p, v_p, a, columns)
    apply_contact_forces(model, x_p, v, h, a)


@inline_kernel
def predict_reevaluate_step(model, state, scratch, h, pairs):
    x, v = state.x, state.v
    a, x_p, v_p, columns = scratch
    accelerations(model, x, v, h, a, columns)
    add_scaled(x_p, x, h, v)
    add_scaled(v_p, v, h, a)
    move_world(model, step_end(model, h))   # moving terrains where the prediction is
    reevaluated_accelerations(model, x_p, v_p, v, h, a, columns)
    add_scaled(x, x, h, v_p)
    add_scaled(v, v, h, a)
    return pairs   # the body-body pair list: the post-step pass's to use


threaded_predict_reevaluate_step = threaded(
    predict_reevaluate_step,
    reevaluated_accelerations=inline_kernel(reevaluated_accelerations.py_func))


@kernel
def advance(model, x, v, h, steps, pairs):
    return drive(predict_reevaluate_step, model, Motion(x, v), two_stage_scratch(x), h, steps,
                 pairs)


@parallel_kernel
def parallel_advance(model, x, v, h, steps, pairs):
    """advance, its loops on threads (integrators.KernelIntegrator)."""
    return threaded_drive(threaded_predict_reevaluate_step, model, Motion(x, v),
                          two_stage_scratch(x), h, steps, pairs)


@register
class PredictReevaluate(KernelIntegrator):
    name = "predict_reevaluate"
    adjoint = "springsim.gradients.adjoints:PredictReevaluateAdjoint"
    order = 1
    summary = "the course framework's 'implicit' Euler: explicit predict, re-evaluate, step"
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)
