"""Hash every built-in scene's state after a fixed time under every integrator, to check that a
change to the code leaves the trajectories as they were.

    .venv/bin/python scripts/trajectory_hashes.py OUT.npz              # this checkout's code
    PYTHONPATH=/other/checkout/src .venv/bin/python scripts/trajectory_hashes.py OTHER.npz
    .venv/bin/python scripts/trajectory_hashes.py --compare OTHER.npz OUT.npz
    .venv/bin/python scripts/trajectory_hashes.py OUT.npz --integrators implicit_euler

``--integrators`` and ``--scenes`` keep only those runs (``--compare`` compares the runs of the
first file).

Each run goes 1 s (cloth-balls-100, the benchmark scene, 0.05 s) at the scene's own step for the
explicit methods, and at 1/60 and 1/30 s for implicit_euler; a run that diverges stops there.
The file keeps x and v of every run; ``--compare`` prints, for each, whether the bits are the
same and else the largest difference in position (m) and velocity (m/s).
"""
import argparse
import hashlib
import sys
import time

import numpy as np


def runs(integrators=None, scenes=None):
    import springsim

    for scene in scenes or springsim.preset_names():
        seconds = 0.05 if scene == "cloth-balls-100" else 1.0
        for integrator in integrators or springsim.integrator_names():
            steps = [1 / 60, 1 / 30] if integrator == "implicit_euler" else [None]
            for dt in steps:
                yield scene, integrator, dt, seconds


def simulate(scene, integrator, dt, seconds):
    import springsim

    sim = springsim.Simulation(springsim.load_scene(scene), integrator=integrator, dt=dt,
                               threads=1)
    steps = round(seconds / sim.dt)
    try:
        sim.step(steps)
        ending = "ran"
    except springsim.SimulationDiverged:
        ending = f"diverged at step {sim.steps_taken}"
    return sim.positions.copy(), sim.velocities.copy(), ending


def record(path, integrators=None, scenes=None):
    arrays = {}
    for scene, integrator, dt, seconds in runs(integrators, scenes):
        name = f"{scene}|{integrator}|{'scene' if dt is None else f'{dt:.6f}'}"
        started = time.perf_counter()
        x, v, ending = simulate(scene, integrator, dt, seconds)
        digest = hashlib.sha256(x.tobytes() + v.tobytes()).hexdigest()[:16]
        print(f"{name:50s} {digest} {ending} ({time.perf_counter() - started:.1f} s)",
              flush=True)
        arrays[name + "|x"], arrays[name + "|v"] = x, v
    np.savez(path, **arrays)


def compare(before_path, after_path):
    before, after = np.load(before_path), np.load(after_path)
    names = sorted({key.rsplit("|", 1)[0] for key in before.files})
    same = 0
    for name in names:
        x0, v0 = before[name + "|x"], before[name + "|v"]
        x1, v1 = after[name + "|x"], after[name + "|v"]
        if x0.tobytes() == x1.tobytes() and v0.tobytes() == v1.tobytes():
            same += 1
            print(f"{name:50s} bit-identical")
            continue
        with np.errstate(invalid="ignore"):
            dx, dv = np.nanmax(np.abs(x1 - x0)), np.nanmax(np.abs(v1 - v0))
        print(f"{name:50s} DIFFERS: |dx| <= {dx:.3g} m, |dv| <= {dv:.3g} m/s")
    print(f"{same} of {len(names)} runs bit-identical")
    return same == len(names)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="+")
    parser.add_argument("--compare", action="store_true")
    parser.add_argument("--integrators", nargs="+", help="only these (default: every one)")
    parser.add_argument("--scenes", nargs="+", help="only these built-in scenes (default: all)")
    arguments = parser.parse_args()
    if arguments.compare:
        sys.exit(0 if compare(*arguments.paths) else 1)
    record(arguments.paths[0], arguments.integrators, arguments.scenes)


if __name__ == "__main__":
    main()
