"""The forward run the gradient is of, and the backward pass over it, with checkpoints.

The forward run is the simulation's own (the compiled integrator, one step a call, or a stretch
of steps a call where the method keeps its stages, below), so the loss is of exactly the motion
``springsim run`` computes. The backward pass needs each step's start
and end states. When all of them fit in ``memory_limit`` bytes they are kept; otherwise the full
state (contact memory and pair lists included: state.State.copy) is kept every ``stride`` steps,
and each stretch between two kept states is run again, bit for bit, before its adjoint, so that
at most one stretch of states is held at a time. ``Tape.stored_bytes`` says what was held.

Where the method can (rk4 on a model that runs the serial kernel: Simulation.keeps_stages),
the compiled steps themselves keep each step's start and its stages' accelerations, a stretch
of steps (all of them, or ``stride``) a call, so that the adjoint takes the accelerations
instead of evaluating the forces again (adjoints.RK4Adjoint), and the recording costs no call a
step.
"""
import math
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..implicit.step_record import copied, grown, new_record, overflowed
from .physics import Cotangents
from .clock import STEP_START

DEFAULT_MEMORY_LIMIT = 1 << 30   # bytes of stored states (the bar: a 10 s run < 2 GB)


@dataclass
class Tape:
    """What the forward run kept: every state, or full states every ``stride`` steps."""

    steps: int
    stride: int
    states: list          # [(x, v)] per step when stride == 1, else full State every stride steps
    times: np.ndarray     # (steps,) s, each step's start as the forward run had it
    stored_bytes: int = 0
    kept: np.ndarray | None = None   # (steps, stages, P, 3): each step's stages' accelerations
    starts: np.ndarray | None = None   # (steps + 1, 2, P, 3): the states, where kept so


