"""Many independent runs on every local core or on a Dask cluster, through one code path.

``Runner(workers=N)`` starts a ``dask.distributed.LocalCluster`` of N single-threaded worker
processes on this machine; ``Runner(address="tcp://host:8786")`` (or the environment variable
DASK_SCHEDULER_ADDRESS) connects to an existing Dask scheduler instead. Either way the work is
``client.submit`` and ``as_completed``, so ``Runner.map`` hands each result over as soon as it is
done, tagged with the index of its input.

Why dask.distributed alone, and not joblib (loky locally, its dask backend for a cluster) or
concurrent.futures:

- isolation: when one worker process of a ``ProcessPoolExecutor`` or of loky dies (killed, out of
  memory, a crash in compiled code), the pool breaks and every pending task fails with it. Dask's
  nanny starts a new worker and the scheduler gives the lost task to another worker; a task whose
  workers keep dying ends with ``KilledWorker``, which ``map`` reports as that task's error
  (``WorkerLost``). Locally each worker holds one task at a time and a task is retried once
  (LOCAL_SCHEDULER); a cluster keeps its own ``distributed.scheduler.allowed-failures`` (Dask's
  default retries three times, and also counts against a task queued behind the one that
  killed the worker);
- streaming: ``as_completed`` yields results in the order they finish, so a caller can save each
  one at once and a killed parent keeps what was done;
- one code path: the local pool is a Dask cluster too, so the code that runs on a laptop is the
  code that runs on Slurm, PBS, SSH or Kubernetes (any deployment that gives a scheduler address).
  joblib's dask backend would be one more layer over the same client and gives none of the above.

Starting a local cluster is quick: its worker processes are forked from a
fork server that has imported springsim, NumPy, Numba and distributed once (``forkserver``
with a preload, where the platform has it), where Dask's default (``spawn``) makes every worker
import them from scratch, several times longer (benchmarks/sweep_scaling.py measures it as the
"fixed cost"). A fork server starts from a clean, single-threaded process, unlike
``fork`` of the parent (whose client threads a fork would copy mid-flight), and its workers load
the compiled kernels from the disk cache as a remote Dask worker does, so local and cluster
results stay the same bit for bit. Workers have one thread each: the runs are CPU-bound compiled
loops, so one process per core is what uses every core.

Compiled kernels are cached on disk (``springsim._jit``); ``warm_kernels`` compiles them in the
parent before fanning out, so that local workers load them instead of each compiling its own. A
worker on another machine compiles once into that machine's cache.
"""
import contextlib
import copy
import logging
import os
from dataclasses import dataclass

from . import signals
from .errors import SceneError, SimulationDiverged, require

ALLOWED_FAILURES = 1        # worker deaths a task may cause on a local cluster and still be retried
CONNECT_TIMEOUT = "10s"     # to reach a remote scheduler
# A local worker holds one task at a time (saturation 1.0: none queued behind the running one),
# so a worker that dies is blamed on its own run only.
LOCAL_SCHEDULER = {"distributed.scheduler.allowed-failures": ALLOWED_FAILURES,
                   "distributed.scheduler.worker-saturation": 1.0}
# What the fork server imports once for every local worker (module doc)
WORKER_PRELOAD = ["distributed", "springsim.sweeps.run"]


class WorkerLost(RuntimeError):
    """The worker processes that ran a task died (killed or out of memory) more often than the
    scheduler allows."""


@dataclass(frozen=True)
class Outcome:
    """The result of ``function(items[index])``, or the error it raised."""

    index: int
    value: object = None
    error: BaseException | None = None


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def scheduler_address(address: str | None) -> str | None:
    """``address``, else DASK_SCHEDULER_ADDRESS, else None (a local cluster)."""
    return address or os.environ.get("DASK_SCHEDULER_ADDRESS") or None


def check_workers(workers) -> int:
    """The number of local worker processes asked for (default: every core), checked."""
    if workers is None:
        return default_workers()
    require(isinstance(workers, int) and not isinstance(workers, bool) and workers >= 1,
            "workers", workers, "must be a whole number >= 1")
    return workers


