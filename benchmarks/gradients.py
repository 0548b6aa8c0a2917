"""The cost of a gradient against the forward run it is of (issue 32's speed and memory bars).

    .venv/bin/python benchmarks/gradients.py cloth [--duration 1] [--repeats 3]
    .venv/bin/python benchmarks/gradients.py cube [--duration 1] [--repeats 3]
    .venv/bin/python benchmarks/gradients.py stack [--duration 0.5] [--repeats 2]
    .venv/bin/python benchmarks/gradients.py stack-implicit [--duration 0.5] [--repeats 1]
    .venv/bin/python benchmarks/gradients.py landing-implicit [--duration 2] [--repeats 2]
    .venv/bin/python benchmarks/gradients.py memory [--duration 10]

``cloth``: the 100 x 100 hanging cloth (cloth-hang, self-collision off) under implicit_euler at
dt = 1/60 s; ``cube``: the default jelly cube (jelly-plane) under rk4 at dt = 1e-3 s; ``stack``:
jelly-stack's three cubes under rk4 at dt = 1e-3 s, which land on the floor and on each other
(the adjoint's NumPy path through terrain and body-body contact); ``stack-implicit``: the same
under implicit_euler at dt = 1/60 s (the contact replay with the penalty contacts beside the
terrain constraints, solved directly); ``landing-implicit``: the default cube (jelly-plane)
under implicit_euler at dt = 1/60 s, which lands on the floor after 1.3 s and rests there (the
terrain replay's solves of 3,000 unknowns). Each repeat
times the forward run (``Simulation.advance``) and then the gradient of the mean height at 30 fps
with respect to the structural ks (``springsim.gradient``: the forward run again, recording,
and the backward pass), alternately, since the machine's speed drifts; it prints both and their
ratio per repeat, and the range of the ratios. Both are warmed (compiled or loaded from the
cache) by a short run first, and one full gradient is timed before the repeats: the first in a
process takes its tape's memory fresh from the system (page faults), which later ones reuse.

``kernels``: the cube's parts, each timed over 200 calls, 3 times: the forward rk4 step, the
adjoint's spring force loop and its VJP one spring at a time (gradients/kernels.py), and one
step's adjoint (run_kernels.rk4_step_vjp: four force loops and four VJPs on springs in runs).

``memory``: the cloth's gradient over ``--duration`` s in a child process; prints the child's
peak resident memory (ru_maxrss) and the bytes of states the tape held.
"""
import argparse
import resource
import subprocess
import sys
import time

import numpy as np

CASES = {
    "cloth": ("cloth-hang", ["bodies.0.particles_per_edge=100", "bodies.0.self_collision=false"],
              "implicit_euler", 1 / 60),
    "cube": ("jelly-plane", [], "rk4", 1e-3),
    "stack": ("jelly-stack", [], "rk4", 1e-3),
    "stack-implicit": ("jelly-stack", [], "implicit_euler", 1 / 60),
    "landing-implicit": ("jelly-plane", [], "implicit_euler", 1 / 60),
}


def mean_height(positions):
    """The mean height over every frame and particle (m), and its gradient."""
    grad = np.zeros_like(positions)
    grad[:, :, 1] = 1.0 / (positions.shape[0] * positions.shape[1])
    return float(positions[:, :, 1].mean()), grad


def setup(case):
    import springsim

    name, sets, integrator, dt = CASES[case]
    return springsim.load_scene(name, sets), {"integrator": integrator, "dt": dt}


def timed(case: str, duration: float, repeats: int) -> None:
    import springsim
    from springsim.gradients import gradient

    scene, options = setup(case)
    wrt = ["bodies.0.structural.ks"]
    springsim.Simulation(scene, **options).advance(5 * options["dt"])   # warm
    gradient(scene, mean_height, wrt, duration=5 * options["dt"], fps=30, **options)
    # the first full gradient in a process takes its tape's memory fresh from the system,
    # which a later one reuses: timed apart, not among the repeats
    began = time.perf_counter()
    gradient(scene, mean_height, wrt, duration=duration, fps=30, **options)
    print(f"{case} {duration:g} s: the first gradient in this process "
          f"{time.perf_counter() - began:.2f} s (fresh memory)", flush=True)
    ratios = []
    for repeat in range(repeats):
        simulation = springsim.Simulation(scene, **options)
        began = time.perf_counter()
        simulation.advance(duration)
        forward = time.perf_counter() - began
        began = time.perf_counter()
        gradient(scene, mean_height, wrt, duration=duration, fps=30, **options)
        backward = time.perf_counter() - began
        ratios.append(backward / forward)
        print(f"{case} {duration:g} s: forward {forward:.2f} s, gradient {backward:.2f} s, "
              f"ratio {ratios[-1]:.2f}", flush=True)
    print(f"{case}: gradient / forward from {min(ratios):.2f} to {max(ratios):.2f} "
          f"({repeats} repeats)")


