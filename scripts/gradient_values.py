"""Record the gradients issue 54 holds to 1e-9 relative across a refactor, and compare two records.

    .venv/bin/python scripts/gradient_values.py OUT.npz            # this checkout's code
    .venv/bin/python scripts/gradient_values.py --compare BEFORE.npz AFTER.npz

Cases: the default cube (jelly-plane) under rk4 at 1e-3 s for 2 s (it lands at about 1.3 s);
the 100 x 100 hanging cloth (cloth-hang, self-collision off) under implicit_euler at 1/60 s for
0.5 s; jelly-stack through terrain and body-body contact under rk4 at 1e-3 s for 1.5 s, and
under implicit_euler at 1/60 s for 0.5 s (as benchmarks/gradients.py stack-implicit: later, its
body-body contacts change within a solve's tolerance, which the implicit replay refuses); the
flag in its gusty wind (12 x 12) under rk4 and implicit_euler; the default cube landing and
resting on the plane, and the cubes on the sphere and the tilted plane, under implicit_euler at
1/60 s (the terrain contact replay: floors, releases, friction dampers). Each is the gradient of the mean
height at 30 fps with respect to the parameters listed (springsim.gradient).
"""
import argparse
import sys

import numpy as np

CASES = {
    "cube-rk4": ("jelly-plane", [], "rk4", 1e-3, 2.0,
                 ["bodies.0.structural.ks", "bodies.0.shear.kd", "bodies.0.particle_mass",
                  "terrains.0.friction"]),
    "cloth-implicit": ("cloth-hang", ["bodies.0.particles_per_edge=100",
                                      "bodies.0.self_collision=false"],
                       "implicit_euler", 1 / 60, 0.5,
                       ["bodies.0.structural.ks", "bodies.0.bend.kd"]),
    "stack-rk4": ("jelly-stack", [], "rk4", 1e-3, 1.5,
                  ["bodies.0.structural.ks", "bodies.1.particle_mass", "terrains.0.friction"]),
    "stack-implicit": ("jelly-stack", [], "implicit_euler", 1 / 60, 0.5,
                       ["bodies.0.structural.ks", "bodies.1.particle_mass", "terrains.0.friction"]),
    "landing-implicit": ("jelly-plane", [], "implicit_euler", 1 / 60, 1.6,
                         ["bodies.0.structural.ks", "terrains.0.friction"]),
    "sphere-implicit": ("jelly-sphere", [], "implicit_euler", 1 / 60, 1.0,
                        ["bodies.0.structural.ks", "terrains.0.friction"]),
    "tilted-implicit": ("jelly-tilted", [], "implicit_euler", 1 / 60, 1.5,
                        ["bodies.0.structural.ks", "terrains.0.friction"]),
    "flag-rk4": ("flag", ["bodies.0.particles_per_edge=12"], "rk4", 5e-4, 0.1,
                 ["bodies.0.structural.ks", "wind.drag", "wind.gusts.strength"]),
    "flag-implicit": ("flag", ["bodies.0.particles_per_edge=12"], "implicit_euler", 1 / 60,
                      0.5, ["bodies.0.structural.ks", "wind.drag", "wind.gusts.strength"]),
}


ZERO = 1e-15   # a gradient this small on both sides is zero (by symmetry) on both


def mean_height(positions):
    grad = np.zeros_like(positions)
    grad[:, :, 1] = 1.0 / (positions.shape[0] * positions.shape[1])
    return float(positions[:, :, 1].mean()), grad


def record(path, names):
    import springsim
    from springsim.gradients import gradient

    arrays = {}
    for name in names:
        scene_name, sets, integrator, dt, duration, wrt = CASES[name]
        scene = springsim.load_scene(scene_name, sets)
        try:
            _, grads = gradient(scene, mean_height, wrt, duration=duration, fps=30,
                                integrator=integrator, dt=dt)
        except Exception as error:   # a case the code cannot differentiate: say so, go on
            print(f"{name}: {type(error).__name__}: {error}", flush=True)
            continue
        for key in wrt:
            arrays[f"{name}|{key}"] = np.asarray(grads[key], float)
            print(f"{name:16s} {key:28s} {np.asarray(grads[key]).ravel()[:3]}", flush=True)
    np.savez(path, **arrays)


def compare(before_path, after_path, tolerance=1e-9):
    before, after = np.load(before_path), np.load(after_path)
    worst, failed = 0.0, False
    for key in sorted(before.files):
        if key not in after.files:
            print(f"{key:46s} MISSING after")
            failed = True
            continue
        a, b = before[key], after[key]
        scale = max(np.abs(a).max(), np.abs(b).max())
        # a gradient that is zero by symmetry is zero to round-off on both sides
        error = float(np.abs(a - b).max() / scale) if scale > ZERO else 0.0
        worst = max(worst, error)
        failed |= not error <= tolerance
        print(f"{key:46s} relative difference {error:.3g}")
    print(f"largest relative difference {worst:.3g} (bar {tolerance:g})")
    return not failed


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="+")
    parser.add_argument("--compare", action="store_true")
    parser.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    arguments = parser.parse_args()
    if arguments.compare:
        sys.exit(0 if compare(*arguments.paths) else 1)
    record(arguments.paths[0], arguments.cases)


if __name__ == "__main__":
    main()
