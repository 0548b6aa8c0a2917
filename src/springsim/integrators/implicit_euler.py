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

``backward_euler_step`` is the method on one screen; the named calls around it are:
- the system: the Jacobians (and what is left out of them to keep the matrix symmetric positive
  definite) in implicit/jacobian.py, the block sparsity pattern, fixed by the springs and built
  once per model, in implicit/pattern.py, the filtered conjugate-gradient solve in implicit/cg.py
  (when nothing is constrained it conserves momentum to rounding, not just to its tolerance);
- constraints: pinned particles and terrain contact (normal velocity floors, friction inside
  the solve, restitution) in implicit/constraints.py;
- body-body contacts as stiff one-sided penalty springs of the solve, found for the pairs the
  step can bring together (collision/contact_sets/solve.py), linearized and kept or released
  between solves with the terrain contacts (collision/response/penalty.py), their friction
  applied when the solve is done (collision/response/solve_friction.py). Without them the solve
  pulls cloth into a ball faster than the post-step correction pushes it out;
- a self-colliding body's own pairs that a solve brings into contact join the contacts, and that
  Newton iteration is solved again (collision/pair_lists/own_pairs.py);
- a step that carries a surface through another (stiff as they are, penalty contacts give under
  a heavy enough load) is taken again in halves (``implicit_euler_step``, with the continuous
  check of collision/ccd/crossing_check.py).
After each step come the collision pipeline and the divergence check every integrator runs
(_steps.drive).
"""
import numpy as np

from .._jit import kernel
from ..clock import CALL_START, STAGE_TIME
from ..collision.ccd.crossing_check import MOST_HALVINGS, carried_through
from ..collision.contact_sets.solve import find_solve_contacts
from ..collision.pair_lists.own_pairs import (MOST_OWN_REDOS, any_self_collision, grown_own_pairs,
                                              own_pairs_touching)
from ..collision.pair_lists.solve_pairs import kept_surface_pairs
from ..collision.response.penalty import (linearize_contacts, newton_iterations_needed,
                                          update_active_contacts)
from ..collision.response.solve_friction import apply_contact_friction
from ..errors import SceneError, require
from ..forces import spring_forces
from ..implicit.coarse import no_coarse_space
from ..implicit.cg import (CGWork, FilteredSystem, conserve_momentum, contact_cg, mass_start,
                           system_multiply)
from ..implicit.constraints import (CAPPED, UNCHANGED, find_constraints,
                                    hold_all_constrained, hold_constrained,
                                    remembered_friction_in_cone, restore_impact_speeds,
                                    set_friction_damping, update_contacts)
from ..implicit.jacobian import add_stiffness_product, assemble_diagonal_and_terms, particle_mass
from ..implicit.pattern import build_solve_layout
from ..implicit.step_record import (no_record, note_end, note_part, note_pass, note_start,
                                    note_step, note_try)
from ..terms import add_external_jacobians, add_step_end_forces
from ..world import aim_pins, move_world, step_end, step_time
from .base import Integrator, KernelCall, register
from ._implicit_arrays import (ImplicitState, Scratch, Settings, Statistics, contact_slots,
                               copy_state, saved_state, workspace)
from ._steps import add_scaled, drive, drive_parts

MAX_CONTACT_UPDATES = 4   # re-solves after updating contacts and friction, per Newton iteration


# --- the method ---------------------------------------------------------------------------------

@kernel
def backward_euler_step(model, state, scratch, h, pairs):
    """One step of backward Euler, linearized as Baraff and Witkin (module doc): Newton
    iterations about the estimate (x_k, v_k) = (x + h (v + dv), v + dv), each solving
        A ddv = b,   A = M - h dF/dv - h^2 dF/dx (at x_k),
                     b = h F(x_k, v_k) - M dv   (+ h^2 dF/dx v in the first iteration)
    with the contacts as constraints and penalty springs of the solve. ``pairs``: the post-step
    pass's surface pair list at x, which a self-colliding body's own contacts come from; the
    list at the step's end is returned."""
    work, settings = scratch.work, scratch.settings
    # the constraints use the moving terrains where they are at the step's end (world.py)
    move_world(model, step_end(model, h))
    aim_pins(model, state.x, state.v, h)   # moving pins: to their paths' points at the end
    slots = contact_slots(state, work)
    contacts, own, pairs = find_step_contacts(model, state, scratch.solve_pairs, work, h, pairs)
    note_start(scratch.record, slots)
    start_estimate(state, work)
    needed = newton_iterations_needed(model, contacts, state.v, h, settings.newton_iterations)
    newton = redone = 0
    while newton < needed:
        assemble_system(model, scratch.layout, state, work, contacts, h, newton == 0)
        if newton == 0:   # the carried dampers it capped
            note_pass(scratch.record, slots)
        updates, solves = solve_with_contacts(model, scratch, state, contacts, h, newton == 0)
        grew = False
        if redone < MOST_OWN_REDOS and any_self_collision(model):
            grew, own, pairs = own_pairs_met(model, state, work, h, own, pairs, newton == 0)
        note_try(scratch.record, updates, solves, grew)
        if grew:   # solve this iteration again, from where it started, with them
            contacts = find_solve_contacts(model, state.x, state.v, h, scratch.solve_pairs, own)
            redone += 1
            continue
        update_estimate(state, work, work.ddv, h)
        newton += 1
    end_step(model, state, work, contacts, h)
    note_end(scratch.record, work.restored)
    return pairs


