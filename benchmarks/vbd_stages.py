"""Where a vertex block descent step's time goes: the stages of integrators/vbd's step and of the
pass after it, called one by one from Python and timed, for a scene after it has run a while.

    .venv/bin/python benchmarks/vbd_stages.py cape [--at 1.0] [--steps 30]
    .venv/bin/python benchmarks/vbd_stages.py cloth-100 [--at 0.5] [--steps 30]

Prints milliseconds a step for each stage, serially (one thread): the world at the step's start
and end (a deforming terrain's refit), the first guess, the terrain planes, the terms'
linearization, the sweeps, the velocities and friction memory, and the pass after the step
(terrain impacts, the surface pair list kept or renewed, the body-body impulses and overlap
corrections). The calls are those ``vbd_step`` and ``_steps.drive`` make, in their order, so the
run is the simulation's own: it ends where Simulation.step ends, positions and velocities bit
for bit, which it checks. Each call crosses from Python (a few microseconds, times the colours
and iterations for the sweeps); the shares are what it is for. Then it times whole steps,
serial and threaded (the kernel ``Simulation.step`` runs), for comparison. The first run
compiles each stage for a call from Python (cached after).
"""
import argparse
import time
from collections import defaultdict

import numba
import numpy as np
from numba import njit

from springsim import Simulation, load_scene
from springsim.clock import CALL_START
from springsim.collision.pair_lists.keeping import pairs_at
from springsim.collision.pipeline import ball_pairs, respond_to_contacts
from springsim.collision.response.terrain import resolve_terrain_impacts
from springsim.attachments import hold_attachments
from springsim.integrators import _steps
from springsim.integrators import vbd as method
from springsim.integrators.implicit_euler import ImplicitState
from springsim.world import (aim_pins, move_world, place_pins, step_end, surface_velocity,
                             terrain_view)

H = 1.0 / 60.0
SCENES = {
    "cape": (lambda: load_scene("cape"), 1.0),
    "cloth-100": (lambda: load_scene("cloth-hang", ["bodies.0.particles_per_edge=100"]), 0.5),
}


class Timer:
    """Seconds spent in each named stage."""

    def __init__(self):
        self.seconds = defaultdict(float)
        self.renewed = 0   # steps whose pair list was renewed (found afresh, age 0)

    def __call__(self, name, function, *arguments):
        start = time.perf_counter()
        result = function(*arguments)
        self.seconds[name] += time.perf_counter() - start
        return result


@njit(cache=True)
def velocity_lookups(model, x, planes):
    """The surface velocity lookups find_terrain_planes makes for moving terrains, again: what
    they cost of the planes (a deforming mesh's is a second closest-triangle search)."""
    terrains = terrain_view(model)
    total = 0.0
    for i in range(x.shape[0]):
        for t in range(planes.shape[1]):
            still = model.terrain_motion[t] < 0 and model.terrain_deforming[t] < 0
            if planes[i, t, 3] < np.inf and not still:
                total += surface_velocity(terrains, t, x[i, 0], x[i, 1], x[i, 2])[0]
    return total


