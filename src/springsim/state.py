"""The state: what changes while simulating. Small, copyable, and all an integrator advances.

Besides positions, velocities and time it carries the contact memory that backward Euler keeps
from one step to the next (which particles were held by which terrain, their velocity floors and
friction), as MuJoCo keeps its warm start in mjData: so a copied or saved state continues a run
bit for bit, whatever the integrator.
"""
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np


class ContactMemory(NamedTuple):
    """Per-particle contacts that implicit_euler carries between steps (implicit/constraints.py)."""

    kind: np.ndarray              # (P,) int8: free, pinned or in contact
    terrain: np.ndarray           # (P,) int64: the terrain touched, or -1
    normal_floor: np.ndarray      # (P,) m/s: the lowest normal velocity the contact allows
    friction_damping: np.ndarray  # (P,) friction carried into the next step's matrix

    @classmethod
    def empty(cls, count: int) -> "ContactMemory":
        return cls(np.zeros(count, np.int8), np.full(count, -1, np.int64), np.zeros(count),
                   np.zeros(count))

    def copy(self) -> "ContactMemory":
        return ContactMemory(*(array.copy() for array in self))


@dataclass
class State:
    positions: np.ndarray   # (P, 3) m
    velocities: np.ndarray  # (P, 3) m/s
    time: float = 0.0       # s
    contacts: ContactMemory = field(default=None)

    def __post_init__(self):
        if self.contacts is None:
            self.contacts = ContactMemory.empty(len(self.positions))

    @classmethod
    def initial(cls, model) -> "State":
        return cls(model.initial_positions.copy(), model.initial_velocities.copy(), 0.0)

    def copy(self) -> "State":
        return State(self.positions.copy(), self.velocities.copy(), self.time,
                     self.contacts.copy())