@kernel
def find_step_contacts(model, state, solve_pairs, work, h, pairs):
    """The step's constraints (pins, terrain contacts: into the state's memory and
    ``work.normal``) and its contact set; returns (the contact set, a self-colliding body's own
    pairs in contact at x, the post-step list at x)."""
    x, v = state.x, state.v
    find_constraints(model, x, v, h, contact_slots(state, work), work.lookups)
    own, pairs = own_pairs_touching(model, x, pairs)
    contacts = find_solve_contacts(model, x, v, h, solve_pairs, own)
    return contacts, own, pairs


@kernel
def start_estimate(state, work):
    """dv = 0: the first estimate is (x, v)."""
    work.dv[:] = 0.0
    work.x_k[:] = state.x
    work.v_k[:] = state.v


@kernel
def update_estimate(state, work, ddv, h):
    """dv += ddv; v_k = v + dv, x_k = x + h v_k."""
    add_scaled(work.dv, work.dv, 1.0, ddv)
    add_scaled(work.v_k, state.v, 1.0, work.dv)
    add_scaled(work.x_k, state.x, h, work.v_k)


@kernel
def assemble_system(model, layout, state, work, contacts, h, first):
    """A = M - h D - h^2 K at the estimate and b (``newton_rhs``), the contacts linearized into
    both, and ddv's start: the constrained components held, the friction carried from the last
    step put back inside the friction cone (first iteration only)."""
    x, v, memory = state
    pattern = layout.diagonal
    assemble_diagonal_and_terms(model, layout, work.x_k, 1.0, h, h * h, work.blocks, work.terms)
    newton_rhs(model, x, work.x_k, v, work.v_k, work.dv, h, first, work.force, work.columns,
               work.rhs)
    add_external_jacobians(model, layout, h, first, work.x_k, work.v_k, v, work.blocks, work.rhs)
    linearize_contacts(model, contacts, x, v, work.dv, h, work.rhs)
    # the particle loop reads its arrays as locals: a field of a named tuple read inside it
    # counts a reference up and down at every particle (six arrays: CHANGELOG, issue 56)
    blocks, rhs, normal, surface, dv, ddv = (work.blocks, work.rhs, work.normal, work.surface,
                                             work.dv, work.ddv)
    kind, floor, friction = memory.kind, memory.normal_floor, memory.friction_damping
    case = work.case
    slots = contact_slots(state, work)
    ddv[:] = 0.0
    for i in range(x.shape[0]):
        hold_constrained(i, kind, normal, floor, v, dv, ddv)
        damping = friction[i]   # the fresh matrix has none yet
        friction[i] = 0.0
        case[i] = UNCHANGED
        if first and damping != 0.0:   # carried from the last step: back inside the cone
            damping, capped = remembered_friction_in_cone(model, pattern, blocks, rhs, i, slots,
                                                          v, dv, ddv, damping)
            if capped:
                case[i] = CAPPED
        if damping != 0.0:   # (a call that would change nothing still counts its arrays)
            set_friction_damping(i, damping, pattern, blocks, rhs, normal, surface, v, dv,
                                 friction)