def staged_steps(sim, steps, timer):
    """``steps`` of sim's vbd steps, stage by stage (vbd.vbd_step and _steps.drive's order)."""
    integrator, model, state = sim.integrator, sim.model, sim.state
    arrays = model.arrays
    graph, layout = integrator.tables(model)
    x, v, memory = state.positions, state.velocities, state.contacts
    scratch = method.vbd_scratch(graph, integrator.settings, layout, x,
                                 arrays.terrain_epsilon.shape[0], H)
    _, settings, layout, x0, y, v_k, term_force, term_blocks, planes, kd_over_h = scratch
    arrays.clock[CALL_START] = state.time
    pairs = _steps.pairs_now(arrays, x, state.pairs)
    start = _steps.step_start(arrays, x)
    colours = graph.colour_start.shape[0] - 1
    for done in range(steps):
        timer("world at the step's start", _steps.start_step, arrays, x, v, done, H)
        timer("world at the step's start", _steps.copy_positions, start, x)
        timer("world at the step's end", move_world, arrays, step_end(arrays, H))
        timer("world at the step's end", aim_pins, arrays, x, v, H)
        timer("first guess", method.start_guess, arrays, x, v, memory.velocity_change, H, x0, y)
        timer("terrain planes", method.find_terrain_planes, arrays, x, planes)
        timer("(again: velocity lookups alone)", velocity_lookups, arrays, x, planes)
        for _ in range(settings.iterations):
            if layout.terms:
                timer("terms", method.linearize_terms, arrays, layout, x, x0, H, v_k, term_force,
                      term_blocks)
            for colour in range(colours):
                timer("sweeps", method.sweep, arrays, graph, settings, colour, x, x0, y,
                      term_force, term_blocks, planes, memory, H, kd_over_h)
        timer("velocities, friction", method.end_velocities, arrays, planes, x, x0, v,
              memory.velocity_change, H)
        timer("velocities, friction", method.keep_friction, arrays, settings, x, planes,
              memory, H)
        # _steps.collide and pipeline.resolve_contacts, stage by stage
        timer("after: world, pins", move_world, arrays, step_end(arrays, H))
        timer("after: world, pins", place_pins, arrays, x, v)
        timer("after: world, pins", hold_attachments, arrays, x, v)
        timer("after: terrain impacts", resolve_terrain_impacts, arrays, x, v)
        if arrays.surface_triangles.shape[0] > 0:
            pairs.age[0] += 1
            pairs = timer("after: pair list", pairs_at, arrays, x, pairs)
            timer.renewed += pairs.age[0] == 0
        balls = ball_pairs(x, arrays.radius, arrays.balls, arrays.ball_slot)
        if pairs.points.shape[0] + pairs.edges.shape[0] + balls.shape[0] > 0:
            timer("after: contacts", respond_to_contacts, arrays, x, v, start, pairs.points,
                  pairs.edges, balls)
        assert _steps.first_diverged(x, v) < 0
    state.pairs = pairs
    state.time += steps * H
    state.steps += steps
    return colours


def whole_steps(build, at, steps, threads):
    """ms a step of Simulation.step over ``steps`` steps after ``at`` s, each timed."""
    sim = Simulation(build(), integrator="vbd", dt=H, threads=threads)
    sim.step(round(at / H))
    times = []
    for _ in range(steps):
        began = time.perf_counter()
        sim.step(1)
        times.append(time.perf_counter() - began)
    return np.array(times) * 1e3


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", choices=SCENES)
    parser.add_argument("--at", type=float, help="s run before timing (default: the scene's)")
    parser.add_argument("--steps", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=2, help="rounds of whole-step timing")
    args = parser.parse_args()
    build, at = SCENES[args.scene]
    at = at if args.at is None else args.at
    numba.set_num_threads(1)

    staged, reference = (Simulation(build(), integrator="vbd", dt=H, threads=1)
                         for _ in range(2))
    for sim in (staged, reference):
        sim.step(round(at / H))
    staged_steps(staged, 1, Timer())   # compiled before timing
    reference.step(1)
    timer = Timer()
    colours = staged_steps(staged, args.steps, timer)
    reference.step(args.steps)
    same = (np.array_equal(staged.positions, reference.positions)
            and np.array_equal(staged.velocities, reference.velocities))
    again = timer.seconds.pop("(again: velocity lookups alone)")
    total = sum(timer.seconds.values())
    print(f"{args.scene}: {staged.model.particle_count} particles, {colours} colours, "
          f"{staged.integrator.settings.iterations} iterations; {args.steps} steps from "
          f"{at:g} s, stage by stage, one thread (same bits as Simulation.step: {same})")
    print("| stage | ms a step | share |")
    print("|---|---|---|")
    for name, seconds in timer.seconds.items():
        print(f"| {name} | {seconds / args.steps * 1e3:.2f} | {seconds / total:.0%} |")
    print(f"| all | {total / args.steps * 1e3:.2f} | |")
    print(f"of the terrain planes, the moving terrains' surface velocity lookups: "
          f"{again / args.steps * 1e3:.2f} ms a step (timed again apart); the pair list was "
          f"renewed in {timer.renewed} of {args.steps} steps")
    for round_ in range(args.rounds):
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            times = whole_steps(build, at, args.steps, threads)
            print(f"whole steps, {threads} thread(s), round {round_ + 1}: median "
                  f"{np.median(times):.1f} ms (range {times.min():.1f} to {times.max():.1f})",
                  flush=True)


if __name__ == "__main__":
    main()
