"""The state: what changes while simulating. Small, copyable, and all an integrator advances."""
from dataclasses import dataclass

import numpy as np


@dataclass
class State:
    positions: np.ndarray   # (P, 3) m
    velocities: np.ndarray  # (P, 3) m/s
    time: float = 0.0       # s

    @classmethod
    def initial(cls, model) -> "State":
        return cls(model.initial_positions.copy(), model.initial_velocities.copy(), 0.0)

    def copy(self) -> "State":
        return State(self.positions.copy(), self.velocities.copy(), self.time)
