"""The one decorator every hot loop uses, and where its compiled code is cached.

fastmath is given as explicit flags rather than ``True``: ``True`` also turns on ``nnan`` and
``ninf``, which let LLVM assume no NaN or infinity exists and so delete the very checks that detect
a diverging simulation. ``error_model="numpy"`` lets a division by zero give inf or NaN (which
the divergence check reports) instead of a branch and an exception in every inner loop.

Numba invalidates a cached kernel only when the kernel's own file changes, not when a kernel it
calls (in another file) does, so an edit to forces.py could leave rk4 running stale code. The cache
therefore lives in a folder named after a hash of all of springsim's sources: any change to any
file starts a fresh cache. Setting NUMBA_CACHE_DIR overrides this.
"""
import hashlib
import os
from pathlib import Path

import numba
from numba import njit

FASTMATH_FLAGS = {"nsz", "arcp", "contract", "afn", "reassoc"}


def _source_fingerprint() -> str:
    package = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def _use_versioned_cache() -> None:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    folder = base / "springsim" / f"numba-{_source_fingerprint()}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return  # unwritable home: Numba falls back to __pycache__ beside the sources
    numba.config.CACHE_DIR = str(folder)


_use_versioned_cache()


def kernel(function):
    """Compile ``function`` as a serial, cached Numba kernel."""
    return njit(cache=True, fastmath=FASTMATH_FLAGS, error_model="numpy")(function)
