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
from typing import NamedTuple


def cache_folder() -> Path:
    import numba

    from . import _jit  # noqa: F401 - sets Numba's cache folder (versioned by the kernel sources)

    return Path(os.environ.get("NUMBA_CACHE_DIR") or numba.config.CACHE_DIR)


def is_compiled(call) -> bool:
    """Whether ``call``'s kernel (an integrators.KernelCall) is compiled for its arguments'
    types: in this process, or in the cache on disk (then loading it takes a second)."""
    kernel = call.kernel
    types = _types(call)
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


# --- compiling in parallel -------------------------------------------------------------------
# A step kernel compiles the kernels it calls first, each on its own (the serial steps'
# collide, accelerations, pairs_now: Integrator.parts), and later compiles load them from the
# cache. So `springsim warmup` compiles in two stages, each spread over the machine's cores in
# worker processes: the parts first (every integrator's serial step calls the same ones), then
# the steps, which load the parts. Numba compiles in one thread, so a process per core is what
# two cores give: the default scene's first compile in about half the time.

RECORDING = "recording"   # the part that compiles the kernels a run's recording calls
TICK = 15.0               # s: at most this long without a line while workers compile
POLL = 0.2                # s between looks at the workers


class CompileTask(NamedTuple):
    """One worker's share of a warmup, under ``integrator``: the step's ``parts`` named
    (Integrator.parts, and RECORDING) for the first of ``scenes``, or, where there are none,
    for each scene the step a run calls and the ``variants`` named (None: every one)."""

    scenes: tuple
    integrator: str
    parts: tuple = ()
    variants: tuple | None = ()

    def label(self) -> str:
        what = ", ".join(self.parts) if self.parts else "step"
        return f"{self.integrator} {what} ({', '.join(scene.name for scene in self.scenes)})"


def compile_jobs() -> int:
    """How many processes compile at once: one per core this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:   # no affinity on this platform
        return max(1, os.cpu_count() or 1)


def part_tasks(integrators, scenes) -> list[CompileTask]:
    """A task for each part not yet compiled (once, however many steps call it), in the
    integrators' order of parts (the costliest first, so that a pool taking them in turn ends
    them together), then each scene's recording."""
    from .simulation import Simulation

    parts, seen = [], set()
    for scene in scenes:
        for integrator in integrators:
            simulation = Simulation(scene, integrator=integrator, threads=1)
            calls = simulation.integrator.parts(simulation.model, simulation.state,
                                                simulation.dt)
            for name, call in calls.items():
                key = (call.kernel, _types(call))
                if key not in seen and not is_compiled(call):
                    seen.add(key)
                    parts.append(CompileTask((scene,), integrator, (name,)))
    return parts + [CompileTask((scene,), integrators[0], (RECORDING,)) for scene in scenes]


def step_tasks(integrators, scenes, variants) -> list[CompileTask]:
    """A task for each integrator's steps on every scene (one process: a second scene's step
    mostly loads what the first compiled), those with the fewest parts first: they compile
    the most of their own."""
    from .simulation import Simulation

    def part_count(integrator):
        simulation = Simulation(scenes[0], integrator=integrator, threads=1)
        return len(simulation.integrator.parts(simulation.model, simulation.state,
                                               simulation.dt))

    return [CompileTask(tuple(scenes), integrator, (), variants)
            for integrator in sorted(integrators, key=part_count)]


def run_task(task: CompileTask) -> float:
    """Compile (or load) what ``task`` names; the seconds it took."""
    import time

    from .compile_notice import announced
    from .recording import Recording
    from .simulation import Simulation

    started = time.perf_counter()
    with announced(task.label(), say=False):
        for scene in task.scenes[:1] if task.parts else task.scenes:
            simulation = Simulation(scene, integrator=task.integrator, threads=1)
            model, state, dt = simulation.model, simulation.state, simulation.dt
            calls = simulation.integrator.parts(model, state, dt)
            for name in task.parts:
                if name == RECORDING:
                    Recording.empty(simulation, 1, 60.0).capture(0, simulation)
                else:
                    calls[name].kernel.compile(_types(calls[name]))
            if task.parts:
                continue
            simulation.step(0)   # a call of no steps compiles the whole step, running none
            for variant, call in simulation.integrator.variants(model, state, dt).items():
                if (task.variants is None or variant in task.variants) and not is_compiled(call):
                    call.kernel.compile(_types(call))
    return time.perf_counter() - started


def run_tasks(tasks: list, jobs: int, say=print) -> list:
    """Run ``tasks`` on ``jobs`` worker processes (here, one after another, where one job or
    one task); [(task, seconds)] as they ended. While workers compile, a line at least every
    TICK seconds. Ctrl-C (or SIGTERM) is the main process's to answer: it ends the workers
    (multiprocessing's Pool terminates them as its block is left) and stops at once."""
    import multiprocessing
    import time

    if jobs <= 1 or len(tasks) <= 1:
        return [(task, run_task(task)) for task in tasks]
    started = last_line = time.monotonic()
    ended = []
    context = multiprocessing.get_context("spawn")   # a fresh interpreter: no Numba state shared
    with context.Pool(min(jobs, len(tasks)), initializer=_leave_signals_to_the_main) as pool:
        running = [(task, pool.apply_async(run_task, (task,))) for task in tasks]
        while running:
            # asked in turn, sleeping between: a signal then finds the main process in Python
            time.sleep(POLL)
            for task, result in [entry for entry in running if entry[1].ready()]:
                running.remove((task, result))
                ended.append((task, result.get()))
                say(f"  compiled {task.label()} in {ended[-1][1]:.1f} s")
                last_line = time.monotonic()
            if running and time.monotonic() - last_line >= TICK:
                say(f"  ... still compiling ({len(running)} to go), "
                    f"{time.monotonic() - started:.0f} s")
                last_line = time.monotonic()
    return ended


def _leave_signals_to_the_main() -> None:
    """A worker ignores Ctrl-C, which a terminal sends to every process of the command: the
    main process answers it and ends the workers."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _types(call) -> tuple:
    return tuple(call.kernel.typeof_pyval(argument) for argument in call.arguments)
