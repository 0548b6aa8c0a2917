"""What every terrain kind shares: contact settings, the registry, and the packed arrays.

A kind registers its class with ``register(cls, names, order)``: ``names`` maps the scene file's
``type`` names to factories (``tilted_plane`` is a Plane with other defaults), ``order`` places
the kind in lists and menus. The class provides:

- ``distance_kernel(row, data, x0, x1, x2) -> (phi, nx, ny, nz)``: a Numba kernel, the signed
  distance (m) of the point to the terrain and the unit normal; ``row`` is the terrain's row of
  the parameter table, ``data`` the shared data buffer;
- ``pack(data_start) -> (row, data)``: its parameters (at most PARAMETERS numbers) and its part of
  the data buffer, which will start at ``data_start``;
- ``signed_distance(x, radius=0.0)``: the NumPy twin of the kernel, for (n, 3) points;
- ``display_mesh(near, extent) -> render.terrain_meshes.TerrainMesh``: what is drawn, given the
  bodies' middle and size;
- ``points_near(corners, size)``: points of the terrain under a box, for cameras;
- ``validate(key)``, and the contact settings of ``Contact``;
- optionally ``look_ahead = True``: the kernel is long (a mesh's grid), and the contact kernel
  looks it up a block of particles ahead of their contact (collision/response/terrain.py says why).
"""
from dataclasses import dataclass

import numpy as np

from ..errors import is_finite, require

PARAMETERS = 10          # numbers per row of the parameter table
KINDS: list = []         # terrain classes, by kind number
TERRAIN_TYPES: dict = {}  # scene ``type`` name -> factory
_registered: list = []   # (order, cls, names) as the kind files are imported


@dataclass
class Contact:
    """Restitution, Coulomb friction and contact band shared by every terrain kind."""

    restitution: float = 0.8
    friction: float = 0.3
    epsilon: float = 0.01

    def validate_contact(self, key: str) -> None:
        require(is_finite(self.restitution) and 0 <= self.restitution <= 1,
                f"{key}.restitution", self.restitution, "must lie in [0, 1]")
        require(is_finite(self.friction) and self.friction >= 0, f"{key}.friction",
                self.friction, "must be >= 0")
        require(is_finite(self.epsilon) and self.epsilon > 0, f"{key}.epsilon", self.epsilon,
                "must be > 0 m")


def register(cls, names: dict, order: int):
    """Add a terrain kind (see the module doc); returns ``cls``."""
    _registered.append((order, cls, names))
    return cls


def registered_kinds() -> list:
    """Number the registered kinds by ``order`` and fill KINDS and TERRAIN_TYPES (once all kind
    files are imported)."""
    KINDS.clear()
    TERRAIN_TYPES.clear()
    for number, (_, cls, names) in enumerate(sorted(_registered, key=lambda r: r[0])):
        cls.kind = number
        KINDS.append(cls)
        TERRAIN_TYPES.update(names)
    return KINDS


def pack_terrains(terrains) -> dict:
    """Arrays the contact kernels read: a kind number, a parameter row and contact settings per
    terrain, and the data buffer they share."""
    count = len(terrains)
    packed = {"terrain_kind": np.zeros(count, np.int64),
              "terrain_parameters": np.zeros((count, PARAMETERS)),
              "terrain_restitution": np.zeros(count), "terrain_friction": np.zeros(count),
              "terrain_epsilon": np.zeros(count)}
    data, length = [np.zeros(1)], 1   # never empty: one array type whatever the terrains
    for t, terrain in enumerate(terrains):
        row, own = terrain.pack(length)
        packed["terrain_kind"][t] = terrain.kind
        packed["terrain_parameters"][t, :len(row)] = row
        packed["terrain_restitution"][t] = terrain.restitution
        packed["terrain_friction"][t] = terrain.friction
        packed["terrain_epsilon"][t] = terrain.epsilon
        data.append(np.asarray(own, float).ravel())
        length += data[-1].size
    packed["terrain_data"] = np.concatenate(data)
    return packed