@kernel
def newton_rhs(model, x, x_k, v, v_k, dv, h, first, force, columns, rhs):
    """rhs = h F(x_k, v_k) - M dv_k, plus h^2 dF/dx v in the first iteration (dv_k = 0, x_k = x);
    a term that adds its force with its derivative (the wind) does so in assemble_system."""
    spring_forces(model, x_k, v_k, columns, force)
    for i in range(x.shape[0]):
        w = model.inv_mass[i]
        m = particle_mass(w)
        for c in range(3):
            external = (m * model.gravity[c] if w > 0.0 else 0.0) - model.drag[i] * v_k[i, c]
            rhs[i, c] = h * (force[i, c] + external) - m * dv[i, c]
    add_step_end_forces(model, x_k, v_k, np.full(1, h), rhs)   # the terms' (terms/)
    if first:
        add_stiffness_product(model, x, v, h * h, rhs)


@kernel
def solve_with_contacts(model, scratch, state, contacts, h, first):
    """Solve A ddv = b for ``work.ddv``, updating terrain contacts and friction
    (implicit/constraints.py) and the penalty contacts' active set (collision/response/penalty.py)
    between solves, MAX_CONTACT_UPDATES times at most. The first solve of a step starts along the
    last step's velocity change (cg.mass_start says why; the solution is the same to the
    tolerance); later Newton iterations solve for a correction, for which it is no guess.
    Returns (the update passes, the solves) it took; each pass's decisions go to the record."""
    x, v, memory = state
    work, settings, statistics = scratch.work, scratch.settings, scratch.statistics
    pattern, blocks, terms, rhs, dv, ddv = (scratch.layout.diagonal, work.blocks, work.terms,
                                           work.rhs, work.dv, work.ddv)
    kind, normal, normal_floor = memory.kind, work.normal, memory.normal_floor
    q = work.q
    coarse = scratch.layout.coarse
    system = FilteredSystem(pattern, blocks, terms, contacts, coarse, kind, normal)
    cg_work = CGWork(work.r, work.s, work.c, q)
    guess = memory.velocity_change if first else np.zeros((0, 3))
    mass_start(system, rhs, model.inv_mass, guess, ddv, cg_work)
    iterations, reference = contact_cg(system, rhs, ddv, settings.tolerance,
                                       settings.max_iterations, 0.0, cg_work)
    conserve_momentum(pattern, blocks, terms, contacts, rhs, kind, ddv, q)
    hold_all_constrained(kind, normal, normal_floor, v, dv, ddv)
    solves = 1
    slots = contact_slots(state, work)
    updates = 0
    for update in range(MAX_CONTACT_UPDATES):
        system_multiply(pattern, blocks, terms, contacts, ddv, q)
        add_scaled(work.reaction, q, -1.0, rhs)
        terrain_changed = update_contacts(model, pattern, blocks, rhs, x, v, dv, ddv, h, slots,
                                          work.reaction, work.lookups)
        note_pass(scratch.record, slots)
        updates += 1
        contacts_changed = update_active_contacts(contacts, h, ddv, rhs) > 0
        if not (terrain_changed or contacts_changed):
            break
        more, reference = contact_cg(system, rhs, ddv, settings.tolerance,
                                     settings.max_iterations, reference, cg_work)
        conserve_momentum(pattern, blocks, terms, contacts, rhs, kind, ddv, q)
        hold_all_constrained(kind, normal, normal_floor, v, dv, ddv)
        iterations += more
        solves += 1
    statistics.cg_iterations[0] += iterations
    statistics.linear_solves[0] += solves
    return updates, solves


