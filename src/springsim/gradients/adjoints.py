"""The adjoint of each integrator's step: given the cotangents of the state after a step, the
cotangents of the state before it, and the parameters' share added to ``bar``.

An open set, as the integrators are: one class per method, which the method names beside its
step (``Integrator.adjoint``: "module:Class"; ``adjoint_class`` reads it). Each mirrors its method's step (integrators/) line by line in
reverse, so the gradient is of the arithmetic the simulation did, not of the differential
equation it approximates. ``step_vjp(physical, h, start, end, x_bar, v_bar, bar, kept)`` takes
the recorded states at the step's start and end, (x, v) each, and what the tape kept of the step
besides (its stages' accelerations, tape.py, or None), and returns (x_bar, v_bar) at its
start, the step's start time in ``physical.clock`` (clock.py); each force evaluation sets its
own time there first, as the forward's stages move the world. The explicit methods' terrain
contact (still planes, spheres, bowls and meshes: contact.py) is in their force evaluations
and in the impact pass after each step (``_steps.collide``), which ``explicit_step`` runs again
in NumPy from the step's start to know what it did; the hard attachments are held just before
that pass (attachments.py), and the body-body contacts answered after it (body_contact.py), the
same way.
"""
import importlib
from typing import NamedTuple

import numpy as np

from ..spring_runs import run_layout
from .attachments import hold, hold_vjp, holds
from .body_contact import check_replayed, far_from_bodies, respond
from .body_contact_adjoint import respond_vjp
from .contact import (contact_accelerations, contact_accelerations_vjp, far_from_terrains,
                      far_steps, impacts, impacts_vjp)
from .kernels import Springs
from .run_kernels import ROWS, Particles, StepBars, entry_table, rk4_step_vjp
from .physics import (accelerations, accelerations_vjp, step_accelerations,
                      step_accelerations_vjp)
from .implicit_bodies import (PenaltyStep, adjoint as bodies_adjoint, check_solved,
                              replay as bodies_replay, touches_bodies)
from .implicit_contact import adjoint as contact_adjoint
from .implicit_replay import replay, touched_terrains
from .solve import ForwardSolver, newton_estimates, system_vjp_iteration
from .clock import at_time
from .pins import aim, place, release
from .terms import any_acts

# how far (relative to the fastest speed) an explicit step's NumPy replay may end from the
# forward's kernels where body contacts acted: rounding, not another contact set
REPLAYED = 1e-7


def adjoint_class(integrator) -> type | None:
    """The adjoint class that ``integrator`` (an Integrator) names beside its step (its
    ``adjoint``: "module:Class"), or None where it names none."""
    if not integrator.adjoint:
        return None
    module, name = integrator.adjoint.split(":")
    return getattr(importlib.import_module(module), name)


def differentiable() -> list[str]:
    """The integrators that name an adjoint."""
    from ..integrators import base

    return [name for name, cls in base.REGISTRY.items() if cls.adjoint]


class Adjoint:
    """The adjoint of one integrator's step (module doc), for the integrator and model given."""

    def __init__(self, integrator, model):
        self.integrator = integrator
        self.model = model

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar, kept=None):
        raise NotImplementedError   # every registered adjoint overrides this


class ExplicitAdjoint(Adjoint):
    """An explicit method: its update (``update``, with what each force evaluation's contact
    did), then the impact pass; the adjoint goes back through both."""

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar, kept=None):
        at_time(physical, 0.0)
        x, v = place(physical, *start)
        x_new, v_new, stages = self.update(physical, h, x, v)
        x_bar, v_bar = x_bar.copy(), v_bar.copy()
        held = found = response = None
        at_time(physical, h)   # the world where the step ends (_steps.collide)
        if x_new is not None:   # the pins on paths are placed first
            x_new, v_new = place(physical, x_new, v_new)
        if holds(physical):
            x_new, v_new, held = hold(physical, x_new, v_new)
        if len(physical.friction):
            x_new, v_new, found = impacts(physical, x_new, v_new)
        if physical.bodies.collide:
            x_new, v_new, response = respond(physical, x_new, v_new, x)
            if response is not None:
                check_replayed((x_new, v_new), end, h, REPLAYED * max(1.0, float(np.abs(
                    end[1]).max())), "touch each other in a way the gradient's replay of "
                    "the step does not (a point carried through a face by more than its "
                    "thickness): try a smaller dt")
        start_bar = 0.0
        if response is not None:
            x_bar, v_bar, start_bar = respond_vjp(physical, response, x_bar, v_bar, bar)
        if found is not None:
            x_bar, v_bar = impacts_vjp(physical, found, x_bar, v_bar, bar)
        if held is not None:
            x_bar, v_bar = hold_vjp(physical, held, x_bar, v_bar, bar)
        release(physical, x_bar, v_bar)   # the pins on paths were put on them after the update
        x_bar, v_bar = self.update_vjp(physical, h, x, v, stages, x_bar, v_bar, bar)
        x_bar += start_bar   # the body contacts' stencils read the step's start (their sides)
        release(physical, x_bar, v_bar)   # and before it
        return x_bar, v_bar


