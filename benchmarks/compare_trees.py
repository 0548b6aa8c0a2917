"""Compare the speed of this checkout with another one, row by row of the README's table.

    .venv/bin/python benchmarks/compare_trees.py /path/to/other/checkout [--rows a,b] [--pairs 3]

A shared machine's speed drifts by 10% or more from minute to minute, so each row is measured
as ``--pairs`` pairs of runs, one of each tree, taken one right after the other (the order
alternating from pair to pair), and the table gives the ratios this / other of each pair and
their median. Both trees run with this checkout's Python environment; the other's code is put
first on the path (PYTHONPATH=OTHER/src). Each tree compiles its kernels into its own cache
folder (the folder is named after a hash of the kernel sources), so a first, uncounted run of
each row warms both.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

from readme_table import ROWS

HERE = Path(__file__).resolve().parent.parent


def bench(source, scene, integrator, dt, overrides, threads, length_flag, length):
    command = [sys.executable, "-m", "springsim", "bench", scene, "--integrator", integrator,
               "--dt", str(dt), "--threads", str(threads), length_flag, length, "--json"]
    for override in overrides:
        command += ["--set", override]
    environment = {**os.environ, "PYTHONPATH": str(source)}
    result = subprocess.run(command, check=True, capture_output=True, text=True,
                            env=environment)
    return json.loads(result.stdout)["steps_per_second"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("other", type=Path, help="the other checkout (its src/ is used)")
    parser.add_argument("--rows", default=",".join(ROWS))
    parser.add_argument("--pairs", type=int, default=3)
    args = parser.parse_args()
    names = [name.strip() for name in args.rows.split(",") if name.strip()]
    unknown = [name for name in names if name not in ROWS]
    if unknown:
        parser.error(f"--rows: unknown {', '.join(unknown)}; benchmarks/readme_table.py --list")
    trees = {"this": HERE / "src", "other": args.other.resolve() / "src"}
    print("| row | this (steps/s) | other (steps/s) | ratios this/other | median |")
    print("|---|---|---|---|---|")
    for name in names:
        for source in trees.values():   # warm both caches
            bench(source, *ROWS[name])
        speeds = {"this": [], "other": []}
        for pair in range(args.pairs):
            order = ["this", "other"] if pair % 2 == 0 else ["other", "this"]
            for tree in order:
                speeds[tree].append(bench(trees[tree], *ROWS[name]))
        ratios = [a / b for a, b in zip(speeds["this"], speeds["other"])]
        print(f"| {name} | {', '.join(f'{s:,.0f}' for s in speeds['this'])} "
              f"| {', '.join(f'{s:,.0f}' for s in speeds['other'])} "
              f"| {', '.join(f'{r:.3f}' for r in ratios)} | {statistics.median(ratios):.3f} |",
              flush=True)


if __name__ == "__main__":
    main()
