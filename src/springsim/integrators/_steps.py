"""What every integrator shares: the one driver loop, and the small kernels of a step.

Each method is a step function ``step(model, state, scratch, h, pairs)`` that advances ``state``
(a NamedTuple whose first fields are the positions x and velocities v, changed in place: Motion
for the explicit methods) by one step h, using the work arrays in ``scratch``; ``pairs`` is the
surface pair list at the step's start (collision/pair_lists/keeping.py), which the explicit
methods leave to the pass after the step and backward Euler's solve also takes a body's own
pairs from. It returns the list for that pass: ``pairs``, or one renewed within the step.

``drive`` takes whole steps with it, each read as the pipeline it is:

    step -> collide (terrain impacts, body-body contact: collision/pipeline.py) -> check divergence

Before each step the clock (model.clock) is set to the step's time and the moving terrains moved
there (world.py); a stage that evaluates forces at another time moves them to it first.

Each integrator file binds its step in a two-line cached kernel, ``advance = drive(its_step,
model, Motion(x, v), its_scratch(x), h, steps, pairs)``, where ``pairs`` is the state's pair list
(state.State.pairs), returned for the next call.

Why ``drive`` is inlined rather than a kernel that takes the step as an argument: Numba types a
function passed as an argument by the identity of its dispatcher object, which is new in every
process, so a cached kernel with a function argument never finds its cache (it recompiles every
run); and a kernel that calls it with a fixed function is refused caching ("uses dynamic
globals"). Inlined into each method's own ``advance``, the step function is a constant of that
kernel, which caches as any other.

The serial ``advance`` calls the force evaluation and ``collide`` as kernels, each compiled once
for every method; the threaded ``parallel_advance`` takes ``threaded(step)`` and
``threaded_drive``, which inline them instead, since a kernel's loops run on threads only in the
kernel compiled with them.
"""
import types
from typing import NamedTuple

import numpy as np
from numba import prange

from .._jit import inline_kernel, kernel
from ..attachments import hold_attachments
from ..collision.pair_lists.keeping import pairs_at, start_surface_pairs
from ..collision.pipeline import resolve_contacts
from ..collision.response.terrain import resolve_terrain_impacts
from ..forces import accelerations, force_columns, threaded_accelerations
from ..world import move_world, place_pins, start_step, step_end
from .calls import KernelCall


class Motion(NamedTuple):
    """The state an explicit method advances."""

    x: np.ndarray   # (P, 3) m: positions, changed in place
    v: np.ndarray   # (P, 3) m/s: velocities, changed in place


SPEED_SQUARED_LIMIT = 1e6  # the course framework's "System Unstable" threshold, m^2/s^2


@inline_kernel
def drive(step, model, state, scratch, h, steps, pairs):
    """Take up to ``steps`` steps; returns (steps done, first diverged particle or -1, the
    surface pair list for the next call). ``pairs`` is the list the last call left (or none):
    kept while it still holds (pair_lists/keeping.pairs_at) for the positions after each step,
    however they came about."""
    x, v = state.x, state.v
    pairs = pairs_now(model, x, pairs)
    start = step_start(model, x)
    for done in range(steps):
        start_step(model, x, v, done, h)   # the world (terrains, pins) at the step's start
        copy_positions(start, x)
        pairs = step(model, state, scratch, h, pairs)
        pairs = collide(model, x, v, start, pairs, h)
        particle = first_diverged(x, v)
        if particle >= 0:
            return done + 1, particle, pairs
    return steps, -1, pairs


@kernel
def pairs_now(model, x, pairs):
    """``pairs`` where it still holds at x, else renewed there, as the pass after each step
    does (pipeline.resolve_contacts); a fresh list where there is none yet (or it
    was found for another number of particles). Why check here too: between calls the state
    may have been replaced (``Simulation.state = ...``, ``load_state``, edited positions), and
    backward Euler's solve takes a body's own pairs from this list before the post-step pass
    would notice. Renewed, not searched afresh: a list that the last step kept (the spread no
    longer holds, the motion was rigid by pieces) is kept again, so stepping one step a call
    gives what one call of many gives (a list for one step alone, no_pairs_this_step, is
    proven again: the same list, at the cost of a proof)."""
    if model.surface_triangles.shape[0] == 0:
        return pairs
    if pairs.found_at.shape[0] != x.shape[0]:
        return start_surface_pairs(model, x)
    return pairs_at(model, x, pairs)


@kernel
def step_start(model, x):
    """Room for the positions at the start of a step, which surface contact reads (none
    without it: ball contacts do not read them)."""
    if model.surface_triangles.shape[0] == 0:
        return np.empty((0, 3))
    return np.empty_like(x)


@kernel
def copy_positions(out, x):
    """out[:] = x, where out has room for them (a plain loop: in a kernel, a slice assignment
    costs a few times more, every step)."""
    for i in range(out.shape[0]):
        for c in range(3):
            out[i, c] = x[i, c]


# An explicit method's scratch is a plain tuple, made and taken apart in its own file: Numba's
# parallel array analysis cannot unpack a NamedTuple in the threaded kernels (parallel_advance).