class SymplecticEulerAdjoint(ExplicitAdjoint):
    """v' = v + h a(x, v), x' = x + h v'."""

    def update(self, physical, h, x, v):
        at_time(physical, 0.0)
        a, touches = step_accelerations(physical, x, v, h)
        v_new = v + h * a
        return x + h * v_new, v_new, touches

    def update_vjp(self, physical, h, x, v, touches, x_bar, v_bar, bar):
        at_time(physical, 0.0)
        v_new_bar = v_bar + h * x_bar
        a_bar = h * v_new_bar
        x_bar, v_bar = x_bar.copy(), v_new_bar.copy()
        step_accelerations_vjp(physical, x, v, h, touches, a_bar, x_bar, v_bar, bar)
        return x_bar, v_bar


class ExplicitEulerAdjoint(ExplicitAdjoint):
    """x' = x + h v, v' = v + h a(x, v)."""

    def update(self, physical, h, x, v):
        at_time(physical, 0.0)
        a, touches = step_accelerations(physical, x, v, h)
        return x + h * v, v + h * a, touches

    def update_vjp(self, physical, h, x, v, touches, x_bar, v_bar, bar):
        at_time(physical, 0.0)
        a_bar = h * v_bar
        x_bar, v_bar = x_bar.copy(), v_bar + h * x_bar
        step_accelerations_vjp(physical, x, v, h, touches, a_bar, x_bar, v_bar, bar)
        return x_bar, v_bar


class Runs(NamedTuple):
    """What RK4's step adjoint kernel (run_kernels.rk4_step_vjp) takes of the parameters, found
    once for each Physical: the springs in runs and their entry table, the loose springs'
    parameters, the particles' (inv_mass, drag, gravity), and whether the kernel can take the
    steps at all (``plain``: no wind, soft pins or attachments, whose forces it leaves out)."""

    physical: object
    layout: object
    table: np.ndarray
    loose: Springs
    particles: Particles
    plain: bool

    @classmethod
    def of(cls, physical):
        layout = run_layout(physical.a, physical.b)
        loose = layout.loose
        # hard bindings are no term but are held between the stages: not plain either
        plain = not (any_acts(physical) or len(physical.attachment_nodes))
        return cls(physical, layout, entry_table(layout, physical.ks, physical.kd, physical.rest),
                   Springs(physical.a[loose], physical.b[loose], physical.ks[loose],
                           physical.kd[loose], physical.rest[loose]),
                   Particles(physical.inv_mass, physical.drag, physical.gravity), plain)


class MidpointAdjoint(ExplicitAdjoint):
    """integrators/midpoint.py: (x_m, v_m) = (x, v) + h/2 (v, a(x, v)), then
    x' = x + h v_m, v' = v + h a(x_m, v_m), the second evaluation half way through the step."""

    def update(self, physical, h, x, v):
        at_time(physical, 0.0)
        a, first = step_accelerations(physical, x, v, h)
        x_m, v_m = x + h / 2 * v, v + h / 2 * a
        at_time(physical, h / 2)
        a_m, second = step_accelerations(physical, x_m, v_m, h)
        return x + h * v_m, v + h * a_m, (x_m, v_m, first, second)

    def update_vjp(self, physical, h, x, v, stages, x_bar, v_bar, bar):
        x_m, v_m, first, second = stages
        out_x, out_v = x_bar.copy(), v_bar.copy()
        xm_bar, vm_bar = np.zeros_like(x), h * x_bar
        at_time(physical, h / 2)
        step_accelerations_vjp(physical, x_m, v_m, h, second, h * v_bar, xm_bar, vm_bar, bar)
        out_x += xm_bar
        out_v += h / 2 * xm_bar + vm_bar
        at_time(physical, 0.0)
        step_accelerations_vjp(physical, x, v, h, first, h / 2 * vm_bar, out_x, out_v, bar)
        return out_x, out_v


