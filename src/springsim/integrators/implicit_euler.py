"""Backward (implicit) Euler, linearized as Baraff and Witkin (1998) do. First order, and stable
at steps far beyond the explicit methods' limits.

Backward Euler takes the new velocity's forces: with dv = v' - v,
    M dv = h F(x + h (v + dv), v + dv),    x' = x + h v'.
Linearizing F about the start of the step gives one linear system for dv,
    (M - h dF/dv - h^2 dF/dx) dv = h (F(x, v) + h dF/dx v),
solved by Jacobi-preconditioned conjugate gradients. Each further Newton iteration
(``newton_iterations``, default 1) relinearizes about the latest estimate
(x_k, v_k) = (x + h (v + dv_k), v + dv_k) and solves
    (M - h dF/dv - h^2 dF/dx)(x_k) ddv = h F(x_k, v_k) - M dv_k.

``springsim.implicit`` holds the parts: the Jacobians (and what is left out of them to keep the
matrix symmetric positive definite) in jacobian.py, the block sparsity pattern, fixed by the
springs and built once per model, in pattern.py, the filtered solve in cg.py, and pinned
particles and terrain contact (normal velocity floors, friction inside the solve, restitution)
as constraints of the solve in constraints.py, and ball-particle contact as stiff one-sided
penalty springs of the solve in ball_contact.py: found each step for the pairs the step can bring
together, added to the matrix-vector products of the solve (the pattern stays fixed), and kept
or released between solves with the terrain contacts. Without them the solve would pull cloth
into a ball faster than the post-step correction pushes it out, and at large steps a dropped or
thrown ball would pass through the cloth. When nothing is constrained, each solve ends with a
correction along the rigid translations that makes it conserve momentum to rounding, not just to
the solve's tolerance (cg.py). A step that carries a surface through another (stiff as they
are, penalty contacts give under a heavy enough load) is taken again in halves
(implicit/halving.py). After each step the impact and collision passes and the divergence check
every integrator runs (``_steps.finish_step``).
"""
import numpy as np

from .._jit import kernel
from ..errors import require, SceneError
from ..forces import force_columns, spring_forces
from ..implicit.ball_contact import (find_solve_contacts, linearize_contacts,
                                     newton_iterations_needed, update_active_contacts)
from ..implicit.cg import conserve_momentum, contact_cg, mass_start, system_multiply
from ..implicit.contact_friction import apply_contact_friction
from ..implicit.constraints import (find_constraints, hold_all_constrained, hold_constrained,
                                    remembered_friction_in_cone, restore_impact_speeds,
                                    set_friction_damping, update_contacts)
from ..implicit.halving import MOST_HALVINGS, carried_through
from ..implicit.own_contact import MOST_OWN_REDOS, any_self_collision, grown_own_pairs, \
    own_pairs_touching
from ..implicit.jacobian import add_stiffness_product, assemble_diagonal_and_terms, particle_mass
from ..implicit.pattern import build_solve_layout
from ..implicit.spring_terms import spring_terms_like
from ..implicit.surface_contact import kept_surface_pairs
from . import Integrator, register
from ._steps import add_scaled, copy_positions, drive

MAX_CONTACT_UPDATES = 4   # re-solves after updating contacts and friction, per Newton iteration


@kernel
def newton_rhs(model, x, x_k, v, v_k, dv, h, first, force, columns, rhs):
    """rhs = h F(x_k, v_k) - M dv_k, plus h^2 dF/dx v in the first iteration (dv_k = 0, x_k = x)."""
    spring_forces(model, x_k, v_k, columns, force)
    for i in range(x.shape[0]):
        w = model.inv_mass[i]
        m = particle_mass(w)
        for c in range(3):
            external = (m * model.gravity[c] if w > 0.0 else 0.0) - model.drag[i] * v_k[i, c]
            rhs[i, c] = h * (force[i, c] + external) - m * dv[i, c]
    if first:
        add_stiffness_product(model, x, v, h * h, rhs)


