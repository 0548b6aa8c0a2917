"""The plane's contact after terrains became an open set: jelly-plane steps/s, this tree against
another checkout's (before), in one run.

    .venv/bin/python benchmarks/terrain_dispatch.py --before /path/to/other/checkout/src

Each tree runs in its own process (its own Numba cache), alternately, ROUNDS times; the cube has
landed and rests on the plane while it is timed (best of five blocks of 1000 steps), so every
step includes contact. Prints steps/s
and the after/before ratio per integrator (median over the rounds).
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent / "src"
ROUNDS = 3
CHILD = """
import json, sys, time
import springsim
result = {}
for name in sys.argv[1:]:
    sim = springsim.Simulation(springsim.load_scene("jelly-plane"), integrator=name, dt=1e-3)
    sim.step(1500)                       # compile, fall and land
    best = float("inf")
    for _ in range(5):                   # best of five: the machine's load comes and goes
        start = time.perf_counter()
        sim.step(1000)
        best = min(best, time.perf_counter() - start)
    result[name] = 1000 / best
print(json.dumps(result))
"""


def steps_per_second(source: Path, integrators) -> dict:
    env = {**os.environ, "PYTHONPATH": str(source), "NUMBA_NUM_THREADS": "1"}
    output = subprocess.run([sys.executable, "-c", CHILD, *integrators], env=env, check=True,
                            capture_output=True, text=True).stdout
    return json.loads(output.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, type=Path, help="the other tree's src folder")
    parser.add_argument("--integrators", default="rk4,explicit_euler")
    args = parser.parse_args()
    integrators = args.integrators.split(",")
    runs = {"before": [], "after": []}
    for _ in range(ROUNDS):
        runs["before"].append(steps_per_second(args.before, integrators))
        runs["after"].append(steps_per_second(HERE, integrators))
    for name in integrators:
        before = [r[name] for r in runs["before"]]
        after = [r[name] for r in runs["after"]]
        ratios = [a / b for a, b in zip(after, before)]
        print(f"{name:16s} before {statistics.median(before):8.0f} steps/s  after "
              f"{statistics.median(after):8.0f} steps/s  after/before {statistics.median(ratios):.3f}"
              f" (rounds: {', '.join(f'{r:.3f}' for r in ratios)})")


if __name__ == "__main__":
    main()