class PredictReevaluateAdjoint(ExplicitAdjoint):
    """integrators/predict_reevaluate.py: (x_p, v_p) = (x, v) + h (v, a(x, v)), then
    x' = x + h v_p, v' = v + h a_p, a_p the forces' at (x_p, v_p) at the step's end with the
    terrains' contact stopping v, not v_p (that module says why)."""

    def update(self, physical, h, x, v):
        at_time(physical, 0.0)
        a, first = step_accelerations(physical, x, v, h)
        x_p, v_p = x + h * v, v + h * a
        at_time(physical, h)
        a_p, second = accelerations(physical, x_p, v_p), []
        if len(physical.friction):
            a_p, second = contact_accelerations(physical, x_p, v, h, a_p)
        return x + h * v_p, v + h * a_p, (x_p, v_p, first, second)

    def update_vjp(self, physical, h, x, v, stages, x_bar, v_bar, bar):
        x_p, v_p, first, second = stages
        out_x, out_v = x_bar.copy(), v_bar.copy()
        xp_bar, vp_bar = np.zeros_like(x), h * x_bar
        a_bar = h * v_bar
        at_time(physical, h)
        if second:   # the contact read (x_p, v)
            a_bar = contact_accelerations_vjp(physical, h, second, a_bar, xp_bar, out_v, bar)
        accelerations_vjp(physical, x_p, v_p, a_bar, xp_bar, vp_bar, bar)
        out_x += xp_bar
        out_v += h * xp_bar + vp_bar
        at_time(physical, 0.0)
        step_accelerations_vjp(physical, x, v, h, first, h * vp_bar, out_x, out_v, bar)
        return out_x, out_v