@kernel
def solve_with_contacts(model, pattern, blocks, terms, contacts, rhs, x, v, dv, h, kind, normal,
                        terrain, normal_floor, friction_damping, guess, ddv, tolerance,
                        max_iterations, reaction, r, s, c, q):
    """Solve for ddv, updating terrain contacts and friction (implicit.constraints) and
    the ball and surface contacts (implicit.ball_contact) between solves; the first solve starts
    along ``guess`` (cg.mass_start). Returns the conjugate-gradient iterations taken and the
    number of solves."""
    mass_start(pattern, blocks, terms, contacts, rhs, kind, normal, model.inv_mass, guess, ddv, r,
               s, q)
    iterations, reference = contact_cg(pattern, blocks, terms, contacts, rhs, kind, normal, ddv,
                                       tolerance, max_iterations, 0.0, r, s, c, q)
    conserve_momentum(pattern, blocks, terms, contacts, rhs, kind, ddv, q)
    hold_all_constrained(kind, normal, normal_floor, v, dv, ddv)
    solves = 1
    for update in range(MAX_CONTACT_UPDATES):
        system_multiply(pattern, blocks, terms, contacts, ddv, q)
        add_scaled(reaction, q, -1.0, rhs)
        terrain_changed = update_contacts(model, pattern, blocks, rhs, x, v, dv, ddv, h, kind,
                                          normal, terrain, normal_floor, friction_damping,
                                          reaction)
        contacts_changed = update_active_contacts(contacts, h, ddv, rhs) > 0
        if not (terrain_changed or contacts_changed):
            break
        more, reference = contact_cg(pattern, blocks, terms, contacts, rhs, kind, normal, ddv,
                                     tolerance, max_iterations, reference, r, s, c, q)
        conserve_momentum(pattern, blocks, terms, contacts, rhs, kind, ddv, q)
        hold_all_constrained(kind, normal, normal_floor, v, dv, ddv)
        iterations += more
        solves += 1
    return iterations, solves


@kernel
def backward_euler_step(model, layout, x, v, h, newton_iterations, tolerance, max_iterations,
                        work, kind, terrain, normal_floor, friction_damping, last_change,
                        statistics, pairs):
    """One step; adds its conjugate-gradient iterations and linear solves to statistics.
    ``pairs``: the post-step pass's surface pair list at x, whose pairs of one body in contact,
    at x and at each Newton estimate, the solve takes as contacts (implicit/own_contact.py).

    The first solve starts along the last step's velocity change (last_change, kept in the
    state; cg.mass_start says why). The solution is the same to the CG tolerance. Later Newton
    iterations solve for a correction, for which it is no guess: they start along none."""
    blocks, force, rhs, dv, ddv, x_k, v_k, normal, reaction, r, s, c, q, columns, terms, kept = work
    pattern = layout.diagonal
    find_constraints(model, x, v, h, kind, normal, terrain, normal_floor, friction_damping)
    own_points, own_edges, pairs = own_pairs_touching(model, x, pairs)
    contacts = find_solve_contacts(model, x, v, h, kept, own_points, own_edges)
    dv[:] = 0.0
    x_k[:] = x
    v_k[:] = v
    no_guess = np.zeros((0, 3))
    needed = newton_iterations_needed(model, contacts, v, h, newton_iterations)
    newton = redone = 0
    while newton < needed:
        guess = last_change if newton == 0 else no_guess
        assemble_diagonal_and_terms(model, pattern, x_k, 1.0, h, h * h, blocks, terms)
        newton_rhs(model, x, x_k, v, v_k, dv, h, newton == 0, force, columns, rhs)
        linearize_contacts(model, contacts, x, v, dv, h, rhs)
        ddv[:] = 0.0
        for i in range(x.shape[0]):
            hold_constrained(i, kind, normal, normal_floor, v, dv, ddv)
            damping = friction_damping[i]   # the fresh matrix has none yet
            friction_damping[i] = 0.0
            if newton == 0:   # carried from the last step: back inside the friction cone
                damping = remembered_friction_in_cone(model, pattern, blocks, rhs, i, kind,
                                                      terrain, normal, v, dv, ddv, damping)
            set_friction_damping(i, damping, pattern, blocks, rhs, normal, v, dv,
                                 friction_damping)
        iterations, solves = solve_with_contacts(model, pattern, blocks, terms, contacts, rhs, x,
                                                 v, dv, h, kind, normal, terrain, normal_floor,
                                                 friction_damping, guess, ddv, tolerance,
                                                 max_iterations, reaction, r, s, c, q)
        statistics[0] += iterations
        statistics[1] += solves
        if redone < MOST_OWN_REDOS and any_self_collision(model):
            # the own pairs this solve brings into contact (own_contact.py): where there are
            # new ones, this iteration is solved again with them, from where it started
            add_scaled(v_k, v_k, 1.0, ddv)
            add_scaled(x_k, x, h, v_k)
            own_points, own_edges, grew, pairs = grown_own_pairs(model, x_k, pairs, own_points,
                                                                 own_edges)
            add_scaled(v_k, v, 1.0, dv)
            add_scaled(x_k, x, h, v_k)
            if grew:
                contacts = find_solve_contacts(model, x, v, h, kept, own_points, own_edges)
                redone += 1
                continue
        add_scaled(dv, dv, 1.0, ddv)
        add_scaled(v_k, v, 1.0, dv)
        add_scaled(x_k, x, h, v_k)
        newton += 1
    if apply_contact_friction(model, contacts, x_k, v_k, h):   # the penalty contacts' friction
        add_scaled(x_k, x, h, v_k)
    x[:] = x_k
    last_change[:] = dv
    restore_impact_speeds(kind, normal, normal_floor, v, v_k)   # for restitution to reflect
    v[:] = v_k
    return pairs


