"""The kernels' first compile done ahead of time (`springsim warmup`), and whether it is done.

What compiles is a kernel for its arguments' types, not an integrator: the serial step, the
threaded one (models of 131,072 particles and more), the one that keeps the gradient's tape are
three compiles of one method (``Integrator.variants``), and a new type of argument is another.
``is_compiled`` asks Numba's cache index whether a kernel is there for given arguments, without
compiling or loading it; ``is_warm`` whether every variant `springsim warmup` compiles for an
integrator is. A compile that does happen is said when it starts (compile_notice.py).
"""
import os
from pathlib import Path


def cache_folder() -> Path:
    import numba

    from . import _jit  # noqa: F401 - sets Numba's cache folder (versioned by the kernel sources)

    return Path(os.environ.get("NUMBA_CACHE_DIR") or numba.config.CACHE_DIR)


def is_compiled(call) -> bool:
    """Whether ``call``'s kernel (an integrators.KernelCall) is compiled for its arguments'
    types: in this process, or in the cache on disk (then loading it takes a second)."""
    kernel = call.kernel
    types = tuple(kernel.typeof_pyval(argument) for argument in call.arguments)
    if types in kernel.overloads:
        return True
    try:   # Numba's cache index, as its own load_overload reads it
        cache = kernel._cache
        key = cache._index_key(types, kernel.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:   # a probe: a cache laid out otherwise, or a damaged index (pickle's
        return False     # errors): not known to be compiled, so compiled again


def variant_calls(integrator: str, variants=None) -> dict:
    """{label: KernelCall} of every variant `springsim warmup` compiles for ``integrator``: each
    of its variants (Integrator.variants), or those named in ``variants``, on each of
    WARMUP_SCENES."""
    from .simulation import Simulation

    calls = {}
    for scene in warmup_scenes():
        simulation = Simulation(scene, integrator=integrator, threads=1)
        found = simulation.integrator.variants(simulation.model, simulation.state,
                                               simulation.dt)
        for variant, call in found.items():
            if variants is None or variant in variants:
                calls[f"{integrator} {variant} ({scene.name})"] = call
    return calls


def warmup_scenes() -> list:
    """Small models of a jelly cube on the plane and a cloth on balls: between them, every
    kind of body, terrain and contact the step kernels are compiled for (the types of
    tests/test_threads.py's small models, which step on the threaded kernels)."""
    from .scenefile import load_scene

    return [load_scene("jelly-plane", ["bodies.0.particles_per_edge=3"]),
            load_scene("cloth-balls", ["bodies.0.particles_per_edge=4"])]


def is_warm(integrator: str, variants=None) -> bool:
    """Whether every variant `springsim warmup` compiles for ``integrator`` (or those named in
    ``variants``) is in the cache."""
    return all(map(is_compiled, variant_calls(integrator, variants).values()))