class RK4Adjoint(ExplicitAdjoint):
    """integrators/rk4.py: stages (x_k, v_k), slopes (v_k, a(x_k, v_k)),
        x' = x + h/6 (v + 2 v2 + 2 v3 + v4),  v' = v + h/6 (a1 + 2 a2 + 2 a3 + a4),
    with (x2, v2) = y + h/2 k1, (x3, v3) = y + h/2 k2, (x4, v4) = y + h k3. Every stage's
    contact is at the whole step h, as the forward's."""

    work = columns = None   # the kernel's work arrays, sized to the model
    runs = None   # Runs of the physical parameters last seen
    reach = None   # contact.Reach of the last step's start (the next one back's end)

    ahead = None   # {id(x): (x, far)}: the far test of each step of the stretch gone back
                   # over, by its start's positions (kept alive with it, so no id is reused)

    def runs_of(self, physical) -> Runs:
        if self.runs is None or self.runs.physical is not physical:
            self.runs = Runs.of(physical)
            self.reach = None
        return self.runs

    def look_over(self, physical, h, states, starts):
        """Take the far test of every step of a stretch at once where it can (``starts``: its
        states as one array, from a keeping run; contact.far_steps)."""
        far = None
        if starts is not None and self.runs_of(physical).plain:
            far = far_steps(physical, h, starts)
        self.ahead = {} if far is None else {id(states[k][0]): (states[k][0], bool(f))
                                             for k, f in enumerate(far)}

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar, kept=None):
        self.runs_of(physical)
        far = False
        if self.runs.plain:   # the step's start is the step before's end: its Reach is kept
            looked_at, far = (self.ahead or {}).get(id(start[0]), (None, None))
            if looked_at is not start[0]:
                far, self.reach = far_from_terrains(physical, h, start, end, self.reach)
        if not far or not far_from_bodies(physical, h, start, end):
            return super().step_vjp(physical, h, start, end, x_bar, v_bar, bar)
        if kept is None:   # the kernel evaluates the stages' forces again
            kept = np.empty((0, len(start[0]), 3))
        at_time(physical, 0.0)
        x, v = place(physical, start[0], start[1])
        if self.work is None or self.work.shape[1] != len(x):
            self.work = np.empty((17, len(x), 3))
            self.columns = np.empty((ROWS, len(x)))
        runs = self.runs
        x_bar, v_bar = x_bar.copy(), v_bar.copy()
        release(physical, x_bar, v_bar)
        rk4_step_vjp(runs.layout, runs.table, runs.loose, runs.particles, h, (x, v),
                     (x_bar, v_bar),
                     StepBars(bar.ks, bar.kd, bar.rest, bar.mass, bar.drag, bar.gravity),
                     self.work, self.columns, kept)
        release(physical, x_bar, v_bar)
        return x_bar, v_bar

    def update(self, physical, h, x, v):
        at_time(physical, 0.0)
        a1, t1 = step_accelerations(physical, x, v, h)
        x2, v2 = x + h / 2 * v, v + h / 2 * a1
        at_time(physical, h / 2)
        a2, t2 = step_accelerations(physical, x2, v2, h)
        x3, v3 = x + h / 2 * v2, v + h / 2 * a2
        a3, t3 = step_accelerations(physical, x3, v3, h)
        x4, v4 = x + h * v3, v + h * a3
        at_time(physical, h)
        a4, t4 = step_accelerations(physical, x4, v4, h)
        stages = ((x2, v2, t2), (x3, v3, t3), (x4, v4, t4), t1)
        if not (len(physical.friction) or holds(physical) or physical.bodies.collide):
            # the end state is not needed
            return None, None, stages
        # the forward's arithmetic order (rk4.first_stage .. last_stage)
        dx = v + 2.0 * v2 + 2.0 * v3
        dv = a1 + 2.0 * a2 + 2.0 * a3
        return x + h / 6 * (dx + v4), v + h / 6 * (dv + a4), stages

    def update_vjp(self, physical, h, x, v, stages, x_bar, v_bar, bar):
        (x2, v2, t2), (x3, v3, t3), (x4, v4, t4), t1 = stages
        out_x, out_v = x_bar.copy(), v_bar.copy()   # y' = y + ...
        # Backwards through the stages: stage k's state is y + step (v_{k-1}, a_{k-1}) and its
        # slope (v_k, a_k) enters y' with ``weight``; what flows into stage k-1's velocity and
        # acceleration is carried to the next pass.
        v_carry, a_carry = np.zeros_like(x), np.zeros_like(x)
        for xk, vk, tk, step, weight in ((x4, v4, t4, h, h / 6), (x3, v3, t3, h / 2, h / 3),
                                         (x2, v2, t2, h / 2, h / 3)):
            at_time(physical, step)   # stage 4 is at the step's end, 2 and 3 half way
            xk_bar, vk_bar = np.zeros_like(x), weight * x_bar + v_carry
            step_accelerations_vjp(physical, xk, vk, h, tk, weight * v_bar + a_carry, xk_bar,
                                   vk_bar, bar)
            out_x += xk_bar
            out_v += vk_bar
            v_carry, a_carry = step * xk_bar, step * vk_bar
        out_v += h / 6 * x_bar + v_carry           # stage 1 is y itself
        at_time(physical, 0.0)
        step_accelerations_vjp(physical, x, v, h, t1, h / 6 * v_bar + a_carry, out_x, out_v, bar)
        return out_x, out_v