class Runner:
    """A pool of worker processes: a local Dask cluster of ``workers`` processes (default: every
    core, at most ``tasks``), or the remote one whose scheduler is at ``address``.

    Use it as a context manager; the local cluster is shut down when the block ends.
    """

    def __init__(self, workers: int | None = None, address: str | None = None,
                 tasks: int | None = None):
        self.address = scheduler_address(address)
        self.workers = check_workers(workers)
        if tasks is not None:   # no idle local workers
            self.workers = max(1, min(self.workers, tasks))
        self._stack = contextlib.ExitStack()
        self.client = None

    def __enter__(self) -> "Runner":
        import dask
        from distributed import Client, LocalCluster

        # A cluster stopped half-started cannot be closed: its worker processes print tracebacks
        # and its exit hook fails. Ctrl-C and SIGTERM wait until it has started (signals.py).
        with signals.deferred(), self._stack:
            if self.address:
                self.client = self._stack.enter_context(_connect(Client, self.address))
            else:
                _quiet_resource_tracker()
                with dask.config.set({**LOCAL_SCHEDULER, **_fork_server()}):
                    cluster = self._stack.enter_context(LocalCluster(
                        n_workers=self.workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, silence_logs=logging.CRITICAL,
                        # no dashboard, and its HTTP server on a free port: not a warning
                        # whenever port 8787 is taken by another cluster
                        scheduler_kwargs={"dashboard_address": "127.0.0.1:0"}))
                self.client = self._stack.enter_context(Client(cluster))
            self._stack = self._stack.pop_all()
        return self

    def __exit__(self, *exc_info) -> None:
        with signals.deferred():   # nor half-closed
            self._stack.close()

    def map(self, function, items):
        """``Outcome``s of ``function(item)`` for every item, in the order they finish."""
        from distributed import as_completed

        futures = {self.client.submit(function, item, pure=False): index
                   for index, item in enumerate(items)}
        try:
            for future in as_completed(futures):
                yield _outcome(futures[future], future)
        finally:
            self.client.cancel(list(futures))

    def results(self, function, items, on_result=None) -> list:
        """``[function(item) for item in items]``, computed by the workers; ``on_result(index,
        value)`` is called as each finishes. The first error is raised (the rest cancelled)."""
        items = list(items)
        values = [None] * len(items)
        for outcome in self.map(function, items):
            if outcome.error is not None:
                raise outcome.error
            values[outcome.index] = outcome.value
            if on_result is not None:
                on_result(outcome.index, outcome.value)
        return values


def _outcome(index: int, future) -> Outcome:
    """Wait for the value (a future whose result was lost with its worker is recomputed first)."""
    from distributed import KilledWorker

    try:
        return Outcome(index, value=future.result())
    except KilledWorker:
        return Outcome(index, error=WorkerLost("its worker process died (killed or out of "
                                               "memory) on every try"))
    except Exception as error:   # noqa: BLE001 - the task's own error, for the caller to judge
        return Outcome(index, error=error)


# multiprocessing's resource tracker, a process of its own, removes the semaphore of a worker
# killed mid-run (a sweep stopped by Ctrl-C) and warns of it on stderr, after the command's
# one-line answer: not news to the user. Its -W options are this process's sys.warnoptions.
QUIET_TRACKER = "ignore::UserWarning:multiprocessing.resource_tracker"


def _quiet_resource_tracker() -> None:
    import sys

    if QUIET_TRACKER not in sys.warnoptions:
        sys.warnoptions.append(QUIET_TRACKER)


def _fork_server() -> dict:
    """The Dask setting that starts local workers from a fork server preloaded with springsim
    (module doc), or nothing where the platform has no fork server (Windows)."""
    import multiprocessing

    import dask
    from distributed.utils import get_mp_context

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return {}
    method = {"distributed.worker.multiprocessing-method": "forkserver"}
    with dask.config.set(method):
        get_mp_context().set_forkserver_preload(WORKER_PRELOAD)   # after Dask sets its own
    return method


def check_scheduler(address: str | None) -> None:
    """Refuse, before any work, a Dask scheduler address (or DASK_SCHEDULER_ADDRESS) where no
    scheduler answers; None asks for a local cluster, which needs no check."""
    address = scheduler_address(address)
    if address:
        from distributed import Client

        with _connect(Client, address):
            pass


@contextlib.contextmanager
def _connect(client_class, address: str):
    try:
        client = client_class(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as error:
        raise SceneError("--dask", address, f"no Dask scheduler answers there ({error}); give "
                         "its address as tcp://HOST:PORT") from None
    with client:
        yield client


def warm_kernels(scenes) -> None:
    """Compile (or load) the kernels each scene needs, one step of each, in this process.

    Errors are left to the runs themselves, which report them.
    """
    from .simulation import Simulation
    from .compile_notice import announced, kernels_of

    for scene in scenes:
        with contextlib.suppress(SceneError, SimulationDiverged, ValueError, ArithmeticError):
            simulation = Simulation(copy.deepcopy(scene))
            with announced(kernels_of(simulation)):
                simulation.step(1)
