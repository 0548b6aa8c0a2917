"""Parameter sweeps: many runs of one scene over a grid of values, on every local core or on a
Dask cluster, with a results table that survives a killed sweep and resumes.

    table = springsim.sweep("jelly-plane", vary={"bodies.0.structural.ks": [1000, 2000]},
                            duration=4, workers=2)

The grid (``grid.py``) is built and validated before anything runs; each run is the pure
function ``run.run_one(spec) -> row`` (``run.py``); ``springsim.runner.Runner`` runs them on a
local Dask cluster or a remote one and hands the rows back as they finish; ``table.py`` keeps
OUT/results.csv. With a local cluster the parent compiles the kernels first, so that the workers
load them from the on-disk cache.

Worker processes are started with the ``spawn`` method, so a script that calls ``sweep`` with
more than one worker must do so under ``if __name__ == "__main__":``.
"""
import os
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass

from ..errors import require
from ..safe_files import atomic_output
from ..runner import Runner, check_scheduler, check_workers, warm_kernels
from ..scenefile import toml_value
from .grid import Variation, build_grid, parse_variation
from .plot import parse_plot, plot_sweep
from .run import NPZ, run_one
from .table import DONE, ResultsTable, columns, parse_row, row_of

SAVE_FORMATS = ("npz",)


@dataclass(frozen=True)
class SweepOptions:
    """How a sweep runs, what it keeps and whom it tells: ``sweep``'s keyword arguments, which
    are the command line's options (checked before anything runs: ``check``)."""

    duration: float | None = None   # simulated s of each run (default: the scene's)
    seeds: int | None = None        # runs of each combination, each with its seed's nudge
    workers: int | None = None      # local processes (default: every core)
    dask: str | None = None         # a Dask scheduler's address (default: DASK_SCHEDULER_ADDRESS)
    out: str | None = None          # the folder of results.csv; runs already there are skipped
    save: str | None = None         # "npz": each run's recording in OUT/runs/ too
    fps: float = 60.0               # frames sampled per simulated second
    overrides: tuple = ()           # "KEY=VALUE" texts applied to the scene first (--set)
    plot: tuple = ()                # "KEY:RESULT[:PATH]": a chart of a result against a key
    progress: bool = False          # a progress bar, and a line for the runs skipped
    on_row: Callable[[dict], object] | None = None   # called with each row as its run ends

    def check(self) -> None:
        check_workers(self.workers)
        require(self.save is None or self.save in SAVE_FORMATS, "--save", self.save,
                "must be " + " or ".join(SAVE_FORMATS))
        require(self.save is None or self.out is not None, "--save", self.save,
                "needs --out, the folder to save to")


def sweep(scene, vary=None, **options) -> list[dict]:
    """Run ``scene`` (a built-in name or a .toml file) for every combination of ``vary`` and
    return the table: a dict per run, in run order (the columns of OUT/results.csv).

    ``vary`` maps scene keys to lists of values or to "START:STOP:COUNT" (a list of
    "KEY=..." texts as the command line gives them works too). The keyword ``options`` are
    SweepOptions' fields: ``overrides``, ``--set`` texts applied first; ``workers`` local
    processes (default: every core), or the Dask scheduler at ``dask`` (default:
    DASK_SCHEDULER_ADDRESS, if set). With ``out`` the table goes to OUT/results.csv as runs
    finish, runs already there are skipped, ``save="npz"`` keeps each run's recording in
    OUT/runs/. Each "KEY:RESULT" of ``plot`` charts a result against a varied key as
    OUT/RESULT-vs-KEY.png ("KEY:RESULT:PATH": as PATH). ``on_row(row)`` is called as each run
    finishes; ``duration``, ``seeds``, ``fps`` and ``progress`` are the command line's.
    """
    options = SweepOptions(**options)   # an unknown keyword raises TypeError, naming it
    variations = variations_of(vary)
    options.check()
    specs = grid_of(scene, variations, options)
    keys = [variation.key for variation in variations]
    charts = [parse_plot(text, keys + (["seed"] if options.seeds else []), options.out)
              for text in options.plot]
    check_scheduler(options.dask)   # before the output folder is made or written
    out = options.out
    table = ResultsTable(out, columns(keys, bool(options.seeds), options.save is not None)) \
        if out else None
    rows = resume(table, specs, out) if table else {}
    pending = [spec for spec in specs if spec.index not in rows]
    if rows and options.progress:
        print(f"springsim sweep: {len(rows)} of {len(specs)} runs are already in {table.path}; "
              f"skipped them, running {len(pending)}", file=sys.stderr, flush=True)
    for spec, row in run_all(pending, options.workers, options.dask, out, options.progress):
        rows[spec.index] = row
        if table:
            table.append(row)
        if options.on_row is not None:
            options.on_row(row)
    ordered = [rows[spec.index] for spec in specs]
    if table:
        table.write(ordered)
    for key, result, path in charts:
        plot_sweep(ordered, key, result, path)
    return ordered


