"""Measure the figures of the README's speed table with `springsim bench` and print the table.

    .venv/bin/python benchmarks/readme_table.py

Each row is ``REPEATS`` runs of `springsim bench ... --json`, each in its own process (so that
peak memory is the row's own); the table gives the run with the median speed and the range of
all runs, since a shared machine's speed drifts by 10% or more from minute to minute.
"""
import json
import platform
import subprocess
import sys

REPEATS = 3

ROWS = [
    ("jelly-plane", "rk4", 0.001, [], "--seconds", "5"),
    ("jelly-plane", "midpoint", 0.001, [], "--seconds", "5"),
    ("jelly-plane", "symplectic_euler", 0.001, [], "--seconds", "5"),
    ("jelly-plane", "explicit_euler", 0.001, [], "--seconds", "5"),
    ("jelly-plane", "implicit_euler", 0.016667, [], "--seconds", "5"),
    ("jelly-plane", "implicit_euler", 0.033333, [], "--seconds", "5"),
    ("cloth-balls", "rk4", 0.0001, [], "--seconds", "5"),
    ("cloth-balls", "explicit_euler", 0.0001, [], "--seconds", "5"),
    ("cloth-balls-100", "rk4", 0.0001, [], "--seconds", "5"),
    ("jelly-plane", "rk4", 0.001, ["bodies.0.particles_per_edge=100"], "--steps", "3"),
]


def bench(scene, integrator, dt, overrides, length_flag, length):
    command = [sys.executable, "-m", "springsim", "bench", scene, "--integrator", integrator,
               "--dt", str(dt), length_flag, length, "--json"]
    for override in overrides:
        command += ["--set", override]
    return json.loads(subprocess.run(command, check=True, capture_output=True,
                                     text=True).stdout)


def rate(run) -> str:
    """Steps per second, to the step (with three digits below 100)."""
    value = run["steps_per_second"]
    return f"{value:,.0f}" if value >= 100 else f"{value:.3g}"


def main():
    print(f"Machine: {platform.processor() or platform.machine()}, "
          f"{subprocess.run(['nproc'], capture_output=True, text=True).stdout.strip()} cores, "
          f"Python {platform.python_version()}")
    print("| scene | integrator | dt (s) | particles | springs | steps/s | range of "
          f"{REPEATS} runs | ms/step | real-time factor | build (s) | peak memory (MB) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for scene, integrator, dt, overrides, flag, length in ROWS:
        runs = sorted((bench(scene, integrator, dt, overrides, flag, length)
                       for _ in range(REPEATS)), key=lambda run: run["steps_per_second"])
        r = runs[len(runs) // 2]
        speeds = f"{rate(runs[0])} to {rate(runs[-1])}"
        label = scene + (" " + " ".join(overrides) if overrides else "")
        print(f"| {label} | {integrator} | {dt:g} | {r['particles']:,} | {r['springs']:,} "
              f"| {rate(r)} | {speeds} | {r['ms_per_step']:.3g} "
              f"| {r['real_time_factor']:.3g} | {r['build_seconds']:.3g} "
              f"| {r['peak_memory_mb']:,.0f} |", flush=True)


if __name__ == "__main__":
    main()