@kernel
def one_stage_scratch(x):
    """The scratch of a method with one force evaluation: the accelerations and the force
    columns."""
    return np.empty_like(x), force_columns(x)


@kernel
def two_stage_scratch(x):
    """The scratch of a method with two: the accelerations, the stage's positions and
    velocities, and the force columns."""
    return np.empty_like(x), np.empty_like(x), np.empty_like(x), force_columns(x)


@inline_kernel
def add_scaled(out, x, alpha, y):
    """out = x + alpha * y, elementwise, with no temporary array."""
    for i in prange(x.shape[0]):
        for c in range(3):
            out[i, c] = x[i, c] + alpha * y[i, c]


DIVERGENCE_CHUNKS = 64   # fixed pieces of the divergence check, whatever the thread count


@inline_kernel
def first_diverged(x, v):
    """Index of the first particle with a non-finite state or |v|^2 above the limit, else -1.
    Each of DIVERGENCE_CHUNKS pieces finds its own first (on threads in a threaded kernel); the
    first piece that found one has the answer, the same for any number of threads."""
    count = v.shape[0]
    size = (count + DIVERGENCE_CHUNKS - 1) // DIVERGENCE_CHUNKS
    found = np.full(DIVERGENCE_CHUNKS, -1, np.int64)
    for chunk in prange(DIVERGENCE_CHUNKS):
        for i in range(chunk * size, min(count, (chunk + 1) * size)):
            if is_diverged(v[i, 0], v[i, 1], v[i, 2], x[i, 0] + x[i, 1] + x[i, 2]):
                found[chunk] = i
                break
    for chunk in range(DIVERGENCE_CHUNKS):
        if found[chunk] >= 0:
            return found[chunk]
    return -1


@kernel
def is_diverged(vx, vy, vz, position):
    """A non-finite state or |v|^2 above the limit (position: the sum of the coordinates)."""
    speed_squared = vx * vx + vy * vy + vz * vz
    # written so that NaN fails the test: every comparison with NaN is False
    return not (speed_squared <= SPEED_SQUARED_LIMIT and np.abs(position) < np.inf)


@kernel
def collide(model, x, v, start, pairs, h):
    """Everything contact does after the integrator's update (with the moving pins on their
    paths and the hard attachments held first): terrain impacts (with the
    terrains where they are at the step's end), then body-body contact (balls and surfaces in
    one set, from the step's ``start`` positions and the surface pair list:
    collision/pipeline.py). Returns the pair list for the next step."""
    move_world(model, step_end(model, h))
    place_pins(model, x, v)   # moving pins exactly on their paths at the step's end
    hold_attachments(model, x, v)   # hard attachments on their triangles (attachments.py)
    resolve_terrain_impacts(model, x, v)
    return resolve_contacts(model, x, v, start, pairs)


# The kernels a step calls whose loops run on threads in the threaded kernel: there they must be
# inlined (parallel_advance), while the serial kernels share one compiled copy of each.
THREADED = {"accelerations": threaded_accelerations,
            "collide": inline_kernel(collide.py_func)}


def threaded(function, **twins):
    """The inline kernel ``function`` as the threaded kernels take it: the same code, with every
    kernel of THREADED (and ``twins``) it calls replaced by its inline twin, so that their prange
    loops run on threads (a kernel's loops run on threads only in the kernel compiled with them).
    Numba resolves a function's globals when it inlines it, so the twin's names are all it
    takes."""
    python = function.py_func
    names = dict(python.__globals__, **THREADED, **twins)
    twin = types.FunctionType(python.__code__, names, python.__name__, python.__defaults__,
                              python.__closure__)
    twin.__qualname__ = python.__qualname__ + "_threaded"
    return inline_kernel(twin)


threaded_drive = threaded(drive)


def drive_parts(model, state, dt) -> dict:
    """{name: KernelCall} of the kernels ``drive`` calls as kernels of their own, with the
    argument types the serial step calls them with: each compiles (and caches) apart from the
    step, so that `springsim warmup` can compile them in parallel before the step, which then
    loads them (warmup.py)."""
    arrays, x, v, pairs = model.arrays, state.positions, state.velocities, state.pairs
    start = np.empty_like(x)
    return {"pairs_now": KernelCall(pairs_now, (arrays, x, pairs)),
            "collide": KernelCall(collide, (arrays, x, v, start, pairs, float(dt))),
            "start_step": KernelCall(start_step, (arrays, x, v, 0, float(dt))),
            "step_start": KernelCall(step_start, (arrays, x)),
            "copy_positions": KernelCall(copy_positions, (start, x))}


def force_parts(model, state, dt) -> dict:
    """The explicit methods' force evaluation (``accelerations``), as ``drive_parts``."""
    x = state.positions
    a = np.empty_like(x)
    return {"accelerations": KernelCall(accelerations, (
                model.arrays, x, state.velocities, float(dt), a, force_columns.py_func(x))),
            "force_columns": KernelCall(force_columns, (x,))}
