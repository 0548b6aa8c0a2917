"""Terrains: static surfaces that particles collide with, an open set of kinds.

Each terrain has a signed distance ``phi`` (positive on the free side, in m) and a unit normal
pointing to the free side. A particle touches when ``phi`` is below the contact band ``epsilon``.

A terrain kind is one file of this package (plane.py, sphere.py, bowl.py, mesh.py). It supplies
one dataclass, registered with ``base.register``, that carries all of the kind: ``validate``,
its Numba distance-and-normal kernel, the NumPy twin of that kernel (``signed_distance``), the
kernel's derivatives for the gradients' adjoint (``adjoint_shape``), the mesh drawn
(``display_mesh``) and exported (``export_mesh``) and the points that bound it for cameras
(base.py lists them). Files are found by listing the package, so a new kind touches no other
file. The meshes' geometry is display.py's, which the renderer and the exporters import too.

How the kernels are dispatched, and why so. Every terrain packs into one row of a uniform
parameter table (T, K) float64, plus its share of one data buffer (a mesh's distance grid); the
model carries those two arrays and each terrain's kind number. The contact kernels call
``terrain_distance(model, t, x0, x1, x2, radius)``, which branches on the kind number to the
kind's kernel. That function is *generated* from the registry (dispatch.py) as plain source, so
no ``if kind ==`` chain is written by hand, and compiled with Numba like any other kernel, so
LLVM inlines each kind's kernel into the branch exactly as it did the hand-written chain before.
The alternatives:
- ``numba.literal_unroll`` over a tuple of the kinds' kernels: it caches (tried), but Numba types
  a tuple of kernels as first-class function types (it warns that the feature is experimental),
  so each call is an indirect call through a pointer, which LLVM cannot inline;
- first-class function types directly (a kernel passed as an argument): the same indirect call;
- a dispatcher module generated into a file: caches the dispatcher itself too, but writes into
  the installed package (or the cache folder) at import time.
The generated dispatcher has no cache of its own (it has no source file), but the kernels that
call it have theirs (``cache=True``): a cached caller carries the dispatcher's compiled code, so
a warm start compiles nothing (tests/test_mesh_terrains.py checks that the contact kernel loads
from the cache). Each kind's kernel is inlined into the dispatcher and the dispatcher into its
callers at Numba's level (dispatch.py says why), so the plane's contact kernel costs what a
hand-written chain of kinds would (benchmarks/terrain_dispatch.py times it).
"""
import importlib
import pkgutil

from .base import KINDS, TERRAIN_TYPES, Contact, pack_terrains, registered_kinds

for _module in pkgutil.iter_modules(__path__):
    if _module.name not in ("base", "dispatch"):
        importlib.import_module(f"{__name__}.{_module.name}")
registered_kinds()   # number the kinds and order TERRAIN_TYPES, now that all are in

from .bowl import Bowl  # noqa: E402  (the built-in kinds, importable from springsim.terrains)
from .dispatch import still_terrain_distance, terrain_distance, terrain_looks_ahead  # noqa: E402
from .mesh import MeshTerrain  # noqa: E402
from .plane import Plane, tilted_plane  # noqa: E402
from .sphere import Sphere  # noqa: E402

__all__ = ["Contact", "Plane", "tilted_plane", "Sphere", "Bowl", "MeshTerrain", "TERRAIN_TYPES",
           "KINDS", "pack_terrains", "terrain_distance", "still_terrain_distance",
           "terrain_looks_ahead"]
