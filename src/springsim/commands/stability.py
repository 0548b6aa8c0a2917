"""`springsim stability`: the largest stable time step of each integrator on each scene."""
import sys
import time

from ._workers import add_worker_arguments

NAME = "stability"
HELP = ("largest stable time step of each integrator on each scene, by bisection: a table, "
        "CSV and a PNG chart")

JELLY_SCENES = ("jelly-plane", "jelly-tilted", "jelly-sphere", "jelly-bowl")
QUICK = {"seconds": 1.5, "tolerance": 0.15}   # --quick: a rougher, faster table


def add_arguments(parser) -> None:
    parser.add_argument("scenes", nargs="*", metavar="SCENE",
                        help="built-in scenes or .toml files (default: the four jelly scenes)")
    parser.add_argument("--integrators", nargs="+", metavar="NAME",
                        help="integrators to measure (default: all)")
    parser.add_argument("--seconds", type=float,
                        help="simulated seconds per trial (default: 3, or 1.5 with --quick)")
    parser.add_argument("--tolerance", type=float,
                        help="stop bisecting when the stable and unstable steps are within this "
                             "relative distance (default: 0.05, or 0.15 with --quick)")
    parser.add_argument("--max-dt", type=float, default=0.1, metavar="SECONDS",
                        help="the largest step tried (default: 0.1 s)")
    parser.add_argument("--quick", action="store_true",
                        help="shorter trials and a coarser bisection: a rough table, fast")
    parser.add_argument("--csv", default="stability.csv", metavar="PATH",
                        help="the table as CSV (default: stability.csv)")
    parser.add_argument("--png", default="stability.png", metavar="PATH",
                        help="the chart, log scale (default: stability.png)")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    add_worker_arguments(parser)


def run(args) -> int:
    from ..errors import require
    from ..integrators import integrator_names
    from ..safe_files import check_output_path
    from ..scenefile import load_scene
    from ..runner import WorkerLost, check_workers
    from ..stability import Search, find_stability_limits

    scenes = args.scenes or list(JELLY_SCENES)
    integrators = args.integrators or integrator_names()
    for name in integrators:
        require(name in integrator_names(), "integrator", name,
                "must be one of " + ", ".join(integrator_names()))
    check_workers(args.workers)
    loaded = {scene: load_scene(scene) for scene in scenes}   # a misspelt scene fails now
    require(args.png.lower().endswith(".png"), "png", args.png, "must end in .png")
    check_output_path("--csv", args.csv)
    check_output_path("--png", args.png)
    seconds = args.seconds if args.seconds is not None else (QUICK["seconds"] if args.quick
                                                             else 3.0)
    tolerance = args.tolerance if args.tolerance is not None else (QUICK["tolerance"]
                                                                   if args.quick else 0.05)
    started = time.perf_counter()
    searches = [Search(loaded[scene], integrator, seconds, args.max_dt, tolerance)
                for scene in scenes for integrator in integrators]
    try:
        limits = find_stability_limits(searches, args.workers, args.dask,
                                       on_limit=None if args.quiet else _progress)
    except WorkerLost as error:
        print(f"springsim stability: a search was lost: {error}", file=sys.stderr)
        return 1
    elapsed = time.perf_counter() - started
    print("\n".join(table_lines(limits)))
    write_csv(args.csv, limits, seconds, tolerance)
    plot_limits(args.png, limits, seconds)
    print(f"\n{plural(len(scenes), 'scene')} x {plural(len(integrators), 'integrator')}, "
          f"{seconds:g} s per trial, "
          f"tolerance {tolerance:g}: {sum(len(limit.trials) for limit in limits)} trials in "
          f"{elapsed:.0f} s. Wrote {args.csv} and {args.png}.")
    return 0


def _progress(limit) -> None:
    """The trials of a finished search, one line each."""
    for trial in limit.trials:
        verdict = ("stable" if trial.stable
                   else f"unstable ({trial.reason} at t = {trial.simulated:.2f} s)")
        print(f"  {limit.scene} {limit.integrator} dt = {trial.dt:.4g} s: {verdict}",
              file=sys.stderr, flush=True)


def describe(limit) -> str:
    """'stable / unstable' in seconds, as the course's reference table writes it."""
    if limit.largest_stable is None:
        return f"< {limit.smallest_unstable:.2g}"
    if limit.capped:
        return f">= {limit.largest_stable:.3g}"
    return f"{limit.largest_stable:.3g} / {limit.smallest_unstable:.3g}"


