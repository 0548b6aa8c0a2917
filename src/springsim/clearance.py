"""How far a model's particles are from each terrain at a time: the recording's penetration and
the stability check's. A plain model's (plain.py) is measured by the plain twin of the kernel,
which compiles without the mesh terrains' lookups, with the same numbers."""
import numpy as np

from .plain import is_plain, plain_twin
from .world import terrain_clearances


def terrain_clearance(model, x: np.ndarray, t: float) -> np.ndarray:
    """(T,) the least signed distance (m) from any particle's surface (its contact radius) to
    each terrain of ``model`` where that terrain is at time ``t`` (s): negative for a
    particle inside. The world is left at t, where the next step moves it from anyway."""
    out = np.full(len(model.terrains), np.inf)
    if len(out):   # a scene without terrains compiles nothing for it
        clearances = (plain_twin(terrain_clearances) if is_plain(model.arrays)
                      else terrain_clearances)   # a plain model's: the short lookups alone
        clearances(model.arrays, np.ascontiguousarray(x, dtype=float), model.arrays.radius,
                   float(t), out)
    return out
