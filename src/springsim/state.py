"""The state: what changes while simulating. Small, copyable, and all an integrator advances.

Besides positions, velocities and time it carries the contact memory that backward Euler keeps
from one step to the next (which particles were held by which terrain, their velocity floors and
friction), as MuJoCo keeps its warm start in mjData: so a copied or saved state continues a run
bit for bit, whatever the integrator.
"""
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .errors import SceneError


class ContactMemory(NamedTuple):
    """Per-particle contacts that implicit_euler carries between steps (implicit/constraints.py),
    and its last velocity change, the next solve's first guess."""

    kind: np.ndarray              # (P,) int8: free, pinned or in contact
    terrain: np.ndarray           # (P,) int64: the terrain touched, or -1
    normal_floor: np.ndarray      # (P,) m/s: the lowest normal velocity the contact allows
    friction_damping: np.ndarray  # (P,) friction carried into the next step's matrix
    velocity_change: np.ndarray   # (P, 3) m/s: the last step's v_new - v

    @classmethod
    def empty(cls, count: int) -> "ContactMemory":
        return cls(np.zeros(count, np.int8), np.full(count, -1, np.int64), np.zeros(count),
                   np.zeros(count), np.zeros((count, 3)))

    def copy(self) -> "ContactMemory":
        return ContactMemory(*(array.copy() for array in self))


CONTACT_DTYPES = ContactMemory(np.int8, np.int64, np.float64, np.float64, np.float64)
CONTACT_COLUMNS = ContactMemory((), (), (), (), (3,))   # each field's shape after (P,)


@dataclass
class State:
    positions: np.ndarray   # (P, 3) m
    velocities: np.ndarray  # (P, 3) m/s
    time: float = 0.0       # s
    contacts: ContactMemory = field(default=None)
    steps: int = 0          # steps taken to reach this state

    def __post_init__(self):
        if self.contacts is None:
            self.contacts = ContactMemory.empty(len(self.positions))

    @classmethod
    def initial(cls, model) -> "State":
        return cls(model.initial_positions.copy(), model.initial_velocities.copy(), 0.0)

    def copy(self) -> "State":
        return State(self.positions.copy(), self.velocities.copy(), self.time,
                     self.contacts.copy(), self.steps)

    def check(self, particle_count: int) -> None:
        """Raise a SceneError unless every array is what the compiled kernels assume: the
        model's shape and dtype, C-contiguous and writeable. A kernel trusts its arrays' sizes,
        so a replaced ``positions`` of another shape would be written past its end.
        Cheap (attribute checks only): it runs before every compiled call."""
        wanted = [("positions", self.positions, (particle_count, 3), np.float64),
                  ("velocities", self.velocities, (particle_count, 3), np.float64)]
        contacts = self.contacts
        if not (isinstance(contacts, tuple) and len(contacts) == len(CONTACT_DTYPES)):
            raise SceneError("state.contacts", type(contacts).__name__,
                             "must be a state.ContactMemory")
        wanted += [(f"contacts.{name}", array, (particle_count,) + columns, dtype)
                   for name, array, dtype, columns in zip(ContactMemory._fields, contacts,
                                                          CONTACT_DTYPES, CONTACT_COLUMNS)]
        for name, array, shape, dtype in wanted:
            if not (isinstance(array, np.ndarray) and array.shape == shape
                    and array.dtype == dtype and array.flags.c_contiguous
                    and array.flags.writeable):
                raise SceneError(f"state.{name}", _Summary(array),
                                 f"must be a writeable C-contiguous {np.dtype(dtype)} array of "
                                 f"shape {shape}: the model has {particle_count} particles")
        if not (isinstance(self.time, (int, float, np.number)) and math.isfinite(self.time)):
            raise SceneError("state.time", self.time, "must be a finite number of seconds")
        if not (isinstance(self.steps, (int, np.integer)) and self.steps >= 0):
            raise SceneError("state.steps", self.steps, "must be a whole number >= 0")


class _Summary:
    """How an error shows an array: its kind, shape and layout, not its numbers."""

    def __init__(self, value):
        self.value = value

    def __repr__(self) -> str:
        value = self.value
        if not isinstance(value, np.ndarray):
            return f"a {type(value).__name__}"
        layout = [] if value.flags.c_contiguous else ["not C-contiguous"]
        layout += [] if value.flags.writeable else ["read-only"]
        return (f"a {value.dtype} array of shape {value.shape}"
                + "".join(f", {text}" for text in layout))
