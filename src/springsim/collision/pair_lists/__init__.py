"""Surface pairs kept between steps: a pair list found once holds every pair within reach until
the surfaces have moved apart by more than its skin (keeping.py), so most steps need no search.
The list is part of the state (state.State.pairs): the contacts a step finds depend only on the
state, whether it was copied, saved or resumed.
"""
from typing import NamedTuple

import numpy as np
from numba.typed import List


class PairList(NamedTuple):
    """The surface pairs within reach of the positions a list was found at (keeping.py)."""

    points: np.ndarray     # (K, 2) int64: (surface particle, surface triangle row), sorted
    edges: np.ndarray      # (L, 2) int64: (edge row, edge row), lower first, sorted
    found_at: np.ndarray   # (P, 3) m: the positions it was found at; NaN: it holds for one step
    age: np.ndarray        # (1,) int64: the steps it has been kept since


POINTS, EDGES = 0, 1   # the lists in SolvePairList.pairs: point-triangle, edge-edge


class SolvePairList(NamedTuple):
    """The implicit solve's surface pairs of two bodies (solve_pairs.py), changed in place."""

    pairs: List            # [POINTS]: point-triangle pairs (K, 2), [EDGES]: edge-edge (L, 2)
    found_at: np.ndarray   # (P, 3) m: the predicted positions they were found at
    reach: np.ndarray      # (1,) m: the reach they were found with; negative: none yet


def no_pair_list() -> PairList:
    """No list yet: the first step searches (or proves there is nothing to find)."""
    return PairList(np.empty((0, 2), np.int64), np.empty((0, 2), np.int64),
                    np.empty((0, 3)), np.zeros(1, np.int64))
