"""The measurement behind `springsim bench`: how fast an integrator advances a scene.

The model is built and the kernels are compiled (or loaded from Numba's cache) before any timing;
then only whole compiled calls of many steps are timed, so that the figure is the integrator's
and not Python's. Build time and warm-up time are reported apart.
"""
import math
import sys
import time

from .errors import require
from .simulation import Simulation

DEFAULT_SECONDS = 3.0
CALL_SECONDS = 0.1  # with --seconds, each timed call runs about this long


def benchmark(scene, steps: int | None = None, seconds: float | None = None,
              threads: int | None = None) -> dict:
    """Time ``steps`` steps in one compiled call, or whole calls for about ``seconds`` s, with
    at most ``threads`` threads (default: all cores)."""
    if steps is None and seconds is None:
        seconds = DEFAULT_SECONDS
    if steps is not None:
        require(isinstance(steps, int) and steps >= 1, "steps", steps, "must be an integer >= 1")
    else:
        require(math.isfinite(seconds) and seconds > 0, "seconds", seconds, "must be > 0 s")

    started = time.perf_counter()
    simulation = Simulation(scene, threads=threads)
    build_seconds = time.perf_counter() - started
    started = time.perf_counter()
    simulation.step(1)  # compiles the kernels, or loads them from the cache
    warmup_seconds = time.perf_counter() - started

    if steps is not None:
        timed_steps, wall_seconds = steps, _timed_call(simulation, steps)
    else:
        timed_steps, wall_seconds = _timed_for(simulation, seconds)
    return {
        "scene": scene.name,
        "integrator": simulation.integrator.name,
        "dt": simulation.dt,
        "threads": simulation.threads,
        "particles": simulation.model.particle_count,
        "springs": simulation.model.spring_count(),
        "steps": timed_steps,
        "wall_seconds": wall_seconds,
        "steps_per_second": timed_steps / wall_seconds,
        "ms_per_step": 1000.0 * wall_seconds / timed_steps,
        "real_time_factor": timed_steps * simulation.dt / wall_seconds,
        "build_seconds": build_seconds,
        "warmup_seconds": warmup_seconds,
        "peak_memory_mb": peak_memory_mb(),
    }


def _timed_call(simulation, steps: int) -> float:
    started = time.perf_counter()
    simulation.step(steps)
    return time.perf_counter() - started


def _timed_for(simulation, seconds: float) -> tuple[int, float]:
    """Whole calls until ``seconds`` have passed; one step is timed first to size the calls."""
    per_step = _timed_call(simulation, 1)
    call_steps = max(1, int(CALL_SECONDS / max(per_step, 1e-9)))
    total_steps, total_seconds = 0, 0.0
    while total_seconds < seconds:
        total_seconds += _timed_call(simulation, call_steps)
        total_steps += call_steps
    return total_steps, total_seconds


def peak_memory_mb() -> float | None:
    """The process's peak resident memory in MB (None where the system does not say)."""
    try:
        import resource
    except ImportError:
        return None
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    # Linux reports kilobytes, macOS bytes.
    return peak / 2 ** 20 if sys.platform == "darwin" else peak / 2 ** 10