def table_lines(limits) -> list[str]:
    """Integrators down, scenes across, as the course's reference table."""
    scenes = list(dict.fromkeys(limit.scene for limit in limits))
    integrators = list(dict.fromkeys(limit.integrator for limit in limits))
    cells = {(limit.scene, limit.integrator): describe(limit) for limit in limits}
    first = max(len("integrator"), *(len(name) for name in integrators))
    widths = [max(len(scene), *(len(cells[scene, i]) for i in integrators)) for scene in scenes]

    def line(label, texts):
        return "  ".join([label.ljust(first)] + [t.ljust(w) for t, w in zip(texts, widths)])

    return (["largest stable / smallest unstable time step (s)", line("integrator", scenes)]
            + [line(i, [cells[scene, i] for scene in scenes]) for i in integrators])


def write_csv(path, limits, seconds: float, tolerance: float) -> None:
    """One row per scene and integrator, written whole or not at all. Empty cells: no such step
    was found (capped: stable up to the largest step tried)."""
    import csv
    import io

    from ..recording import atomic_output

    text = io.StringIO()
    writer = csv.writer(text, lineterminator="\n")
    writer.writerow(["scene", "integrator", "largest_stable_dt_s", "smallest_unstable_dt_s",
                     "capped", "trials", "seconds_per_trial", "tolerance"])
    for limit in limits:
        writer.writerow([limit.scene, limit.integrator, _number(limit.largest_stable),
                         _number(limit.smallest_unstable), limit.capped, len(limit.trials),
                         seconds, tolerance])
    with atomic_output(path) as file:
        file.write(text.getvalue().encode())


def _number(value) -> str:
    return "" if value is None else f"{value:.6g}"


def plot_limits(path, limits, seconds: float) -> None:
    """Grouped bars of the largest stable dt (log scale), one group per scene; a tick marks the
    smallest unstable dt, and an arrow a step stable up to the largest tried."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..recording import atomic_output

    scenes = list(dict.fromkeys(limit.scene for limit in limits))
    integrators = list(dict.fromkeys(limit.integrator for limit in limits))
    found = {(limit.scene, limit.integrator): limit for limit in limits}
    figure = Figure(figsize=(10, 5), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    width = 0.8 / len(integrators)
    for k, integrator in enumerate(integrators):
        positions = np.arange(len(scenes)) + (k - (len(integrators) - 1) / 2) * width
        stable = [found[scene, integrator].largest_stable or np.nan for scene in scenes]
        bars = axes.bar(positions, stable, width, label=integrator)
        for position, scene in zip(positions, scenes):
            limit = found[scene, integrator]
            if limit.largest_stable is not None:
                axes.annotate(f"{limit.largest_stable:.2g}", (position, limit.largest_stable),
                              xytext=(0, 3), textcoords="offset points", ha="center",
                              fontsize="x-small")
            if limit.smallest_unstable is not None and limit.largest_stable is not None:
                axes.plot([position - width / 2, position + width / 2],
                          [limit.smallest_unstable] * 2, color=bars.patches[0].get_facecolor(),
                          linewidth=1.0)
            if limit.capped:
                axes.annotate("", xy=(position, limit.largest_stable * 2.2),
                              xytext=(position, limit.largest_stable * 1.3),
                              arrowprops={"arrowstyle": "->"})
    axes.set_yscale("log")
    values = [value for limit in limits
              for value in (limit.largest_stable, limit.smallest_unstable) if value is not None]
    axes.set_ylim(10 ** np.floor(np.log10(min(values))), 4 * max(values))
    axes.set_xticks(np.arange(len(scenes)), scenes)
    axes.set_ylabel("largest stable time step (s)")
    axes.set_title(f"Largest stable time step ({seconds:g} s per trial). Line: smallest "
                   "unstable step; arrow: stable at the largest step tried", fontsize="medium")
    axes.grid(axis="y", which="both", alpha=0.3)
    axes.legend(fontsize="small", ncols=min(3, len(integrators)))
    with atomic_output(path) as file:
        figure.savefig(file, format="png")


def plural(count: int, noun: str) -> str:
    """"1 scene", "2 scenes"."""
    return f"{count} {noun}" + ("" if count == 1 else "s")
