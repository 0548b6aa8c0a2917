"""What the viewer's drawing (render/drawing.py) and camera (render/camera.py) read of a model,
rebuilt from a recording: its bodies, springs, ball radii, terrains, pins and wind
(recording_layout.py),
so that a replay draws exactly what `springsim view` draws."""
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..wind import ON


class RecordedArrays(NamedTuple):
    radius: np.ndarray        # (P,) m, zero for points
    rest_length: np.ndarray   # (S,) m, the springs' lengths in the first frame
    balls: np.ndarray         # (N,) particle numbers
    wind_settings: np.ndarray  # (6,) as wind.pack_wind's, of which drawing reads only ON
    wind_keys: np.ndarray     # (K, 4) time and the mean wind's velocity


@dataclass(frozen=True)
class RecordedModel:
    arrays: RecordedArrays
    bodies: tuple
    springs: np.ndarray       # (S, 2)
    spring_kind: np.ndarray   # (S,)
    terrains: tuple
    initial_positions: np.ndarray
    pinned: np.ndarray        # (P,) bool: a pin holds or moves the particle

    @property
    def particle_count(self) -> int:
        return len(self.initial_positions)


def recorded_model(take) -> RecordedModel:
    """The model of ``take`` (export.take.Take) as far as drawing it needs."""
    first = np.asarray(take.positions[0], float)
    springs = np.asarray(take.arrays.get("springs", np.empty((0, 2))), np.int64).reshape(-1, 2)
    kinds = np.asarray(take.arrays.get("spring_kind", np.empty(0)), np.int8)
    radius = np.zeros(len(first))
    radius[take.layout.ball_particles] = take.layout.ball_radii
    rest = np.linalg.norm(first[springs[:, 0]] - first[springs[:, 1]], axis=1)
    wind_keys = take.layout.wind_keys
    wind_settings = np.zeros(6)
    wind_settings[ON] = 1.0 if len(wind_keys) else 0.0
    pinned = np.zeros(len(first), bool)
    pinned[take.layout.pinned] = True
    return RecordedModel(RecordedArrays(radius, rest, take.layout.ball_particles, wind_settings,
                                        wind_keys),
                         take.layout.bodies, springs, kinds, take.layout.terrains, first, pinned)