@kernel
def own_pairs_met(model, state, work, h, own, pairs, first):
    """(whether a self-colliding body's own pairs in contact grew, them (OwnPairs), the list):
    ``own`` and those that the estimate after this solve, x + h (v_k + ddv), brings into
    contact (collision/pair_lists/own_pairs.py). The estimate is put back where the iteration
    started: (x, v) itself in the ``first`` (start_estimate), since at x + h v that iteration's
    forces and matrix, with its h^2 dF/dx v term, would count the step's motion twice."""
    add_scaled(work.v_k, work.v_k, 1.0, work.ddv)
    add_scaled(work.x_k, state.x, h, work.v_k)
    own, grew, pairs = grown_own_pairs(model, work.x_k, pairs, own)
    if first:
        start_estimate(state, work)
    else:
        add_scaled(work.v_k, state.v, 1.0, work.dv)
        add_scaled(work.x_k, state.x, h, work.v_k)
    return grew, own, pairs


@kernel
def end_step(model, state, work, contacts, h):
    """The penalty contacts' friction, then x = x_k, v = v_k; the velocity change is kept as
    the next step's guess, and impact speeds are restored for the restitution pass."""
    x, v, memory = state
    if apply_contact_friction(model, contacts, work.x_k, work.v_k, h):
        add_scaled(work.x_k, x, h, work.v_k)
    x[:] = work.x_k
    memory.velocity_change[:] = work.dv
    restore_impact_speeds(memory.kind, work.normal, memory.normal_floor, v, work.v_k,
                          work.restored)
    v[:] = work.v_k


# --- a step taken again in halves ---------------------------------------------------------------

@kernel
def implicit_euler_step(model, state, scratch, h, pairs):
    """backward_euler_step as the driver calls it (_steps.drive). A step that carries a surface
    through another is taken again from its start as two steps of half the size, each checked
    the same way (collision/ccd/crossing_check.py), down to 1 / 2^MOST_HALVINGS of the step; after
    a half that passes, steps grow back. Where even the shortest part crosses, the step is taken
    whole, as without the check."""
    note_step(scratch.record)
    if model.surface_triangles.shape[0] == 0:
        return backward_euler_step(model, state, scratch, h, pairs)
    step_start = step_time(model)   # each part's own start time, for the moving terrains
    start = scratch.start
    copy_state(start, state)
    saved = start   # where the part being taken started
    whole = 1 << MOST_HALVINGS
    done, size = 0, whole
    pairs_at_start = pairs
    while done < whole:
        # h * whole / whole is h exactly (powers of two): a step that is not cut is as before
        model.clock[STAGE_TIME] = step_start + h * done / whole
        stepped = backward_euler_step(model, state, scratch, h * size / whole, pairs)
        if carried_through(model, saved.x, state.x, stepped, scratch.solve_pairs):
            if size == 1:   # even the shortest part crossed: the step as it was
                copy_state(state, start)
                model.clock[STAGE_TIME] = step_start
                return backward_euler_step(model, state, scratch, h, pairs_at_start)
            copy_state(state, saved)   # back to the part's start, to go again in halves
            size //= 2
            scratch.statistics.halvings[0] += 1
            note_part(scratch.record)
            continue
        pairs = stepped
        done += size
        if done % (2 * size) == 0 and size < whole:
            size *= 2   # the halves went through: back to longer steps
        if done < whole:
            copy_state(scratch.part, state)
            saved = scratch.part
    # the pass after the step takes its end from the step's start
    model.clock[STAGE_TIME] = step_start
    return pairs


# --- the driver ---------------------------------------------------------------------------------

@kernel
def advance(model, layout, settings, state, solve_pairs, statistics, h, steps, pairs, record):
    """Take ``steps`` steps of ``state`` (an ImplicitState, changed in place); returns (steps
    done, first diverged particle or -1, the post-step pass's pair list: _steps.drive).
    ``solve_pairs`` is the solve's own surface pair list (a SolvePairList), changed in place;
    ``record`` (implicit/step_record.py) keeps the last step's decisions where it has room."""
    work = workspace(layout, state.x, model.terrain_epsilon.shape[0])
    scratch = Scratch(layout, settings, work, solve_pairs, statistics, saved_state(state),
                      saved_state(state), record)
    return drive(implicit_euler_step, model, state, scratch, h, steps, pairs)


