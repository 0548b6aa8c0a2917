"""The one decorator every hot loop uses.

fastmath is given as explicit flags rather than ``True``: ``True`` also turns on ``nnan`` and
``ninf``, which let LLVM assume no NaN or infinity exists and so delete the very checks that detect
a diverging simulation. ``error_model="numpy"`` lets a division by zero give inf or NaN (which
the divergence check reports) instead of a branch and an exception in every inner loop.
"""
from numba import njit

FASTMATH_FLAGS = {"nsz", "arcp", "contract", "afn", "reassoc"}


def kernel(function):
    """Compile ``function`` as a serial, cached Numba kernel."""
    return njit(cache=True, fastmath=FASTMATH_FLAGS, error_model="numpy")(function)