@kernel
def workspace(layout, x, kept):
    """The arrays a step works in: the matrix's diagonal blocks, twelve vectors shaped like x,
    the force columns, the springs' terms of the matrix and the kept surface pair list
    ``kept`` (implicit.surface_contact.kept_surface_pairs)."""
    blocks = np.empty((layout.diagonal.column.shape[0], 3, 3))
    vectors = [np.zeros_like(x) for _ in range(12)]
    return (blocks, vectors[0], vectors[1], vectors[2], vectors[3], vectors[4], vectors[5],
            vectors[6], vectors[7], vectors[8], vectors[9], vectors[10], vectors[11],
            force_columns(x), spring_terms_like(layout.runs, layout.run_entries,
                                                layout.loose_pairs, x), kept)


@kernel
def implicit_euler_step(model, state, scratch, h, pairs):
    """backward_euler_step as the driver calls it: the state carries the contacts
    (state.ContactMemory), the scratch the pattern, the settings, the work arrays, the
    statistics and room for the state at the start of the step and of a part of it; ``pairs`` is
    the post-step pass's list at the step's start. A step that carries a surface through another
    is taken again in halves (implicit/halving.py); statistics[2] counts the times a step or a
    part was cut in half."""
    if model.surface_triangles.shape[0] == 0:
        return state_step(model, state, scratch, h, pairs)
    kept, statistics = scratch[4][15], scratch[5]   # the solve's pair list (workspace)
    start, part = scratch[6], scratch[7]   # room for the step's start, and a part's
    copy_state(start, state)
    saved = start   # where the part being taken started
    whole = 1 << MOST_HALVINGS
    done, size = 0, whole
    pairs_at_start = pairs
    while done < whole:
        # h * whole / whole is h exactly (powers of two): a step that is not cut is as before
        stepped = state_step(model, state, scratch, h * size / whole, pairs)
        if carried_through(model, saved[0], state[0], stepped, kept):
            if size == 1:   # even the shortest part crossed: the step as it was (halving.py)
                copy_state(state, start)
                return state_step(model, state, scratch, h, pairs_at_start)
            copy_state(state, saved)   # back to the part's start, to go again in halves
            size //= 2
            statistics[2] += 1
            continue
        pairs = stepped
        done += size
        if done % (2 * size) == 0 and size < whole:
            size *= 2   # the halves went through: back to longer steps
        if done < whole:
            copy_state(part, state)
            saved = part
    return pairs


@kernel
def saved_state(state):
    """A copy of the implicit step's state (the tuple implicit_euler_step takes)."""
    x, v, kind, terrain, normal_floor, friction_damping, last_change = state
    return (x.copy(), v.copy(), kind.copy(), terrain.copy(), normal_floor.copy(),
            friction_damping.copy(), last_change.copy())


@kernel
def copy_state(out, state):
    """Copy the implicit step's ``state`` into ``out`` (one like it: saved_state), in place."""
    copy_positions(out[0], state[0])
    copy_positions(out[1], state[1])
    copy_positions(out[6], state[6])
    for i in range(state[2].shape[0]):
        out[2][i] = state[2][i]
        out[3][i] = state[3][i]
        out[4][i] = state[4][i]
        out[5][i] = state[5][i]


@kernel
def state_step(model, state, scratch, h, pairs):
    """One backward_euler_step of ``state`` with ``scratch`` (implicit_euler_step)."""
    x, v, kind, terrain, normal_floor, friction_damping, last_change = state
    layout, newton_iterations, tolerance, max_iterations, work, statistics, _, _ = scratch
    return backward_euler_step(model, layout, x, v, h, newton_iterations, tolerance,
                               max_iterations, work, kind, terrain, normal_floor,
                               friction_damping, last_change, statistics, pairs)


