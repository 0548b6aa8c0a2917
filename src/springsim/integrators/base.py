"""What every integrator is: the ``Integrator`` interface, and the registry that names them.

Adding an integrator is one new file in this package that defines an ``Integrator`` subclass
decorated with ``@register``, plus its import line in ``__init__.py``. The registry lives here,
not in the package's ``__init__``, so that a method's file imports nothing that imports it back.
"""
import numba
import numpy as np

from ..clock import CALL_START
from ..errors import SceneError
from ..spring_runs import partition_count
from .calls import KernelCall

REGISTRY: dict[str, type] = {}


class Integrator:
    """Advances a state by whole steps of size dt; subclasses set ``name``, ``order``, ``summary``.

    ``advance(model, state, dt, steps, threads)`` returns ``(steps_done, particle)`` where
    ``particle`` is the first particle found diverging after step ``steps_done`` (and -1 if none
    did). ``threads`` is the most threads it may use. Everything a step reads of the steps
    before it is in the state (state.State), so an integrator holds only what it derives from
    the model (``model_cache``).
    """

    name = ""
    order = 0
    summary = ""
    # "module:Class" of the adjoint of its step (gradients/adjoints.py), read by
    # springsim.gradient; empty: the method has no adjoint yet and gradients refuse it
    adjoint = ""
    _kept_for = None   # the model whose things are kept (model_cache)

    def __init__(self, **options):
        if options:
            key = next(iter(options))
            raise SceneError(f"integrator option {key}", options[key],
                             f"'{self.name}' takes no options")

    def advance(self, model, state, dt: float, steps: int, threads: int = 1) -> tuple[int, int]:
        raise NotImplementedError  # every registered integrator overrides this

    def variants(self, model, state, dt: float) -> dict[str, KernelCall]:
        """Every compiled call a simulation of ``model`` with this integrator can make, by a
        short name (``serial``, ``threaded``, ``keeping``): what `springsim warmup` compiles
        and ``warmup.is_warm`` checks; none for a method that is not one compiled call."""
        return {}

    def parts(self, model, state, dt: float) -> dict[str, KernelCall]:
        """The kernels the serial step calls as kernels of their own, by name, with the
        arguments it calls them with: `springsim warmup` compiles them first, in parallel,
        and the step's compile then loads them (warmup.py). Empty for a method that is not
        one compiled call."""
        return {}

    def model_cache(self, model) -> dict:
        """What this integrator derives from ``model`` and keeps between calls (a solve's
        layout); a new model (a Simulation rebuilt by an edit) starts with nothing."""
        if self._kept_for is not model:
            self._kept_for, self._kept = model, {}
        return self._kept


class KernelIntegrator(Integrator):
    """An integrator whose whole loop of steps is one compiled kernel
    ``kernel(model_arrays, x, v, dt, steps, pairs) -> (steps_done, particle, pairs)`` (pairs:
    the state's surface pair list, returned as the last step left it), and the same compiled
    with its loops on threads, ``parallel_kernel``.

    Which one runs depends on the model's size and its ``spring_partition``
    (spring_runs.partition_count): a model whose force loop has one partition (under 131,072
    particles, by default) runs serially, since starting
    threads for every loop costs more than it saves there; a larger one runs the threaded kernel
    with ``threads`` threads, one thread included, so that its results do not depend on the
    number of threads (spring_runs.py: bit-identical for any count)."""

    kernel = None
    parallel_kernel = None
    # ``keeping_kernel(model_arrays, x, v, dt, steps, pairs, kept, starts)``: ``kernel``,
    # serial, that also keeps each step's start (x, v) in starts (steps, 2, P, 3) and its
    # ``stages`` force evaluations' accelerations in kept (steps, stages, P, 3), for the
    # gradient's adjoint to reuse (gradients/tape.py); None where a method has none
    keeping_kernel = None
    stages = 0

    def keeps_stages(self, model) -> bool:
        """Whether ``advance_keeping`` takes this model's steps as ``advance`` does: a method
        with a keeping kernel, on a model that runs the serial kernel."""
        partitions = partition_count(model.particle_count, model.arrays.spring_partition)
        return self.keeping_kernel is not None and partitions == 1

    def advance_keeping(self, model, state, dt, kept, starts):
        """``advance`` (where ``keeps_stages``) of len(kept) steps, keeping each one's start
        and stages' accelerations."""
        model.arrays.clock[CALL_START] = state.time
        call = self.keeping_call(model, state, dt, kept, starts)
        done, particle, state.pairs = call.kernel(*call.arguments)
        return int(done), int(particle)

    def serial_kernel(self, model):
        """``kernel``, or its plain twin for a plain model (plain.py: the same steps, compiled
        without what the model does not have)."""
        from ..plain import is_plain, plain_twin

        return plain_twin(self.kernel) if is_plain(model.arrays) else self.kernel

    def kernel_call(self, model, state, dt, steps, threaded=None) -> KernelCall:
        """The call ``advance`` makes: ``parallel_kernel`` where ``threaded`` (by default, where
        the model's size asks for it), else the serial kernel (``serial_kernel``)."""
        if threaded is None:
            threaded = partition_count(model.particle_count,
                                       model.arrays.spring_partition) > 1
        return KernelCall(self.parallel_kernel if threaded else self.serial_kernel(model),
                          (model.arrays, state.positions, state.velocities, float(dt),
                           int(steps), state.pairs))

    def keeping_call(self, model, state, dt, kept, starts) -> KernelCall:
        return KernelCall(self.keeping_kernel,
                          (model.arrays, state.positions, state.velocities, float(dt),
                           len(kept), state.pairs, kept, starts))

    def variants(self, model, state, dt):
        from ..plain import plain_twin

        serial = self.kernel_call(model, state, dt, 0, threaded=False)
        calls = {"serial": serial._replace(kernel=self.kernel),
                 "plain": serial._replace(kernel=plain_twin(self.kernel)),
                 "threaded": self.kernel_call(model, state, dt, 0, threaded=True)}
        if self.keeping_kernel is not None:
            # the tape's arrays for one step (gradients/tape.py), empty: only their types count
            particles = state.positions.shape[0]
            calls["keeping"] = self.keeping_call(model, state, dt,
                                                 np.empty((1, self.stages, particles, 3)),
                                                 np.empty((1, 2, particles, 3)))
        return calls

    def parts(self, model, state, dt):
        from ..plain import plain_parts
        from ._steps import drive_parts, force_parts   # _steps imports this module

        calls = {**force_parts(model, state, dt), **drive_parts(model, state, dt)}
        return plain_parts(calls, model)

    def advance(self, model, state, dt, steps, threads=1):
        call = self.kernel_call(model, state, dt, steps)
        if call.kernel is self.parallel_kernel:
            numba.set_num_threads(threads)
        # the kernels' steps take their times from it
        model.arrays.clock[CALL_START] = state.time
        done, particle, state.pairs = call.kernel(*call.arguments)
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
