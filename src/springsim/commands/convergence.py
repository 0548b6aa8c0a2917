"""`springsim convergence`: the measured order of accuracy of each integrator."""
import math
import sys
import time

from ._workers import add_worker_arguments

NAME = "convergence"
MAX_FINAL_TIME = 60.0   # s: the reference solve and the smallest steps grow with it
HELP = ("measured order of accuracy of each integrator against SciPy's DOP853 on a squeezed "
        "cube: fitted slopes and a log-log plot")


def add_arguments(parser) -> None:
    parser.add_argument("--integrators", nargs="+", metavar="NAME",
                        help="integrators to measure (default: all)")
    parser.add_argument("--final-time", type=float, metavar="SECONDS",
                        help="time at which the error is measured (default: 0.5 s)")
    parser.add_argument("--png", default="convergence.png", metavar="PATH",
                        help="the log-log plot of error against dt (default: convergence.png)")
    add_worker_arguments(parser)


def run(args) -> int:
    from ..convergence import FINAL_TIME, measure_convergence
    from ..errors import require
    from ..integrators import integrator_names
    from ..runner import WorkerLost, check_workers
    from ..safe_files import check_output_path

    integrators = args.integrators or integrator_names()
    for name in integrators:
        require(name in integrator_names(), "integrator", name,
                "must be one of " + ", ".join(integrator_names()))
    final_time = FINAL_TIME if args.final_time is None else args.final_time
    require(math.isfinite(final_time) and 0 < final_time <= MAX_FINAL_TIME, "final-time",
            final_time, f"must be a time > 0 s and at most {MAX_FINAL_TIME:g} s")
    require(args.png.lower().endswith(".png"), "png", args.png, "must end in .png")
    check_output_path("--png", args.png)
    check_workers(args.workers)
    started = time.perf_counter()
    try:
        results = measure_convergence(integrators, final_time, workers=args.workers,
                                      dask=args.dask, parallel=True)
    except WorkerLost as error:
        print(f"springsim convergence: a run was lost: {error}", file=sys.stderr)
        return 1
    elapsed = time.perf_counter() - started
    print("\n".join(table_lines(results)))
    plot_convergence(args.png, results, final_time)
    print(f"\nreference: solve_ivp DOP853, rtol = atol = 1e-12; error: largest position error at "
          f"t = {final_time:g} s. {elapsed:.0f} s. Wrote {args.png}.")
    return 0


def table_lines(results) -> list[str]:
    width = max(len("integrator"), *(len(r.integrator) for r in results))
    lines = [f"{'integrator':<{width}}  expected  measured  errors (m) at dt = ..."]
    for result in results:
        errors = "  ".join(f"{dt:.3g}: {error:.2e}" for dt, error in zip(result.dts,
                                                                           result.errors))
        lines.append(f"{result.integrator:<{width}}  {result.expected_order:>8}  "
                     f"{result.slope:>8.2f}  {errors}")
    return lines


def plot_convergence(path, results, final_time: float) -> None:
    """Error against dt on log-log axes, one line per integrator, written whole or not at all."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from ..recording import atomic_output

    figure = Figure(figsize=(8, 5.5), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    styles = [("o", "-"), ("s", "-"), ("^", "-"), ("D", "-"), ("v", "--"), ("x", ":")]
    for k, result in enumerate(results):
        marker, line = styles[k % len(styles)]   # methods with equal errors stay distinguishable
        axes.loglog(result.dts, result.errors, marker=marker, linestyle=line,
                    label=f"{result.integrator}: slope {result.slope:.2f} "
                          f"(order {result.expected_order})")
    axes.set_xlabel("time step dt (s)")
    axes.set_ylabel(f"largest position error at t = {final_time:g} s (m)")
    axes.set_title("Convergence on a squeezed cube (no gravity, no contact) "
                   "against DOP853 at rtol 1e-12", fontsize="medium")
    axes.grid(which="both", alpha=0.3)
    axes.legend(fontsize="small")
    with atomic_output(path) as file:
        figure.savefig(file, format="png")
