"""``terrain_distance``: the one function the contact kernels call, generated from the registry.

The package docstring says why it is generated. The source it compiles reads, for two kinds::

    def terrain_distance(kind, row, data, x0, x1, x2, particle_radius):
        if kind == 0:
            phi, nx, ny, nz = kernel_0(row, data, x0, x1, x2)
        else:
            phi, nx, ny, nz = kernel_1(row, data, x0, x1, x2)
        return phi - particle_radius, nx, ny, nz

(``kernel_k`` is the distance kernel of the k-th registered kind.)
"""
import linecache

import numpy as np
from numba import njit

from .._jit import FASTMATH
from .base import KINDS

FILENAME = "<springsim.terrains.dispatch: generated>"


def dispatcher_source(count: int) -> str:
    lines = ["def terrain_distance(kind, row, data, x0, x1, x2, particle_radius):",
             '    """Signed distance (m) from a particle\'s surface to a terrain, and the',
             '    terrain\'s unit normal there."""']
    call = "phi, nx, ny, nz = kernel_{}(row, data, x0, x1, x2)"
    for number in range(count):
        if count == 1:
            lines.append("    " + call.format(number))
            break
        if number == 0:
            lines.append(f"    if kind == {number}:")
        elif number < count - 1:
            lines.append(f"    elif kind == {number}:")
        else:
            lines.append("    else:")
        lines.append("        " + call.format(number))
    lines.append("    return phi - particle_radius, nx, ny, nz")
    return "\n".join(lines) + "\n"


def inlined(dispatcher):
    return njit(fastmath=FASTMATH, error_model="numpy", inline="always")(
        dispatcher.py_func)


@njit(fastmath=FASTMATH, error_model="numpy", inline="always")
def out_of_reach(row, data, x0, x1, x2):
    """What the still dispatcher answers for a kind that is never still: nothing near."""
    return np.inf, 0.0, 1.0, 0.0


def kind_kernel(cls, still_only, short_only=False):
    if still_only and getattr(cls, "never_still", False):
        return out_of_reach
    if short_only and getattr(cls, "look_ahead", False):
        return out_of_reach
    return inlined(cls.distance_kernel)


def build_dispatcher(kinds, still_only=False, short_only=False):
    """The dispatcher over ``kinds``; with ``still_only``, the kinds that deform by themselves
    (``never_still = True``) answer out_of_reach, for the lookups of terrains known not to
    deform (still, or moving rigidly in world.terrain_at); with ``short_only``, so do the
    kinds whose lookup is long (``look_ahead``: the meshes), for the plain kernels of the models
    that have none (plain.py), which compile in a fraction of the time."""
    source = dispatcher_source(len(kinds))
    # Every kind's kernel is inlined into the dispatcher, and the dispatcher into its callers, at
    # Numba's level (inline="always"): then no call is left in the contact loops, and Numba drops
    # the reference counting of the row it passes; a call left in any branch (the mesh kernel is
    # too big for LLVM to inline) kept it, and made the plane's contact four times slower. The
    # deforming mesh's kernel, inlined, still made the plane's lookup ten times slower (LLVM no
    # longer takes the kind's branch out of the particle loop): hence the still dispatcher.
    namespace = {f"kernel_{number}": kind_kernel(cls, still_only, short_only)
                 for number, cls in enumerate(kinds)}
    # registered with linecache so that tracebacks and Numba's error messages can show it
    linecache.cache[FILENAME] = (len(source), None, source.splitlines(True), FILENAME)
    exec(compile(source, FILENAME, "exec"), namespace)
    return njit(fastmath=FASTMATH, error_model="numpy", inline="always")(
        namespace["terrain_distance"])


def looks_ahead_source(kinds) -> str:
    numbers = [number for number, cls in enumerate(kinds) if getattr(cls, "look_ahead", False)]
    return ("def terrain_looks_ahead(kind):\n"
            f"    return {' or '.join(f'kind == {n}' for n in numbers) or 'False'}\n")


def build_looks_ahead(kinds):
    """``terrain_looks_ahead(kind)``: whether the kind's class sets ``look_ahead`` (a long
    lookup, which the contact kernel does a block of particles ahead; collision/response/terrain.py
    says why)."""
    namespace = {}
    exec(compile(looks_ahead_source(kinds), FILENAME, "exec"), namespace)
    return njit(inline="always")(namespace["terrain_looks_ahead"])


terrain_distance = build_dispatcher(KINDS)
still_terrain_distance = build_dispatcher(KINDS, still_only=True)
short_terrain_distance = build_dispatcher(KINDS, still_only=True, short_only=True)
terrain_looks_ahead = build_looks_ahead(KINDS)