def grid_of(scene, variations, options: SweepOptions):
    """The sweep's runs (grid.build_grid), with its ``duration`` as one more override."""
    settings = list(options.overrides)
    if options.duration is not None:
        settings.append(f"duration={toml_value(options.duration)}")
    return build_grid(scene, variations, overrides=settings, seeds=options.seeds,
                      fps=options.fps, save=options.save is not None)


def variations_of(vary) -> list[Variation]:
    if vary is None:
        return []
    if isinstance(vary, dict):
        return [variation_of(key, values) for key, values in vary.items()]
    return [parse_variation(text) for text in vary]


def variation_of(key, values) -> Variation:
    """A key's values: a list, or a "V1,V2" or "START:STOP:COUNT" text."""
    if isinstance(values, str):
        return parse_variation(f"{key}={values}")
    require(isinstance(values, (list, tuple)) and len(values) > 0, str(key), values,
            "must be a list of values or a text 'V1,V2,...' or 'START:STOP:COUNT'")
    return Variation(str(key), tuple(values))


def run_all(specs, workers, address, out, progress):
    """(spec, row) of each run, as the runs finish."""
    from tqdm import tqdm

    if not specs:
        return
    first_of_each = {spec.scene.integrator: spec.scene for spec in reversed(specs)}
    warm_kernels(first_of_each.values())
    with Runner(workers, address, tasks=len(specs)) as runner, tqdm(total=len(specs), unit="run", desc="sweep", leave=False,
                      disable=None if progress else True) as bar:
        for outcome in runner.map(run_one, specs):
            spec = specs[outcome.index]
            if outcome.error is not None:
                result = {"status": "error",
                          "message": f"{type(outcome.error).__name__}: {outcome.error}"}
            else:
                result = outcome.value
            yield spec, row_of(spec, result, save_npz(out, spec, result.pop(NPZ, None)))
            bar.update()


def save_npz(out, spec, data: bytes | None) -> str | None:
    """Write a run's recording to OUT/runs/run-<run_id>.npz; its path relative to OUT."""
    if data is None:
        return None
    relative = os.path.join("runs", f"run-{spec.run_id}.npz")
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    with atomic_output(os.path.join(out, relative)) as file:
        file.write(data)
    return relative


def resume(table, specs, out) -> dict:
    """Check the output folder, and the rows of the runs already done there (by run index)."""
    check_folder(out)
    found = table.read()
    by_id = {spec.run_id: spec for spec in specs}
    strangers = [run_id for run_id in found if run_id not in by_id]
    require(not strangers, "--out", out,
            f"{table.path} holds {len(strangers)} runs that this sweep does not have; give "
            "another --out, or the arguments of the sweep that wrote it")
    done = {}
    for run_id, row in found.items():
        spec = by_id[run_id]
        saved = not spec.save or (row.get("npz") and os.path.exists(os.path.join(out,
                                                                               row["npz"])))
        if row["status"] in DONE and saved:
            done[spec.index] = {**parse_row(row), "run": spec.index}
    table.write(done.values())   # drops a line cut short, and rows to run again
    return done


def check_folder(out: str) -> None:
    """The output folder exists (or is made) and can be written."""
    try:
        os.makedirs(out, exist_ok=True)
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as error:
        require(False, "--out", out, f"cannot be made or written ({error.strerror})")


__all__ = ["sweep", "SweepOptions", "build_grid", "parse_variation", "Variation", "run_one",
           "plot_sweep"]
