"""Measure the figures of the README's speed table with `springsim bench` and print the table.

    .venv/bin/python benchmarks/readme_table.py [--rows NAME,NAME,...] [--repeats 3]

Each row is ``--repeats`` runs of `springsim bench ... --json`, each in its own process (so that
peak memory is the row's own); the table gives the run with the median speed and the range of
all runs, since a shared machine's speed drifts by 10% or more from minute to minute. All rows
take about 5 minutes on a 2-core machine; ``--rows`` picks some (``--list`` names them).
"""
import argparse
import json
import platform
import subprocess
import sys

CUBE_30 = ["bodies.0.particles_per_edge=30"]
CUBE_100 = ["bodies.0.particles_per_edge=100"]
CLOTH_100 = ["bodies.0.particles_per_edge=100"]
CLOTH_200 = ["bodies.0.particles_per_edge=200"]

# name: (scene, integrator, dt, overrides, threads, length flag, length)
ROWS = {
    "rk4": ("jelly-plane", "rk4", 0.001, [], 1, "--seconds", "3"),
    "midpoint": ("jelly-plane", "midpoint", 0.001, [], 1, "--seconds", "3"),
    "symplectic": ("jelly-plane", "symplectic_euler", 0.001, [], 1, "--seconds", "3"),
    "explicit": ("jelly-plane", "explicit_euler", 0.001, [], 1, "--seconds", "3"),
    "rk4-2": ("jelly-plane", "rk4", 0.001, [], 2, "--seconds", "3"),
    "implicit": ("jelly-plane", "implicit_euler", 0.016667, [], 1, "--seconds", "3"),
    "implicit-30": ("jelly-plane", "implicit_euler", 0.033333, [], 1, "--seconds", "3"),
    "cloth-rk4": ("cloth-balls", "rk4", 0.0001, [], 1, "--seconds", "3"),
    "cloth-explicit": ("cloth-balls", "explicit_euler", 0.0001, [], 1, "--seconds", "3"),
    "cloth-implicit": ("cloth-balls", "implicit_euler", 0.016667, [], 1, "--seconds", "3"),
    "cloth-100-rk4": ("cloth-balls-100", "rk4", 0.0001, [], 1, "--seconds", "3"),
    "cloth-hang-100": ("cloth-hang", "implicit_euler", 0.016667, CLOTH_100, 1, "--seconds", "3"),
    "cloth-hang-200": ("cloth-hang", "implicit_euler", 0.016667,
                       CLOTH_200, 1, "--steps", "20"),
    "cube-30": ("jelly-plane", "implicit_euler", 0.016667, CUBE_30, 1, "--seconds", "3"),
    "cube-100": ("jelly-plane", "rk4", 0.001, CUBE_100, 1, "--steps", "3"),
    "cube-100-2": ("jelly-plane", "rk4", 0.001, CUBE_100, 2, "--steps", "3"),
}


def bench(scene, integrator, dt, overrides, threads, length_flag, length):
    command = [sys.executable, "-m", "springsim", "bench", scene, "--integrator", integrator,
               "--dt", str(dt), "--threads", str(threads), length_flag, length, "--json"]
    for override in overrides:
        command += ["--set", override]
    return json.loads(subprocess.run(command, check=True, capture_output=True,
                                     text=True).stdout)


def rate(run) -> str:
    """Steps per second, to the step (with three digits below 100)."""
    value = run["steps_per_second"]
    return f"{value:,.0f}" if value >= 100 else f"{value:.3g}"


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--rows", default=",".join(ROWS), help="names of the rows to measure")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--list", action="store_true", help="name the rows and stop")
    args = parser.parse_args()
    if args.list:
        for name, row in ROWS.items():
            print(f"{name:16s} {row}")
        return
    names = [name.strip() for name in args.rows.split(",") if name.strip()]
    unknown = [name for name in names if name not in ROWS]
    if unknown:
        parser.error(f"--rows: unknown {', '.join(unknown)}; --list names them")
    print(f"Machine: {platform.processor() or platform.machine()}, "
          f"{subprocess.run(['nproc'], capture_output=True, text=True).stdout.strip()} cores, "
          f"Python {platform.python_version()}")
    print("| scene | integrator | dt (s) | threads | particles | springs | steps/s | range of "
          f"{args.repeats} runs | ms/step | real-time factor | build (s) | peak memory (MB) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        scene, integrator, dt, overrides, threads, flag, length = ROWS[name]
        runs = sorted((bench(*ROWS[name]) for _ in range(args.repeats)),
                      key=lambda run: run["steps_per_second"])
        r = runs[len(runs) // 2]
        speeds = f"{rate(runs[0])} to {rate(runs[-1])}"
        label = scene + (" " + " ".join(overrides) if overrides else "")
        print(f"| {label} | {integrator} | {dt:g} | {threads} | {r['particles']:,} "
              f"| {r['springs']:,} | {rate(r)} | {speeds} | {r['ms_per_step']:.3g} "
              f"| {r['real_time_factor']:.3g} | {r['build_seconds']:.3g} "
              f"| {r['peak_memory_mb']:,.0f} |", flush=True)


if __name__ == "__main__":
    main()