def plan_stride(steps: int, particles: int, memory_limit: int, stages: int = 0) -> int:
    """1 when every (x, v) (and the ``stages`` accelerations of each step) fits in memory_limit,
    else the stride that keeps about sqrt(steps) checkpoints and a stretch of as many states,
    each within half the limit."""
    per_state = particles * (6 + 3 * stages) * 8
    if (steps + 1) * per_state <= memory_limit:
        return 1
    stride = max(2, math.ceil(math.sqrt(steps)))
    while (steps // stride + 1) * per_state > memory_limit / 2 and stride < steps:
        stride *= 2
    return min(stride, max(steps, 1))


def keeps_memory(simulation) -> bool:
    """Whether the adjoint needs each step's contact memory and record: backward Euler's terrain
    contacts carry their friction dampers from step to step, and the replay reads the step's
    decisions (implicit_replay.py)."""
    return simulation.integrator.name == "implicit_euler" and bool(simulation.model.terrains)


class Memory(NamedTuple):
    """Backward Euler's contact memory at a step's start (state.ContactMemory's part the
    adjoint reads)."""

    kind: np.ndarray               # (P,) the last step's constraints
    terrain: np.ndarray            # (P,) their terrains
    friction_damping: np.ndarray   # (P,) the dampers carried into this step


class Kept(NamedTuple):
    """A step's start with backward Euler's contact memory, and what the step decided."""

    x: np.ndarray
    v: np.ndarray
    memory: Memory
    record: object   # implicit/step_record.StepRecord, the step's (None for the last state)


def snapshot(state, memory: bool):
    """(x, v) of a state, or Kept with its memory (the step's record added after the step)."""
    x, v = state.positions.copy(), state.velocities.copy()
    if not memory:
        return x, v
    contacts = state.contacts
    return Kept(x, v, Memory(contacts.kind.copy(), contacts.terrain.copy(),
                             contacts.friction_damping.copy()), None)


def recorded_step(simulation, states):
    """One step; where the integrator keeps a record of it (backward Euler with terrains:
    ImplicitEuler.record), the record goes with the step's start, ``states[-1]`` (if any). A
    step that wanted more room than the record had is taken again from its start with more."""
    integrator = simulation.integrator
    record = getattr(integrator, "record", None)
    if record is None:
        simulation.step(1)
        return
    before = simulation.state.copy()
    simulation.step(1)
    while overflowed(integrator.record):
        integrator.record = grown(integrator.record)
        simulation.state = before.copy()
        simulation.step(1)
    if states and isinstance(states[-1], Kept):
        states[-1] = states[-1]._replace(record=copied(integrator.record))


def record_bytes(state) -> int:
    """The bytes of a kept step's record (0 for anything else)."""
    if not isinstance(state, Kept) or state.record is None:
        return 0
    return sum(array.nbytes for array in state.record)


@contextmanager
def recording(simulation):
    """Within it, backward Euler's steps keep their decisions for the adjoint (where it has
    terrains: keeps_memory)."""
    if not keeps_memory(simulation):
        yield
        return
    simulation.integrator.record = new_record(simulation.model.particle_count, 16, 4)
    try:
        yield
    finally:
        simulation.integrator.record = None


def record(simulation, steps: int, frame_steps: np.ndarray, memory_limit: int):
    """Run ``steps`` steps; returns (the positions at frame_steps (F, P, 3), the Tape)."""
    particles = simulation.model.particle_count
    memory = keeps_memory(simulation)
    stages = simulation.keeps_stages()
    stride = plan_stride(steps, particles, memory_limit, stages)
    wanted = {int(s): k for k, s in enumerate(frame_steps)}
    frames = np.empty((len(frame_steps), particles, 3))
    if stages:
        return frames, record_keeping(simulation, steps, stride, stages, wanted, frames)
    states, stored = [], 0
    times = np.empty(steps)   # the forward's own clock: start + n h rounds otherwise
    with recording(simulation) if stride == 1 else nullcontext():
        for n in range(steps + 1):
            state = simulation.state
            if n in wanted:
                frames[wanted[n]] = state.positions
            if stride == 1:
                states.append(snapshot(state, memory))
                stored += particles * (65 if memory else 48)
            elif n % stride == 0 and n < steps:
                states.append(state.copy())
                stored += particles * 48
            if n < steps:
                times[n] = state.time
                recorded_step(simulation, states if stride == 1 else None)
    stored += sum(record_bytes(state) for state in states)
    return frames, Tape(steps, stride, states, times,
                        stored + (stride > 1) * stride * particles * 48)


def record_keeping(simulation, steps, stride, stages, wanted, frames) -> Tape:
    """record's run where the method keeps its stages: a stretch of ``stride`` steps a call,
    each step's start and stages' accelerations kept by the compiled step itself; the frames
    ``wanted`` (step: row of frames) filled in."""
    particles = simulation.model.particle_count
    states, times, stored = [], np.empty(steps), 0
    kept = None
    calls = steps if stride == 1 else stride   # every step in one call, or checkpoints
    for first in range(0, steps, calls):
        if stride > 1:
            states.append(simulation.state.copy())
            stored += particles * 48
        run = keeping_run(simulation, min(calls, steps - first), stages)
        starts, kept = run.starts, run.kept
        times[first:first + len(kept)] = run.times
        for n in range(first, first + len(starts)):
            if n in wanted:
                frames[wanted[n]] = starts[n - first, 0]
        if stride == 1:
            states = [(start[0], start[1]) for start in starts]
            stored += starts.nbytes + kept.nbytes
    stretch_bytes = stride * particles * (48 + stages * 24)
    return Tape(steps, stride, states, times, stored + (stride > 1) * stretch_bytes,
                kept if stride == 1 else None, starts if stride == 1 else None)


class KeepingRun(NamedTuple):
    """``count`` steps run in one call, keeping each step's start and stages."""

    starts: np.ndarray   # (count + 1, 2, P, 3): each step's (x, v) at its start, and the end
    kept: np.ndarray     # (count, stages, P, 3): each step's stages' accelerations
    times: np.ndarray    # (count,) s: each step's start, as the call's clock has it


def keeping_run(simulation, count: int, stages: int) -> KeepingRun:
    """Run ``count`` steps in one call (Simulation.step_keeping). The first start is the state
    before the call, as a step a call would have recorded it (the call places the moving pins
    on their paths first, the same for later steps as the step before left them)."""
    state = simulation.state
    particles = simulation.model.particle_count
    starts = np.empty((count + 1, 2, particles, 3))
    kept = np.empty((count, stages, particles, 3))
    begin = state.time
    first = state.positions.copy(), state.velocities.copy()
    simulation.step_keeping(kept, starts[:count])
    starts[0, 0], starts[0, 1] = first
    starts[count, 0], starts[count, 1] = simulation.positions, simulation.velocities
    # start_step's clock: the call's start plus n h
    return KeepingRun(starts, kept, begin + np.arange(count) * simulation.dt)


def stretch(simulation, tape: Tape, first: int):
    """The (x, v) of steps first .. first + stride (at most tape.steps), run again from the
    checkpoint at ``first``: the same bits as the forward run (calls as it made them), and each
    step's stages' accelerations and the states as one array where the method keeps them (else
    None, None)."""
    simulation.state = tape.states[first // tape.stride].copy()
    last = min(first + tape.stride, tape.steps)
    stages = simulation.keeps_stages()
    if stages:
        run = keeping_run(simulation, last - first, stages)
        return [(start[0], start[1]) for start in run.starts], run.kept, run.starts
    states = []
    memory = keeps_memory(simulation)
    with recording(simulation):
        for n in range(first, last + 1):
            states.append(snapshot(simulation.state, memory))
            if n < last:
                recorded_step(simulation, states)
    return states, None, None


def backward(simulation, adjoint, physical, tape: Tape, frame_steps, frame_bars, check=None):
    """Run the adjoint from the last step to the first: returns (x0_bar, v0_bar, Cotangents).
    ``frame_bars`` (F, P, 3): the loss's gradient with respect to the positions at each frame;
    ``check(step, (x, v))``, if given, sees every step's start first (checks.contact_check)."""
    h = simulation.dt
    particles = simulation.model.particle_count
    inject = {}
    for k, s in enumerate(frame_steps):
        inject.setdefault(int(s), []).append(frame_bars[k])
    x_bar, v_bar = np.zeros((particles, 3)), np.zeros((particles, 3))
    bar = Cotangents.zeros(physical)
    stride = tape.stride
    # an adjoint may look over a stretch's states at once (RK4Adjoint.look_over: its far test)
    look = getattr(adjoint, "look_over", lambda *_: None)
    states, kept, first = (tape.states, tape.kept, 0) if stride == 1 else (None, None, None)
    if stride == 1:
        look(physical, h, states, tape.starts)
    for n in range(tape.steps, 0, -1):
        for g in inject.get(n, ()):
            x_bar += g
        if stride > 1 and (states is None or n - 1 < first):
            first = ((n - 1) // stride) * stride
            states, kept, starts = stretch(simulation, tape, first)
            look(physical, h, states, starts)
        start, end = states[n - 1 - first], states[n - first]
        physical.clock[STEP_START] = tape.times[n - 1]
        if check is not None:
            check(n - 1, start)
        stages = None if kept is None else kept[n - 1 - first]
        x_bar, v_bar = adjoint.step_vjp(physical, h, start, end, x_bar, v_bar, bar, stages)
    for g in inject.get(0, ()):
        x_bar += g
    return x_bar, v_bar, bar
