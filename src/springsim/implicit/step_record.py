"""What a backward Euler step decided, kept for the gradient.

The adjoint of a step with terrain contact (gradients/implicit_contact.py) goes back through the
solves the forward made, with the constraints each had: which particles were contacts, on which
terrain, how each floor came about, which friction dampers were capped, which contacts slid or
held or were let go, which particles a solve carried into a terrain, how many passes each
Newton iteration took and which contacts got their impact speed back. Those are choices, made
from numbers that the forward's solves reach to their tolerance; the adjoint reads them here
instead of making them again from its own numbers, so it cannot take another branch.

The step writes them when its integrator is handed a ``StepRecord`` with room
(ImplicitEuler.recording); otherwise it is handed one with none, and each note returns at once.
"""
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from .constraints import CONTACT, GROWN


class StepRecord(NamedTuple):
    """One step's decisions (module doc); each array empty where nothing is recorded."""

    kind: np.ndarray        # (P,) int8: each particle's constraint at the step's start
    terrain: np.ndarray     # (P,) int64: a contact's terrain (-1 where free or pinned)
    floor_case: np.ndarray  # (P,) int8: how each contact's floor came about, when made
    rows: np.ndarray        # (R, P) int16: each pass's decisions (constraints.UNCHANGED, ...)
    tries: np.ndarray       # (T, 3) int64: each Newton iteration tried: its update passes, its
                            # solves, 1 where it was solved again (a fold closed within it)
    restored: np.ndarray    # (P,) bool: contacts whose approach speed the end gave back
    counts: np.ndarray      # (3,) int64: rows and tries written (or wanted, beyond the room),
                            # and the parts the step was cut into beyond the first


def no_record() -> StepRecord:
    """A record with no room: the step notes nothing."""
    return StepRecord(np.zeros(0, np.int8), np.zeros(0, np.int64), np.zeros(0, np.int8),
                      np.zeros((0, 0), np.int16), np.zeros((0, 3), np.int64),
                      np.zeros(0, np.bool_), np.zeros(0, np.int64))


def new_record(particles: int, rows: int, tries: int) -> StepRecord:
    """A record with room for ``rows`` passes and ``tries`` Newton iterations."""
    return StepRecord(np.zeros(particles, np.int8), np.full(particles, -1, np.int64),
                      np.zeros(particles, np.int8), np.zeros((rows, particles), np.int16),
                      np.zeros((tries, 3), np.int64), np.zeros(particles, np.bool_),
                      np.zeros(3, np.int64))


def overflowed(record: StepRecord) -> bool:
    """Whether the step wanted more rows or tries than the record has room for."""
    return bool(record.counts[0] > record.rows.shape[0]
                or record.counts[1] > record.tries.shape[0])


def grown(record: StepRecord) -> StepRecord:
    """A record with twice the room of one that overflowed."""
    wanted_rows = max(int(record.counts[0]), 1)
    wanted_tries = max(int(record.counts[1]), 1)
    return new_record(record.kind.shape[0], 2 * max(wanted_rows, record.rows.shape[0]),
                      2 * max(wanted_tries, record.tries.shape[0]))


def copied(record: StepRecord) -> StepRecord:
    """The record as the step left it, its rows and tries cut to what it wrote."""
    rows, tries = int(record.counts[0]), int(record.counts[1])
    return StepRecord(record.kind.copy(), record.terrain.copy(), record.floor_case.copy(),
                      record.rows[:rows].copy(), record.tries[:tries].copy(),
                      record.restored.copy(), record.counts.copy())


@kernel
def note_step(record):
    """A step begins: nothing written yet."""
    if record.counts.shape[0] == 0:
        return
    record.counts[:] = 0


@kernel
def note_part(record):
    """The step is taken again from its start in shorter parts (implicit_euler_step)."""
    if record.counts.shape[0] == 0:
        return
    record.counts[2] += 1


@kernel
def note_start(record, slots):
    """The constraints a (part of a) step starts with (constraints.find_constraints)."""
    if record.counts.shape[0] == 0:
        return
    record.counts[0] = record.counts[1] = 0
    for i in range(slots.kind.shape[0]):
        record.kind[i] = slots.kind[i]
        record.terrain[i] = slots.terrain[i] if slots.kind[i] == CONTACT else -1
        record.floor_case[i] = slots.floor_case[i]


@kernel
def taken_row(counts, which, room):
    """The next row of what ``counts[which]`` counts, counted even beyond the ``room`` there
    is (the caller grows the record and takes the step again); -1 where there is no room, or
    no record."""
    if counts.shape[0] == 0:
        return -1
    row = counts[which]
    counts[which] += 1
    return row if row < room else -1


@kernel
def note_pass(record, slots):
    """A pass's decisions (slots.case): a first iteration's cap, or an update's."""
    row = taken_row(record.counts, 0, record.rows.shape[0])
    if row < 0:
        return
    for i in range(slots.case.shape[0]):
        record.rows[row, i] = slots.case[i]
        if slots.case[i] >= GROWN:   # how its floor came about
            record.floor_case[i] = slots.floor_case[i]


@kernel
def note_try(record, updates, solves, again):
    """A Newton iteration's shape: its update passes, its solves, whether it goes again."""
    row = taken_row(record.counts, 1, record.tries.shape[0])
    if row < 0:
        return
    record.tries[row, 0], record.tries[row, 1] = updates, solves
    record.tries[row, 2] = 1 if again else 0


@kernel
def note_end(record, restored):
    """The contacts whose approach speed the step's end gave back."""
    if record.counts.shape[0] == 0:
        return
    record.restored[:] = restored