@kernel
def advance(model, layout, x, v, h, steps, newton_iterations, tolerance, max_iterations,
            kind, terrain, normal_floor, friction_damping, last_change, statistics, pairs,
            kept):
    """Take ``steps`` steps; returns (steps done, first diverged particle or -1, the
    post-step pass's pair list: _steps.drive). ``kept`` is the solve's own surface pair list
    (implicit.surface_contact.kept_surface_pairs), changed in place.

    kind, terrain, normal_floor and friction_damping carry the contacts from one step (and one
    call) to the next, last_change the velocity change; statistics[0], [1] and [2] count the
    conjugate-gradient iterations, the linear solves and the halvings (implicit_euler_step)."""
    state = (x, v, kind, terrain, normal_floor, friction_damping, last_change)
    # the last entries: room for a step's start and a part's, which a step taken again in
    # halves goes back to (implicit_euler_step)
    scratch = (layout, newton_iterations, tolerance, max_iterations, workspace(layout, x, kept),
               statistics, saved_state(state), saved_state(state))
    return drive(implicit_euler_step, model, state, scratch, h, steps, pairs)


@register
class ImplicitEuler(Integrator):
    """Options: ``newton_iterations`` (default 1: the Baraff-Witkin step), ``cg_tolerance``
    (relative residual of each linear solve, against the larger of its starting residual and
    its right-hand side, default 1e-5) and ``cg_max_iterations``."""

    name = "implicit_euler"
    order = 1
    summary = "backward Euler, one linearized solve per step (Baraff-Witkin): large stable steps"
    OPTIONS = ("newton_iterations", "cg_tolerance", "cg_max_iterations")

    def __init__(self, newton_iterations=1, cg_tolerance=1e-5, cg_max_iterations=500, **others):
        for key, value in others.items():
            raise SceneError(f"integrator option {key}", value,
                             f"'{self.name}' takes only " + ", ".join(self.OPTIONS))
        require(_is_whole(newton_iterations) and newton_iterations >= 1, "implicit.newton_iterations",
                newton_iterations, "must be a whole number >= 1")
        require(_is_number(cg_tolerance) and 0 < cg_tolerance < 1, "implicit.cg_tolerance",
                cg_tolerance, "must be a relative residual in (0, 1)")
        require(_is_whole(cg_max_iterations) and cg_max_iterations >= 1, "implicit.cg_max_iterations",
                cg_max_iterations, "must be a whole number >= 1")
        self.newton_iterations = int(newton_iterations)
        self.cg_tolerance = float(cg_tolerance)
        self.cg_max_iterations = int(cg_max_iterations)
        # running totals, for diagnostics: conjugate-gradient iterations, linear solves, times a
        # step or a part of one was cut in half (implicit/halving.py)
        self.statistics = np.zeros(3, np.int64)

    def solve_pair_list(self, model, x):
        """The solve's surface pair list (implicit/surface_contact.py), kept from call to call
        for ``model`` like the post-step pass's (Integrator.pair_list): each step checks that it
        still holds before using it. Stepping one step a call (the viewer at 1/60 s) searched
        it afresh every call: cloth-drape took 20.5 to 21.2 ms a step that way, now 13.6 to
        13.8, against 9.9 to 11.1 in one call (benchmarks/step_per_call.py)."""
        kept = self.model_cache(model)
        if "solve pairs" not in kept:
            kept["solve pairs"] = kept_surface_pairs(x)
        return kept["solve pairs"]

    def pattern(self, model):
        """What the solve needs of the model (pattern.SolveLayout), built on first use and kept
        for as long as the model (a Simulation keeps one model)."""
        kept = self.model_cache(model)
        if "layout" not in kept:
            kept["layout"] = build_solve_layout(model.arrays)
        return kept["layout"]

    def advance(self, model, state, dt, steps, threads=1):
        # serial: threads are for the explicit methods' large models (integrators.KernelIntegrator)
        # the contacts carried between steps live in the state (state.ContactMemory)
        done, particle, pairs = advance(model.arrays, self.pattern(model), state.positions,
                                        state.velocities, float(dt), int(steps),
                                        self.newton_iterations, self.cg_tolerance,
                                        self.cg_max_iterations, *state.contacts,
                                        self.statistics, self.pair_list(model),
                                        self.solve_pair_list(model, state.positions))
        self.keep_pair_list(model, pairs)
        return int(done), int(particle)


def _is_whole(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.number)) and not isinstance(value, bool) \
        and np.isfinite(value)
