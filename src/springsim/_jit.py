"""The one decorator every hot loop uses, and where its compiled code is cached.

No fast-math: strict IEEE arithmetic, so that the same input gives the same bits whether a
kernel was compiled in this process or loaded from the cache. LLVM's fast-math flags
(reassoc, contract) let it reorder sums and fuse multiply-adds differently in each compilation
context: a backward-Euler step compiled in the process differed from the cached one by 3e-17 m,
and a chaotic run (a cube pressing a folded cloth) ended 0.5 m apart after 8 steps
(tests/test_cache.py). What strict arithmetic costs is on the documentation's performance
page. ``error_model="numpy"`` lets a division by zero give inf or NaN (which
the divergence check reports) instead of a branch and an exception in every inner loop.

Numba invalidates a cached kernel only when the kernel's own file changes, not when a kernel it
calls (in another file) does, nor a constant it reads from another module (compiled in as a
literal), so an edit to forces.py could leave rk4 running stale code. The cache therefore lives in
a folder named after a hash of the kernel sources (``kernel_sources``): the modules that import
this one, and every springsim module they import, transitively. Editing any of them starts a fresh
cache; editing the rest (the command line, the viewer, recording) keeps the compiled kernels. Each
import marks its folder as used, and folders of other versions left unused for STALE_DAYS are
deleted. Setting NUMBA_CACHE_DIR overrides all of this.

Numba names each compiled function by its qualified name, its argument types and a counter
that starts at 1 in every process (``numba.core.bytecode.FunctionIdentity``). Functions made by
one factory share name and types: Numba's quicksort behind ``np.sort`` and the one behind
``np.argsort`` both define ``partition(A, R, low, high)`` for int64 arrays. Two processes can
thus give two different bodies one symbol; once both are cached, a kernel compiled later links
both, LLVM keeps one body under that name, and argsort runs sort's partition (numba#10486):
wrong contact orders, or a crash. ``distinct_function_ids`` starts each process's counter at a
random 63-bit offset, so that no two processes share an id (tests/test_cache.py rebuilds the
collision).

LLVM vectorizes a loop whose stores it cannot prove apart from its loads only behind runtime
checks, and by default gives up beyond 8 of them (``runtime-memory-check-threshold``): a loop
over springs that writes nine results (the adjoint's, gradients/run_kernels.py) compiled to
scalar code. ``allow_memory_checks`` raises the limits at import, before any kernel compiles;
the checks change no result (a loop's iterations do the same arithmetic, in lanes).

Numba's cache keeps, per kernel, an index of its compiled signatures and a numbered data file
each. Saving one reads the index, takes the first free number, writes the index, then the
data: two processes compiling one kernel for two signatures at once (`springsim warmup`'s
parallel compiles, pytest's workers) can take the same number, and one index entry then names
the other signature's code, which a later run would load and call. ``locked_cache_saves`` makes
each save one step under a lock file in the cache folder, the data written before the index
that names it (tests/test_cache.py).
"""
import ast
import contextlib
import fcntl
import hashlib
import itertools
import os
import re
import secrets
import shutil
import time
import types
from pathlib import Path

import llvmlite.binding as llvm
import numba
from numba import njit
from numba.core.bytecode import FunctionIdentity
from numba.core.caching import IndexDataCacheFile, NullCache
from numba.core.registry import CPUDispatcher as Dispatcher

FASTMATH = False   # strict IEEE arithmetic: the same bits however compiled (module doc)
MEMORY_CHECKS = 256   # runtime alias checks a vectorized loop may take (module doc)
STALE_DAYS = 30


PACKAGE = Path(__file__).parent
# a module that imports this one defines kernels (``from .._jit import kernel``)
_IMPORTS_JIT = re.compile(rb"^\s*(from\s+[\w.]*_jit\s+import|import\s+[\w.]*_jit\b)", re.M)


def source_fingerprint(package: Path = PACKAGE) -> str:
    """A hash of the kernel sources' names and contents: it changes when a kernel may."""
    digest = hashlib.sha256()
    for path in kernel_sources(package):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


def kernel_sources(package: Path = PACKAGE) -> list[Path]:
    """The modules that define kernels, with every module of ``package`` they import at their
    top level, transitively (the kernels they call and the constants they read), sorted."""
    pending = [path for path in package.rglob("*.py") if _IMPORTS_JIT.search(path.read_bytes())]
    found = set(pending)
    while pending:
        for imported in _package_imports(pending.pop(), package):
            if imported not in found:
                found.add(imported)
                pending.append(imported)
    return sorted(found)


def _package_imports(path: Path, package: Path) -> list[Path]:
    """The files of ``package`` that ``path`` imports at its top level (relative imports, or
    absolute ones naming the package)."""
    here = path.parent.relative_to(package).parts
    modules = []
    for node in ast.parse(path.read_bytes()).body:
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[:len(here) - (node.level - 1)] if node.level > 1 else here
                parts = base + tuple((node.module or "").split(".")) if node.module else base
            elif (node.module or "").split(".")[0] == package.name:
                parts = tuple(node.module.split(".")[1:])
            else:
                continue
            modules.append(parts)
            modules += [parts + (alias.name,) for alias in node.names]   # submodules by name
        elif isinstance(node, ast.Import):
            modules += [tuple(alias.name.split(".")[1:]) for alias in node.names
                        if alias.name.split(".")[0] == package.name]
    return [file for parts in modules if (file := _module_file(package, parts)) is not None]


