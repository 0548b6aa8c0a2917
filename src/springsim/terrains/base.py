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
- ``adjoint_shape(row)``: the kernel as differentiable NumPy for the gradients' contact adjoint
  (gradients/contact.py): an object with ``distance(x, offset)``, ``normals(x)``,
  ``gradient(x)`` (grad phi) and ``curvature(x)`` ((dn/dx)^T per point, or None where it is
  zero), computing the kernel's bits from its row of the parameter table (the kind's file
  defines it: plane.Flat, sphere.Round, mesh.Gridded); ``Contact``'s gives None, a kind the
  adjoint does not follow;
- ``display_mesh(near, extent) -> display.TerrainMesh``: what is drawn, given the bodies' middle
  and size;
- ``export_mesh(positions) -> (vertices, triangles)``: what an exporter writes (export/geometry.py),
  given every particle at every frame (..., 3); ``Contact``'s gives None, nothing written;
- ``points_near(corners, size)``: points of the terrain under a box, for cameras;
- ``validate(key)``, and the contact settings of ``Contact``;
- optionally ``look_ahead = True``: the kernel is long (a mesh's grid), and the contact kernel
  looks it up a block of particles ahead of their contact (collision/response/terrain.py says why);
- optionally ``never_still = True``: its surface moves by itself (a point cache), so it is never
  looked up as a still terrain (dispatch.still_terrain_distance).
"""
import math
from dataclasses import dataclass

import numpy as np

from ..errors import is_finite, require
from ..motion import Motion

PARAMETERS = 10          # numbers per row of the parameter table
KINDS: list = []         # terrain classes, by kind number
TERRAIN_TYPES: dict = {}  # scene ``type`` name -> factory
_registered: list = []   # (order, cls, names) as the kind files are imported


@dataclass
class Contact:
    """Restitution, Coulomb friction, contact band and motion shared by every terrain kind.

    ``motion`` (motion.py) moves the terrain rigidly as a function of time; contact looks the
    terrain up in its own frame (so a mesh's distance grid moves with it) and makes restitution
    and friction relative to its surface velocity (world.py)."""

    restitution: float = 0.8
    friction: float = 0.3
    epsilon: float = 0.01
    motion: Motion | None = None

    def validate_contact(self, key: str) -> None:
        require(is_finite(self.restitution) and 0 <= self.restitution <= 1,
                f"{key}.restitution", self.restitution, "must lie in [0, 1]")
        require(is_finite(self.friction) and self.friction >= 0, f"{key}.friction",
                self.friction, "must be >= 0")
        require(is_finite(self.epsilon) and self.epsilon > 0, f"{key}.epsilon", self.epsilon,
                "must be > 0 m")
        if self.motion is not None:
            self.motion.validate(f"{key}.motion")

    def anchor(self) -> tuple:
        """The point a motion's rotation turns the terrain about unless it names a pivot."""
        return (0.0, 0.0, 0.0)

    def packed_kind(self) -> int:
        """The kind number its row is packed as (a kind may pack as another: mesh.py)."""
        return self.kind

    def deforms(self) -> bool:
        """Whether its data block is refitted as time goes (terrains/deforming_mesh.py)."""
        return False

    def pose_at(self, t: float):
        """(R, c, pivot) at time t: the terrain as placed at x is at c + R (x - pivot) (the
        identity for a still terrain). For drawing and export."""
        if self.motion is None:
            return np.eye(3), np.zeros(3), np.zeros(3)
        pose = self.motion.pose(t, self.anchor())
        return pose[:9].reshape(3, 3), pose[9:12], pose[12:15]

    def moves(self) -> bool:
        """Whether it is drawn anew as time goes."""
        return self.motion is not None

    def thickness(self) -> float:
        """The terrain's thinnest part (m): a motion that carries it further than a part of this
        in one step takes the step in substeps (substeps.py). A half-space, an open mesh and a
        bowl's wall have no far side to pass a particle through: inf."""
        return math.inf

    def motion_probes(self) -> np.ndarray:
        """Points of the terrain as placed (n, 3), whose travel in a step bounds its surface's
        (substeps.py); none for a terrain of infinite thickness."""
        return np.zeros((0, 3))

    def adjoint_shape(self, row):
        """Its shape for the gradients' contact adjoint (module doc); None: not followed."""
        return None

    def export_mesh(self, positions):
        """(vertices, triangles) an exporter writes (module doc); None: nothing."""
        return None

    def vertices_at(self, vertices, t: float) -> np.ndarray:
        """Its display mesh's ``vertices`` where they are at time t."""
        return self.place_at(vertices, t)

    def place_at(self, points, t: float) -> np.ndarray:
        """``points`` of the terrain as placed, where they are at time t."""
        rotation, center, pivot = self.pose_at(t)
        return (np.asarray(points, float) - pivot) @ rotation.T + center


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


def pack_terrains(terrains, largest_offset: float = 0.0) -> dict:
    """Arrays the contact kernels read: a kind number, a parameter row and contact settings per
    terrain, the data buffer they share, where a deforming terrain's block starts in it (-1:
    it keeps its shape) and each terrain's row of the motion table (-1: it stands still).
    ``largest_offset``: the most any particle keeps from a terrain (m), which a deforming
    mesh's lookup must reach beyond its band."""
    count = len(terrains)
    packed = {"terrain_kind": np.zeros(count, np.int64),
              "terrain_parameters": np.zeros((count, PARAMETERS)),
              "terrain_restitution": np.zeros(count), "terrain_friction": np.zeros(count),
              "terrain_epsilon": np.zeros(count),
              "terrain_deforming": np.full(count, -1, np.int64)}
    data, length = [np.zeros(1)], 1   # never empty: one array type whatever the terrains
    for t, terrain in enumerate(terrains):
        row, own = terrain.pack(length, largest_offset)
        packed["terrain_kind"][t] = terrain.packed_kind()
        packed["terrain_deforming"][t] = length if terrain.deforms() else -1
        packed["terrain_parameters"][t, :len(row)] = row
        packed["terrain_restitution"][t] = terrain.restitution
        packed["terrain_friction"][t] = terrain.friction
        packed["terrain_epsilon"][t] = terrain.epsilon
        data.append(np.asarray(own, float).ravel())
        length += data[-1].size
    packed["terrain_data"] = np.concatenate(data)
    # each moving terrain's row of the motion table (world_tables.pack_world packs the motions in
    # this order, then the pins')
    packed["terrain_motion"] = np.full(count, -1, np.int64)
    packed["terrain_motion"][[t for t, terrain in enumerate(terrains)
                              if terrain.motion is not None]] = np.arange(
        sum(terrain.motion is not None for terrain in terrains))
    return packed
