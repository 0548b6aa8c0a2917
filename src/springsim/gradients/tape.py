"""The forward run the gradient is of, and the backward pass over it, with checkpoints.

The forward run is the simulation's own (the compiled integrator, one step a call), so the loss
is of exactly the motion ``springsim run`` computes. The backward pass needs each step's start
and end states. When all of them fit in ``memory_limit`` bytes they are kept; otherwise the full
state (contact memory and pair lists included: state.State.copy) is kept every ``stride`` steps,
and each stretch between two kept states is run again, bit for bit, before its adjoint, so that
at most one stretch of states is held at a time. ``Tape.stored_bytes`` says what was held.
"""
import math
from dataclasses import dataclass

import numpy as np

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


def plan_stride(steps: int, particles: int, memory_limit: int) -> int:
    """1 when every (x, v) fits in memory_limit, else the stride that keeps about
    sqrt(steps) checkpoints and a stretch of as many states, each within half the limit."""
    per_state = particles * 6 * 8
    if (steps + 1) * per_state <= memory_limit:
        return 1
    stride = max(2, math.ceil(math.sqrt(steps)))
    while (steps // stride + 1) * per_state > memory_limit / 2 and stride < steps:
        stride *= 2
    return min(stride, max(steps, 1))


def keeps_memory(simulation) -> bool:
    """Whether the adjoint needs each step's contact memory: backward Euler's terrain contacts
    carry their friction dampers from step to step (implicit_contact.py)."""
    return simulation.integrator.name == "implicit_euler" and bool(simulation.model.terrains)


def snapshot(state, memory: bool):
    """(x, v) of a state, or (x, v, (kind, terrain, friction dampers)) with its memory."""
    x, v = state.positions.copy(), state.velocities.copy()
    if not memory:
        return x, v
    contacts = state.contacts
    return x, v, (contacts.kind.copy(), contacts.terrain.copy(),
                  contacts.friction_damping.copy())


def record(simulation, steps: int, frame_steps: np.ndarray, memory_limit: int):
    """Run ``steps`` steps; returns (the positions at frame_steps (F, P, 3), the Tape)."""
    particles = simulation.model.particle_count
    memory = keeps_memory(simulation)
    stride = plan_stride(steps, particles, memory_limit)
    wanted = {int(s): k for k, s in enumerate(frame_steps)}
    frames = np.empty((len(frame_steps), particles, 3))
    states, stored = [], 0
    times = np.empty(steps)   # the forward's own clock: start + n h rounds otherwise
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
            simulation.step(1)
    return frames, Tape(steps, stride, states, times,
                        stored + (stride > 1) * stride * particles * 48)


def stretch(simulation, tape: Tape, first: int):
    """The (x, v) of steps first .. first + stride (at most tape.steps), run again from the
    checkpoint at ``first``: the same bits as the forward run (one step a call, as it was)."""
    simulation.state = tape.states[first // tape.stride].copy()
    last = min(first + tape.stride, tape.steps)
    states = []
    memory = keeps_memory(simulation)
    for n in range(first, last + 1):
        states.append(snapshot(simulation.state, memory))
        if n < last:
            simulation.step(1)
    return states


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
    states, first = (tape.states, 0) if stride == 1 else (None, None)
    for n in range(tape.steps, 0, -1):
        for g in inject.get(n, ()):
            x_bar += g
        if stride > 1 and (states is None or n - 1 < first):
            first = ((n - 1) // stride) * stride
            states = stretch(simulation, tape, first)
        start, end = states[n - 1 - first], states[n - first]
        physical.clock[STEP_START] = tape.times[n - 1]
        if check is not None:
            check(n - 1, start)
        x_bar, v_bar = adjoint.step_vjp(physical, h, start, end, x_bar, v_bar, bar)
    for g in inject.get(0, ()):
        x_bar += g
    return x_bar, v_bar, bar
