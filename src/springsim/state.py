"""The state: what changes while simulating. Small, copyable, and all an integrator advances.

Besides positions, velocities and time it carries what a step reads of the steps before it, as
MuJoCo keeps its warm start in mjData: the contact memory that backward Euler keeps from one
step to the next (which particles were held by which terrain, their velocity floors and
friction) and the surface pair lists (collision/pair_lists/), whose age decides whether a list is
kept or renewed. So a copied or saved state continues a run bit for bit, whatever the integrator.
"""
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .collision.pair_lists import EDGES, POINTS, PairList, SolvePairList, no_pair_list
from .errors import SceneError


class ContactMemory(NamedTuple):
    """Per-particle contacts that implicit_euler carries between steps (implicit/constraints.py),
    and its last velocity change, the next solve's first guess."""

    kind: np.ndarray              # (P,) int8: free, pinned or in contact
    terrain: np.ndarray           # (P,) int64: the terrain touched; free: a release's mark; -1
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
    pairs: PairList = field(default=None)   # the post-step pass's surface pair list
    # backward Euler's list of surface pairs of two bodies (None until its first step)
    solve_pairs: SolvePairList | None = None

    def __post_init__(self):
        if self.contacts is None:
            self.contacts = ContactMemory.empty(len(self.positions))
        if self.pairs is None:
            self.pairs = no_pair_list()

    @classmethod
    def initial(cls, model) -> "State":
        return cls(model.initial_positions.copy(), model.initial_velocities.copy(), 0.0)

    def copy(self) -> "State":
        return State(self.positions.copy(), self.velocities.copy(), self.time,
                     self.contacts.copy(), self.steps, copy_pair_list(self.pairs),
                     copy_solve_pairs(self.solve_pairs))

    def check(self, particle_count: int, shapes: tuple[int, int] | None = None,
              trusted: tuple = (None, None)) -> None:
        """Raise a SceneError unless every array is what the compiled kernels assume: the
        model's shape and dtype, C-contiguous and writeable. A kernel trusts its arrays' sizes,
        so a replaced ``positions`` of another shape would be written past its end.
        ``shapes``: how many surface triangles and edges the model has, which the pair lists
        number (None: their numbers are not checked); ``trusted``: the (pairs, solve_pairs) that
        the last compiled call left in this state, whose rows are not read again (a pass over
        them, and over a typed list from Python, every call would cost a short step's time).
        Cheap (attribute checks, and a pass over the pair lists): it runs before every compiled
        call."""
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
        self.check_pairs(particle_count, shapes, trusted)
        if not (isinstance(self.time, (int, float, np.number)) and math.isfinite(self.time)):
            raise SceneError("state.time", self.time, "must be a finite number of seconds")
        if not (isinstance(self.steps, (int, np.integer)) and self.steps >= 0):
            raise SceneError("state.steps", self.steps, "must be a whole number >= 0")

    def check_pairs(self, particle_count: int, shapes: tuple[int, int] | None,
                    trusted: tuple = (None, None)) -> None:
        """The pair lists' arrays as the kernels read them, their rows within the model's."""
        pairs = self.pairs
        if not isinstance(pairs, PairList):
            raise SceneError("state.pairs", type(pairs).__name__,
                             "must be a collision.pair_lists.PairList")
        triangles, edges = shapes if shapes is not None else (None, None)
        if self.solve_pairs is not trusted[1]:
            self.check_solve_pairs(particle_count, triangles, edges)
        if pairs is trusted[0]:
            return
        rows = [("points", pairs.points, (2,), np.int64, (particle_count, triangles)),
                ("edges", pairs.edges, (2,), np.int64, (edges, edges)),
                ("found_at", pairs.found_at, (3,), np.float64, None),
                ("age", pairs.age, (), np.int64, None)]
        check_rows("state.pairs", rows, shapes is not None)
        if pairs.age.shape != (1,) or pairs.found_at.shape[0] not in (0, particle_count):
            raise SceneError("state.pairs", "a list of another model",
                             f"must be found for this model's {particle_count} particles")

    def check_solve_pairs(self, particle_count: int, triangles, edges) -> None:
        """The solve's kept list, as its kernels read it (None: none yet)."""
        kept = self.solve_pairs
        if kept is None:
            return
        if not isinstance(kept, SolvePairList) or len(kept.pairs) != 2:
            raise SceneError("state.solve_pairs", type(kept).__name__,
                             "must be a collision.pair_lists.SolvePairList or None")
        rows = [("points", kept.pairs[POINTS], (2,), np.int64, (particle_count, triangles)),
                ("edges", kept.pairs[EDGES], (2,), np.int64, (edges, edges)),
                ("found_at", kept.found_at, (3,), np.float64, None),
                ("reach", kept.reach, (), np.float64, None)]
        check_rows("state.solve_pairs", rows, triangles is not None)
        if kept.found_at.shape[0] != particle_count or kept.reach.shape != (1,):
            raise SceneError("state.solve_pairs", "a list of another model",
                             f"must be found for this model's {particle_count} particles")


def check_rows(key: str, rows: list, numbered: bool) -> None:
    """Each (name, array, columns, dtype, limits) as the kernels read it: a writeable
    C-contiguous array of that dtype and shape (N,) + columns, and, where ``numbered`` and
    ``limits`` say, its two columns below those limits."""
    for name, array, columns, dtype, limits in rows:
        if not (isinstance(array, np.ndarray) and array.shape[1:] == columns
                and array.dtype == dtype and array.flags.c_contiguous
                and array.flags.writeable):
            raise SceneError(f"{key}.{name}", _Summary(array),
                             f"must be a writeable C-contiguous {np.dtype(dtype)} array of "
                             f"shape (N,) + {columns}")
        if numbered and limits is not None and array.size and not (
                array.min() >= 0 and array[:, 0].max() < limits[0]
                and array[:, 1].max() < limits[1]):
            raise SceneError(f"{key}.{name}", _Summary(array),
                             "must number particles, triangles and edges of this model")


def copy_pair_list(pairs: PairList) -> PairList:
    return PairList(*(array.copy() for array in pairs))


def copy_solve_pairs(kept: SolvePairList | None) -> SolvePairList | None:
    if kept is None:
        return None
    return solve_pair_list(kept.pairs[POINTS], kept.pairs[EDGES], kept.found_at, kept.reach)


def solve_pair_list(points, edges, found_at, reach) -> SolvePairList:
    """A SolvePairList of copies of these arrays (its pairs in a typed list, which the solve
    replaces in place)."""
    from numba.typed import List

    pairs = List()
    pairs.append(np.array(points, np.int64).reshape(-1, 2))
    pairs.append(np.array(edges, np.int64).reshape(-1, 2))
    return SolvePairList(pairs, np.array(found_at, np.float64), np.array(reach, np.float64))


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