def memory(duration: float) -> None:
    """The gradient in a child process, so that its peak memory is the gradient's alone."""
    out = subprocess.run([sys.executable, __file__, "child", "--duration", str(duration)],
                         capture_output=True, text=True, check=True)
    print(out.stdout.strip())


def child(duration: float) -> None:
    from springsim.gradients import prepare, run_gradient
    from springsim.gradients.losses import as_loss

    scene, options = setup("cloth")
    _, simulation, _ = prepare(scene, ["bodies.0.structural.ks"], None, **options)
    result = run_gradient(simulation, as_loss(mean_height, 30), duration)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024   # Linux: KiB
    print(f"cloth {duration:g} s: peak resident memory {peak / 1e9:.2f} GB, states held "
          f"{result.stored_bytes / 1e9:.2f} GB")


def parts() -> None:
    import springsim
    from springsim.gradients import kernels, run_kernels
    from springsim.spring_runs import run_layout
    from springsim.gradients.physics import Cotangents, Physical

    scene, options = setup("cube")
    simulation = springsim.Simulation(scene, **options)
    simulation.advance(0.01)
    p = Physical.of(simulation.model)
    x = simulation.positions.copy()
    v = np.random.default_rng(0).normal(size=x.shape)
    g = v.copy()
    bar = Cotangents.zeros(p)
    x_bar, v_bar, force = np.zeros_like(x), np.zeros_like(x), np.zeros_like(x)
    work = np.empty((17, len(x), 3))
    layout = run_layout(p.a, p.b)
    table = run_kernels.entry_table(layout, p.ks, p.kd, p.rest)
    loose = kernels.Springs(*(values[layout.loose] for values in (p.a, p.b, p.ks, p.kd, p.rest)))
    particles = run_kernels.Particles(p.inv_mass, p.drag, p.gravity)
    bars = run_kernels.StepBars(bar.ks, bar.kd, bar.rest, bar.mass, bar.drag, bar.gravity)
    columns = np.empty((run_kernels.ROWS, len(x)))
    kept = np.empty((1, 4, len(x), 3))
    simulation.step_keeping(kept, np.empty((1, 2, len(x), 3)))
    kept = kept[0]
    calls = {
        "forward rk4 step": lambda: simulation.step(1),
        "force loop": lambda: kernels.add_spring_forces(p.a, p.b, p.ks, p.kd, p.rest, x, v,
                                                        force),
        "force VJP": lambda: kernels.add_spring_forces_vjp(
            kernels.Springs(p.a, p.b, p.ks, p.kd, p.rest), x, v, g, x_bar, v_bar,
            kernels.SpringBars(bar.ks, bar.kd, bar.rest)),
        "rk4 step adjoint": lambda: run_kernels.rk4_step_vjp(
            layout, table, loose, particles, options["dt"], (x, v), (x_bar, v_bar), bars, work,
            columns, np.empty((0, len(x), 3))),
        "the same, the stages kept": lambda: run_kernels.rk4_step_vjp(
            layout, table, loose, particles, options["dt"], (x, v), (x_bar, v_bar), bars, work,
            columns, kept),
    }
    print(f"cube: {len(x)} particles, {len(p.a)} springs")
    for _ in range(3):
        line = []
        for name, call in calls.items():
            call()
            began = time.perf_counter()
            for _ in range(200):
                call()
            line.append(f"{name} {(time.perf_counter() - began) / 200 * 1e6:.0f} us")
        print(", ".join(line), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", choices=[*CASES, "kernels", "memory", "child"])
    parser.add_argument("--duration", type=float)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    if args.case == "memory":
        memory(args.duration or 10.0)
    elif args.case == "child":
        child(args.duration)
    elif args.case == "kernels":
        parts()
    else:
        timed(args.case, args.duration or 1.0, args.repeats)


if __name__ == "__main__":
    main()