@register
class ImplicitEuler(Integrator):
    """Options: ``newton_iterations`` (default 1: the Baraff-Witkin step), ``cg_tolerance``
    (relative residual of each linear solve, against the larger of its starting residual and
    its right-hand side, default 1e-5), ``cg_max_iterations`` and ``preconditioner``
    (``"two_level"``, the default: block Jacobi with a coarse space of aggregates,
    implicit/coarse.py; or ``"block_jacobi"`` alone)."""

    name = "implicit_euler"
    adjoint = "springsim.gradients.adjoints:ImplicitEulerAdjoint"
    order = 1
    summary = "backward Euler, one linearized solve per step (Baraff-Witkin): large stable steps"
    SECTION = "implicit"   # the scene's table of its options
    OPTIONS = ("newton_iterations", "cg_tolerance", "cg_max_iterations", "preconditioner")
    PRECONDITIONERS = ("two_level", "block_jacobi")

    def __init__(self, newton_iterations=1, cg_tolerance=1e-5, cg_max_iterations=500,
                 preconditioner="two_level", **others):
        for key, value in others.items():
            raise SceneError(f"integrator option {key}", value,
                             f"'{self.name}' takes only " + ", ".join(self.OPTIONS))
        require(_is_whole(newton_iterations) and newton_iterations >= 1,
                "implicit.newton_iterations", newton_iterations, "must be a whole number >= 1")
        require(_is_number(cg_tolerance) and 0 < cg_tolerance < 1, "implicit.cg_tolerance",
                cg_tolerance, "must be a relative residual in (0, 1)")
        require(_is_whole(cg_max_iterations) and cg_max_iterations >= 1,
                "implicit.cg_max_iterations", cg_max_iterations, "must be a whole number >= 1")
        require(preconditioner in self.PRECONDITIONERS, "implicit.preconditioner",
                preconditioner, "must be " + " or ".join(f'"{p}"' for p in self.PRECONDITIONERS))
        self.newton_iterations = int(newton_iterations)
        self.preconditioner = preconditioner
        self.cg_tolerance = float(cg_tolerance)
        self.cg_max_iterations = int(cg_max_iterations)
        self.statistics = Statistics.zeros()   # running totals, for diagnostics
        self.record = None   # a StepRecord the steps write their decisions to (``recording``)

    def pattern(self, model):
        """What the solve needs of the model (pattern.SolveLayout), built on first use and kept
        for as long as the model (a Simulation keeps one model)."""
        kept = self.model_cache(model)
        if "layout" not in kept:
            kept["layout"] = build_solve_layout(model.arrays, model.spring_kind)
        return kept["layout"]

    def solve_layout(self, model):
        """``pattern`` with the coarse space that the ``preconditioner`` option asks for."""
        layout = self.pattern(model)
        if self.preconditioner == "two_level":
            return layout
        return layout._replace(coarse=no_coarse_space(model.particle_count))

    def advance(self, model, state, dt, steps, threads=1):
        # serial: threads are for the explicit methods' large models (integrators.KernelIntegrator)
        state.solve_pairs = _solve_pairs(state)
        # the steps take their times from it (world.py)
        model.arrays.clock[CALL_START] = state.time
        call = self.kernel_call(model, state, dt, steps)
        done, particle, state.pairs = call.kernel(*call.arguments)
        return int(done), int(particle)

    def kernel_call(self, model, state, dt, steps) -> KernelCall:
        """The call ``advance`` makes."""
        settings = Settings(self.newton_iterations, self.cg_tolerance, self.cg_max_iterations)
        return KernelCall(advance, (
            model.arrays, self.solve_layout(model), settings,
            ImplicitState(state.positions, state.velocities, state.contacts), _solve_pairs(state),
            self.statistics, float(dt), int(steps), state.pairs,
            no_record() if self.record is None else self.record))

    def variants(self, model, state, dt):
        # one kernel: no threaded twin, and both preconditioners' layouts have the same types
        return {"serial": self.kernel_call(model, state, dt, 0)}

    def parts(self, model, state, dt):
        return drive_parts(model, state, dt)


def _solve_pairs(state):
    """The state's surface pair list for the solve, or a new one where it has none that fits."""
    if state.solve_pairs is None or state.solve_pairs.found_at.shape != state.positions.shape:
        return kept_surface_pairs(state.positions)
    return state.solve_pairs


def _is_whole(value) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float, np.number)) and not isinstance(value, bool) \
        and np.isfinite(value)