def _module_file(package: Path, parts: tuple) -> Path | None:
    folder = package.joinpath(*parts)
    for file in (folder.with_suffix(".py") if parts else None, folder / "__init__.py"):
        if file is not None and file.is_file():
            return file
    return None


def _use_versioned_cache() -> None:
    if os.environ.get("NUMBA_CACHE_DIR"):
        return
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    folder = base / "springsim" / f"numba-{source_fingerprint()}"
    try:
        folder.mkdir(parents=True, exist_ok=True)
        os.utime(folder)   # used now
    except OSError:
        return  # unwritable home: Numba falls back to __pycache__ beside the sources
    numba.config.CACHE_DIR = str(folder)
    remove_stale_caches(folder.parent, keep=folder)


def remove_stale_caches(parent: Path, keep: Path, now: float | None = None) -> list[Path]:
    """Delete the numba-* folders in ``parent`` other than ``keep`` that no import has used
    for STALE_DAYS (other versions' caches: about 15 MB each). Returns those deleted."""
    cutoff = (time.time() if now is None else now) - STALE_DAYS * 86400
    deleted = []
    for folder in parent.glob("numba-*"):
        try:
            if folder != keep and folder.is_dir() and folder.stat().st_mtime < cutoff:
                shutil.rmtree(folder)
                deleted.append(folder)
        except OSError:
            continue   # in use or not ours to delete: leave it
    return deleted


def distinct_function_ids() -> None:
    """Number the functions this process compiles from a random 63-bit start (module doc)."""
    FunctionIdentity._unique_ids = itertools.count(secrets.randbits(63))


def allow_memory_checks() -> None:
    """Let LLVM's loop vectorizer emit as many runtime alias checks as a loop needs (module
    doc)."""
    llvm.set_option("", f"--runtime-memory-check-threshold={MEMORY_CHECKS}")
    llvm.set_option("", f"--vectorize-memory-check-threshold={MEMORY_CHECKS}")


def locked_cache_saves() -> None:
    """Numba's cache saves, one process at a time, data before index (module doc)."""
    IndexDataCacheFile.save = _locked_save


def _locked_save(cache_file, key, data) -> None:
    with _cache_lock(cache_file._cache_path):
        overloads = cache_file._load_index()
        data_name = overloads.get(key)
        if data_name is None:
            taken = set(overloads.values())
            data_name = next(name for number in itertools.count(1)
                             if (name := cache_file._data_name(number)) not in taken)
        cache_file._save_data(data_name, data)
        overloads[key] = data_name
        cache_file._save_index(overloads)


@contextlib.contextmanager
def _cache_lock(folder: str):
    with open(os.path.join(folder, "springsim-saves.lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


distinct_function_ids()
allow_memory_checks()
locked_cache_saves()
_use_versioned_cache()


def kernel(function):
    """Compile ``function`` as a serial, cached Numba kernel.

    A tuple of arrays built inside a kernel (world.TerrainView) goes only to inline kernels:
    handed to a kernel like this one, the pair computed right when compiled in the process and
    wrong when loaded from the cache (tests/test_cache.py caught it; once it crashed)."""
    return njit(cache=True, fastmath=FASTMATH, error_model="numpy")(function)


def twin(dispatcher, replacements: dict, suffix: str, made: dict):
    """``dispatcher`` (a kernel or an inline kernel) with every kernel it calls that is a key of
    ``replacements`` replaced by its value, wherever it is called: in its own code, or in any
    kernel it calls, which is then a twin too (made once: ``made``, by id). A kernel that
    reaches none is itself. Each twin is the same code compiled with other globals (Numba
    resolves a function's globals when it compiles it), under its own name (``suffix``) and so
    its own cache entry."""
    if id(dispatcher) in made:
        return made[id(dispatcher)]
    made[id(dispatcher)] = dispatcher   # until known otherwise (a kernel calls itself: none do)
    python = dispatcher.py_func
    found = {}
    for name in _global_names(python.__code__):
        called = python.__globals__.get(name)
        if not isinstance(called, Dispatcher):
            continue
        if called in replacements:
            found[name] = replacements[called]
        elif (made_twin := twin(called, replacements, suffix, made)) is not called:
            found[name] = made_twin
    if found:
        copy = types.FunctionType(python.__code__, {**python.__globals__, **found},
                                  python.__name__, python.__defaults__, python.__closure__)
        copy.__qualname__ = python.__qualname__ + suffix
        options = {key: value for key, value in dispatcher.targetoptions.items()
                   if key != "nopython"}
        made[id(dispatcher)] = njit(cache=not isinstance(dispatcher._cache, NullCache),
                                    **options)(copy)
    return made[id(dispatcher)]


def _global_names(code) -> set:
    """The names ``code`` (with the functions defined in it) may read as globals."""
    names = set(code.co_names)
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            names |= _global_names(constant)
    return names


def inline_kernel(function):
    """A small kernel inlined into the kernels that call it (in Numba's IR, before compiling).

    For helpers called once per particle or spring with an array argument: a call between
    kernels passes each array with a reference count up and down, which can be a
    hundred times the helper's own work. Helpers that take and return scalars need not be
    inlined this way: the compiler inlines them itself."""
    return njit(inline="always", cache=True, fastmath=FASTMATH,
                error_model="numpy")(function)


def parallel_kernel(function):
    """A kernel whose ``prange`` loops (its own, or those of the inline kernels it calls) run
    on Numba's threads. Only ever called from Python: a cached kernel that calls a parallel one
    crashes when loaded from the cache (numba#8578)."""
    return njit(parallel=True, cache=True, fastmath=FASTMATH,
                error_model="numpy")(function)