class ImplicitEulerAdjoint(Adjoint):
    """integrators/implicit_euler.py without contact: Newton iterations k = 0 .. K-1 from
    dv_0 = 0, each solving A(x_k) ddv_k = r_k on the free particles,
        x_0 = x, v_0 = v;  x_k = x + h (v + dv_k), v_k = v + dv_k  (k > 0)
        r_k = h (F(x_k, v_k) + m g - c v_k) - M dv_k  (+ h^2 dF/dx(x) v for k = 0)
    and x' = x + h (v + dv_K), v' = v + dv_K. By the implicit function theorem each iteration's
    adjoint is one solve with the same matrix (symmetric): lambda = A_k^-1 dv_bar, then lambda
    is the cotangent of r_k and -lambda ddv_k^T that of A_k. The last iteration's ddv is what
    the simulation computed (v' - v - dv_{K-1}); earlier ones are solved again here, tightly."""

    carried_bar = None   # the cotangent of the friction dampers carried into the step after
    solver = None        # solve.ForwardSolver, made on first use

    def step_vjp(self, physical, h, start, end, x_bar, v_bar, bar, kept=None):
        iterations = self.integrator.newton_iterations
        at_time(physical, 0.0)
        x, v = place(physical, start[0], start[1])
        at_time(physical, h)   # the air and the paths at the step's end, as the forward's
        x_bar, v_bar = x_bar.copy(), v_bar.copy()
        release(physical, x_bar, v_bar)   # the pins on paths, put on them after the step
        v = aim(physical, x, v, h)
        bodies = touches_bodies(physical, h, start, end)
        if len(start) == 4 and touched_terrains(physical, start.record):
            carried = np.zeros(len(x)) if self.carried_bar is None else self.carried_bar
            penalty = PenaltyStep(physical, h, x, v, iterations) if bodies else None
            x_out, v_out, _, replayed = replay(physical, h, x, v, start.memory, start.record,
                                               penalty)
            if bodies:
                check_solved((x_out, v_out), end, h, self.integrator.cg_tolerance)
            x_bar, v_bar, self.carried_bar = contact_adjoint(physical, h, x, v, replayed, x_bar,
                                                             v_bar, carried, bar)
        elif bodies:
            self.carried_bar = None
            x_bar, v_bar = self.bodies_vjp(physical, h, x, v, end, x_bar, v_bar, bar)
        else:
            self.carried_bar = None   # a step without contacts leaves no damper behind
            estimates = None
            if holds(physical):   # the step's end before the hold: its last solve again
                estimates = self.estimates(physical, h, x, v, None)
                v_end = v + estimates[-1]
                _, _, held = hold(physical, *place(physical, x + h * v_end, v_end))
                x_bar, v_bar = hold_vjp(physical, held, x_bar, v_bar, bar)
            x_bar, v_bar = self.newton_vjp(physical, h, x, v, end, x_bar, v_bar, bar,
                                           estimates)
        release(physical, x_bar, v_bar)   # placed at the step's start, then aimed
        return x_bar, v_bar

    def bodies_vjp(self, physical, h, x, v, end, x_bar, v_bar, bar):
        """A step with body-body contact (implicit_bodies.py): replayed with the forward's
        solver, checked against the recorded end, then differentiated."""
        if self.solver is None:
            self.solver = ForwardSolver(self.model, self.integrator)
        x_out, v_out, replayed = bodies_replay(physical, self.integrator, self.solver, h, x, v)
        check_solved((x_out, v_out), end, h, self.integrator.cg_tolerance)
        return bodies_adjoint(physical, h, x, v, replayed, x_bar, v_bar, bar, self.solver)

    def estimates(self, physical, h, x, v, dv_end):
        """solve.newton_estimates with the forward's own solver (made on first use)."""
        if self.solver is None:
            self.solver = ForwardSolver(self.model, self.integrator)
        return newton_estimates(physical, h, x, v, dv_end, self.integrator.newton_iterations,
                                self.solver)

    def newton_vjp(self, physical, h, x, v, end, x_bar, v_bar, bar, estimates=None):
        """The Newton iterations backwards (class doc), from the step's end to (x, v);
        ``estimates`` if they are known already."""
        iterations = self.integrator.newton_iterations
        if estimates is None:
            # the solve holds every pinned particle's velocity: dv is zero there
            dv_end = np.where(physical.free[:, None], end[1] - v, 0.0)
            estimates = self.estimates(physical, h, x, v, dv_end)
        dv_bar = v_bar + h * x_bar
        x_bar, v_bar = x_bar.copy(), dv_bar.copy()
        for k in reversed(range(iterations)):
            dv_bar = system_vjp_iteration(physical, h, x, v, estimates[k], estimates[k + 1],
                                          k == 0, dv_bar, x_bar, v_bar, bar, self.solver)
        return x_bar, v_bar
