"""Measure the figures of the README's speed table with `springsim bench` and print the table.

    .venv/bin/python benchmarks/readme_table.py

Each row is one `springsim bench ... --json` run in its own process (so that peak memory is the
row's own); run it on a quiet machine.
"""
import json
import platform
import subprocess
import sys

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


def main():
    print(f"Machine: {platform.processor() or platform.machine()}, "
          f"{subprocess.run(['nproc'], capture_output=True, text=True).stdout.strip()} cores, "
          f"Python {platform.python_version()}")
    print("| scene | integrator | dt (s) | particles | springs | steps/s | ms/step "
          "| real-time factor | build (s) | peak memory (MB) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for scene, integrator, dt, overrides, flag, length in ROWS:
        r = bench(scene, integrator, dt, overrides, flag, length)
        label = scene + (" " + " ".join(overrides) if overrides else "")
        print(f"| {label} | {integrator} | {dt:g} | {r['particles']:,} | {r['springs']:,} "
              f"| {r['steps_per_second']:,.0f} | {r['ms_per_step']:.3g} "
              f"| {r['real_time_factor']:.3g} | {r['build_seconds']:.3g} "
              f"| {r['peak_memory_mb']:,.0f} |", flush=True)


if __name__ == "__main__":
    main()
