"""The arrays backward Euler's step works on (integrators/implicit_euler.py): what it advances,
its settings and statistics, the work arrays a call allocates once, and room for the state at a
step's start and a part's."""
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from ..forces import force_columns
from ..implicit.constraints import ContactSlots
from ..implicit.spring_terms import spring_terms_like
from ..implicit.step_record import StepRecord
from ..state import ContactMemory
from ._steps import copy_positions


class ImplicitState(NamedTuple):
    """What a backward Euler step advances, in place (state.State's arrays)."""

    x: np.ndarray          # (P, 3) m: positions
    v: np.ndarray          # (P, 3) m/s: velocities
    memory: ContactMemory  # terrain contacts and the last velocity change


class Settings(NamedTuple):
    """The integrator's options (ImplicitEuler)."""

    newton_iterations: int   # linearized solves a step asks for (contacts may ask for more)
    tolerance: float         # each conjugate-gradient solve's relative residual
    max_iterations: int      # the most conjugate-gradient iterations a solve takes


class Statistics(NamedTuple):
    """Running totals, for diagnostics (each a (1,) int64 array, added to in place)."""

    cg_iterations: np.ndarray   # conjugate-gradient iterations
    linear_solves: np.ndarray   # linear solves (several a Newton iteration when contacts change)
    halvings: np.ndarray        # times a step or a part of one was cut in half

    @classmethod
    def zeros(cls) -> "Statistics":
        return cls(np.zeros(1, np.int64), np.zeros(1, np.int64), np.zeros(1, np.int64))


class Workspace(NamedTuple):
    """The arrays a step works in, allocated once a call (``workspace``)."""

    blocks: np.ndarray     # (B, 3, 3): the stored blocks of A = M - h D - h^2 K
    terms: tuple           # the springs' terms of A that are not stored (implicit/spring_terms.py)
    force: np.ndarray      # (P, 3) N: the spring forces at the estimate
    columns: np.ndarray    # the force kernel's columns (forces.force_columns)
    rhs: np.ndarray        # (P, 3) N s: b, the right-hand side
    dv: np.ndarray         # (P, 3) m/s: the step's velocity change so far
    ddv: np.ndarray        # (P, 3) m/s: this Newton iteration's correction to it
    x_k: np.ndarray        # (P, 3) m: the estimate's positions x + h (v + dv)
    v_k: np.ndarray        # (P, 3) m/s: the estimate's velocities v + dv
    normal: np.ndarray     # (P, 3): each constrained particle's terrain normal
    surface: np.ndarray    # (P, 3) m/s: the velocity of its terrain's surface there (world.py)
    reaction: np.ndarray   # (P, 3) N s: A ddv - b, the constraints' reaction impulses
    r: np.ndarray          # (P, 3): conjugate gradients' residual
    s: np.ndarray          # (P, 3): its search direction
    c: np.ndarray          # (P, 3): its preconditioned residual
    q: np.ndarray          # (P, 3): its products A s
    lookups: np.ndarray    # (P, T, 4): each terrain's phi and normal at x (constraints.py)
    floor_case: np.ndarray  # (P,) int8: how each contact's floor came about (constraints.py)
    case: np.ndarray       # (P,) int16: what the last pass decided for each particle
    restored: np.ndarray   # (P,) bool: the contacts whose impact speed the end gave back


class Scratch(NamedTuple):
    """What ``implicit_euler_step`` takes besides the state: the model's solve layout, the
    settings, the work arrays and room for the state at a step's start and a part's."""

    layout: tuple                # implicit/pattern.SolveLayout
    settings: Settings
    work: Workspace
    solve_pairs: tuple           # collision/pair_lists.SolvePairList, kept between steps
    statistics: Statistics
    start: ImplicitState         # room for the state at the step's start
    part: ImplicitState          # room for the state at the start of a part of the step
    record: StepRecord           # what the step decided, where the gradient asks (else empty)


@kernel
def workspace(layout, x, terrain_count):
    """The arrays a step works in (Workspace), for a model of ``terrain_count`` terrains."""
    blocks = np.empty((layout.diagonal.column.shape[0], 3, 3))
    vectors = [np.zeros_like(x) for _ in range(13)]
    terms = spring_terms_like(layout.runs, layout.run_entries, layout.loose_pairs, x)
    count = x.shape[0]
    return Workspace(blocks, terms, vectors[0], force_columns(x), vectors[1], vectors[2],
                     vectors[3], vectors[4], vectors[5], vectors[6], vectors[7], vectors[8],
                     vectors[9], vectors[10], vectors[11], vectors[12],
                     np.empty((count, terrain_count, 4)), np.zeros(count, np.int8),
                     np.zeros(count, np.int16), np.zeros(count, np.bool_))


@kernel
def contact_slots(state, work):
    """Where the step writes its constraints: the state's memory and the work arrays."""
    memory = state.memory
    return ContactSlots(memory.kind, memory.terrain, work.normal, work.surface,
                        memory.normal_floor, memory.friction_damping, work.floor_case, work.case)


@kernel
def saved_state(state):
    """Room for a copy of ``state`` (an ImplicitState)."""
    memory = state.memory
    return ImplicitState(state.x.copy(), state.v.copy(),
                         ContactMemory(memory.kind.copy(), memory.terrain.copy(),
                                       memory.normal_floor.copy(), memory.friction_damping.copy(),
                                       memory.velocity_change.copy()))


@kernel
def copy_state(out, state):
    """Copy ``state`` into ``out`` (one like it: saved_state), in place."""
    copy_positions(out.x, state.x)
    copy_positions(out.v, state.v)
    copy_positions(out.memory.velocity_change, state.memory.velocity_change)
    memory, saved = state.memory, out.memory
    for i in range(memory.kind.shape[0]):
        saved.kind[i] = memory.kind[i]
        saved.terrain[i] = memory.terrain[i]
        saved.normal_floor[i] = memory.normal_floor[i]
        saved.friction_damping[i] = memory.friction_damping[i]
