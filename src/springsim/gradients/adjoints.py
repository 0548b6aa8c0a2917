"""The adjoint of each integrator's step: given the cotangents of the state after a step, the
cotangents of the state before it, and the parameters' share added to ``bar``.

An open set, as the integrators are: one class per method, registered under the integrator's
name (``@register_adjoint``). Each mirrors its method's step (integrators/) line by line in
reverse, so the gradient is of the arithmetic the simulation did, not of the differential
equation it approximates. ``step_vjp(physical, h, start, end, x_bar, v_bar, bar)`` takes the
recorded states at the step's start and end, (x, v) each, and returns (x_bar, v_bar) at its
start. Contact is not in these steps: the caller refuses scenes with any (gradients/checks.py).
"""
import numpy as np

from .physics import accelerations, accelerations_vjp
from .solve import newton_estimates, system_vjp_iteration

ADJOINTS: dict[str, type] = {}


def register_adjoint(cls):
    ADJOINTS[cls.name] = cls
    return cls


class Adjoint:
    name = ""

    def __init__(self, integrator):
        self.integrator = integrator

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar):
        raise NotImplementedError   # every registered adjoint overrides this


@register_adjoint
class SymplecticEulerAdjoint(Adjoint):
    """v' = v + h a(x, v), x' = x + h v'."""

    name = "symplectic_euler"

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar):
        x, v = start
        v_new_bar = v_bar + h * x_bar
        a_bar = h * v_new_bar
        x_bar, v_bar = x_bar.copy(), v_new_bar.copy()
        accelerations_vjp(physical, x, v, a_bar, x_bar, v_bar, bar)
        return x_bar, v_bar


@register_adjoint
class ExplicitEulerAdjoint(Adjoint):
    """x' = x + h v, v' = v + h a(x, v)."""

    name = "explicit_euler"

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar):
        x, v = start
        a_bar = h * v_bar
        x_bar, v_bar = x_bar.copy(), v_bar + h * x_bar
        accelerations_vjp(physical, x, v, a_bar, x_bar, v_bar, bar)
        return x_bar, v_bar


@register_adjoint
class RK4Adjoint(Adjoint):
    """integrators/rk4.py: stages (x_k, v_k), slopes (v_k, a(x_k, v_k)),
        x' = x + h/6 (v + 2 v2 + 2 v3 + v4),  v' = v + h/6 (a1 + 2 a2 + 2 a3 + a4),
    with (x2, v2) = y + h/2 k1, (x3, v3) = y + h/2 k2, (x4, v4) = y + h k3."""

    name = "rk4"

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar):
        x, v = start
        a1 = accelerations(physical, x, v)
        x2, v2 = x + h / 2 * v, v + h / 2 * a1
        a2 = accelerations(physical, x2, v2)
        x3, v3 = x + h / 2 * v2, v + h / 2 * a2
        a3 = accelerations(physical, x3, v3)
        x4, v4 = x + h * v3, v + h * a3
        out_x, out_v = x_bar.copy(), v_bar.copy()   # y' = y + ...
        # Backwards through the stages: stage k's state is y + step (v_{k-1}, a_{k-1}) and its
        # slope (v_k, a_k) enters y' with ``weight``; what flows into stage k-1's velocity and
        # acceleration is carried to the next pass.
        v_carry, a_carry = np.zeros_like(x), np.zeros_like(x)
        for xk, vk, step, weight in ((x4, v4, h, h / 6), (x3, v3, h / 2, h / 3),
                                     (x2, v2, h / 2, h / 3)):
            xk_bar, vk_bar = np.zeros_like(x), weight * x_bar + v_carry
            accelerations_vjp(physical, xk, vk, weight * v_bar + a_carry, xk_bar, vk_bar, bar)
            out_x += xk_bar
            out_v += vk_bar
            v_carry, a_carry = step * xk_bar, step * vk_bar
        out_v += h / 6 * x_bar + v_carry           # stage 1 is y itself
        accelerations_vjp(physical, x, v, h / 6 * v_bar + a_carry, out_x, out_v, bar)
        return out_x, out_v


@register_adjoint
class ImplicitEulerAdjoint(Adjoint):
    """integrators/implicit_euler.py without contact: Newton iterations k = 0 .. K-1 from
    dv_0 = 0, each solving A(x_k) ddv_k = r_k on the free particles,
        x_0 = x, v_0 = v;  x_k = x + h (v + dv_k), v_k = v + dv_k  (k > 0)
        r_k = h (F(x_k, v_k) + m g - c v_k) - M dv_k  (+ h^2 dF/dx(x) v for k = 0)
    and x' = x + h (v + dv_K), v' = v + dv_K. By the implicit function theorem each iteration's
    adjoint is one solve with the same matrix (symmetric): lambda = A_k^-1 dv_bar, then lambda
    is the cotangent of r_k and -lambda ddv_k^T that of A_k. The last iteration's ddv is what
    the simulation computed (v' - v - dv_{K-1}); earlier ones are solved again here, tightly."""

    name = "implicit_euler"

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar):
        x, v = start
        iterations = self.integrator.newton_iterations
        estimates = newton_estimates(physical, h, x, v, end[1] - v, iterations,
                                     self.integrator.cg_tolerance)
        dv_bar = v_bar + h * x_bar
        x_bar, v_bar = x_bar.copy(), dv_bar.copy()
        for k in reversed(range(iterations)):
            dv_bar = system_vjp_iteration(physical, h, x, v, estimates[k], estimates[k + 1],
                                          k == 0, dv_bar, x_bar, v_bar, bar)
        return x_bar, v_bar
