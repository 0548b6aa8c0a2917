"""Integrators, chosen by name.

Adding one is one new file in this package that defines an ``Integrator`` subclass decorated with
``@register``, plus its import line at the bottom of this file.
"""
import numba
import numpy as np

from ..errors import SceneError
from ..spring_runs import partition_count

REGISTRY: dict[str, type] = {}
# no body-body pair list yet: (point-triangle pairs, edge-edge pairs, positions found at,
# steps kept since; surface_collisions.start_surface_pairs)
NO_PAIRS = (np.empty((0, 2), np.int64), np.empty((0, 2), np.int64), np.empty((0, 3)),
            np.zeros(1, np.int64))


class Integrator:
    """Advances a state by whole steps of size dt; subclasses set ``name``, ``order``, ``summary``.

    ``advance(model, state, dt, steps, threads)`` returns ``(steps_done, particle)`` where
    ``particle`` is the first particle found diverging after step ``steps_done`` (and -1 if none
    did). ``threads`` is the most threads it may use.
    """

    name = ""
    order = 0
    summary = ""
    _kept_for = None   # the model whose things are kept (model_cache)

    def __init__(self, **options):
        if options:
            key = next(iter(options))
            raise SceneError(f"integrator option {key}", options[key],
                             f"'{self.name}' takes no options")

    def advance(self, model, state, dt: float, steps: int, threads: int = 1) -> tuple[int, int]:
        raise NotImplementedError  # every registered integrator overrides this

    def pair_list(self, model) -> tuple:
        """The body-body pair list the last call left for ``model`` (_steps.drive keeps it
        while it holds, whatever the state's positions are now), or none yet. Why: a search
        costs several steps (0.7 ms on cloth-balls against 0.08 ms a step), and stepping one
        step a call, as a script that records every step does, paid it every call."""
        return self.model_cache(model).get("pairs", NO_PAIRS)

    def keep_pair_list(self, model, pairs) -> None:
        self.model_cache(model)["pairs"] = pairs

    def model_cache(self, model) -> dict:
        """What this integrator keeps for ``model`` between calls (pair lists, a solve's
        layout); a new model (a Simulation rebuilt by an edit) starts with nothing."""
        if self._kept_for is not model:
            self._kept_for, self._kept = model, {}
        return self._kept


class KernelIntegrator(Integrator):
    """An integrator whose whole loop of steps is one compiled kernel
    ``kernel(model_arrays, x, v, dt, steps, pairs) -> (steps_done, particle, pairs)`` (pairs:
    the body-body pair list, Integrator.pair_list), and the same compiled
    with its loops on threads, ``parallel_kernel``.

    Which one runs depends on the model's size alone (spring_runs.partition_count): a model
    whose force loop has one partition (under 131,072 particles) runs serially, since starting
    threads for every loop costs more than it saves there; a larger one runs the threaded kernel
    with ``threads`` threads, one thread included, so that its results do not depend on the
    number of threads (spring_runs.py: bit-identical for any count)."""

    kernel = None
    parallel_kernel = None

    def advance(self, model, state, dt, steps, threads=1):
        kernel = self.kernel
        if partition_count(model.particle_count) > 1:
            numba.set_num_threads(threads)
            kernel = self.parallel_kernel
        done, particle, pairs = kernel(model.arrays, state.positions, state.velocities,
                                       float(dt), int(steps), self.pair_list(model))
        self.keep_pair_list(model, pairs)
        return int(done), int(particle)


def available_threads() -> int:
    """The most threads a simulation can use: the machine's cores (or NUMBA_NUM_THREADS)."""
    return numba.config.NUMBA_NUM_THREADS


def register(cls):
    REGISTRY[cls.name] = cls
    return cls


def integrator_names() -> list[str]:
    return list(REGISTRY)


def get_integrator(name: str, **options) -> Integrator:
    if name not in REGISTRY:
        raise SceneError("integrator", name, "must be one of " + ", ".join(REGISTRY))
    return REGISTRY[name](**options)


# The registry: one line per integrator file.
from . import explicit_euler, symplectic_euler, midpoint, rk4, implicit_euler, predict_reevaluate  # noqa: E402,F401,E501
