"""`springsim sweep`: one scene over a grid of values, on every local core or a Dask cluster."""
import os
import sys

from ._workers import add_worker_arguments

NAME = "sweep"
HELP = ("run a scene for every combination of varied keys (and seeds) on every local core or "
        "a Dask cluster: OUT/results.csv, resumable")


def add_arguments(parser) -> None:
    parser.add_argument("scene", help="a built-in scene (see `springsim scenes`) or a .toml file")
    parser.add_argument("--vary", action="append", default=[], metavar="KEY=V1,V2|START:STOP:COUNT",
                        help="values of one scene key (any key --set takes, integrator and dt "
                             "included); COUNT evenly spaced values from START to STOP with "
                             "START:STOP:COUNT (repeatable: every combination runs)")
    parser.add_argument("--seeds", type=int, metavar="N",
                        help="run each combination N times, each with its seed's small random "
                             "nudge of the initial positions (1%% of the shortest spring)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change one key of the scene for every run (repeatable)")
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="simulated time of each run in s (default: the scene's)")
    parser.add_argument("--fps", type=float, default=60.0,
                        help="frames sampled per simulated second, for the results and --save "
                             "(default: 60)")
    parser.add_argument("--out", required=True, metavar="DIR",
                        help="the folder for results.csv (made if missing; runs already in it "
                             "are skipped)")
    parser.add_argument("--save", choices=["npz"],
                        help="also keep every run's recording as OUT/runs/run-<run_id>.npz")
    add_worker_arguments(parser)
    parser.add_argument("--plot", action="append", default=[], metavar="KEY:RESULT[:PATH]",
                        help="chart a result column against a varied key as "
                             "OUT/RESULT-vs-KEY.png, or as PATH (repeatable)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar and no summary")


def run(args) -> int:
    from ..sweeps import sweep

    table = sweep(args.scene, args.vary, duration=args.duration, seeds=args.seeds,
                  workers=args.workers, dask=args.dask, out=args.out, save=args.save,
                  fps=args.fps, overrides=args.set, plot=args.plot, progress=not args.quiet)
    if not args.quiet:
        counts = {}
        for row in table:
            counts[row["status"]] = counts.get(row["status"], 0) + 1
        summary = ", ".join(f"{count} {status}" for status, count in sorted(counts.items()))
        print(f"springsim sweep: {len(table)} runs ({summary}); wrote "
              f"{os.path.join(args.out, 'results.csv')}", file=sys.stdout)
    return 0
