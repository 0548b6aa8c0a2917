"""Where a backward Euler step's time goes: the stages of integrators/implicit_euler's step,
called one by one from Python and timed, for a built-in scene after it has run a while.

    .venv/bin/python benchmarks/implicit_stages.py cape --at 1.0 --steps 30 [--tolerance 1e-3]

Prints milliseconds a step for each stage (the conjugate-gradient solves, the contact updates
between them, the start-of-step contact search, the pass after the step, ...), then the linear
solves and conjugate-gradient iterations a step, and, for the first steps, each solve's
iterations with what the update before it changed: the terrain contacts it released and
joined, and how far it moved the friction dampers. The stages are the same calls
``backward_euler_step`` makes, in its order, so the run is the simulation's own: it ends
where Simulation.step ends, positions, velocities and contacts bit for bit, which it checks
(and it stops where a step needed halving or a self-contact redo, which it does not take).
"Terrain contact updates" is constraints.update_contacts alone: the products and the penalty
contacts' updates between solves fall in none of the stages named. A step timed this way costs a
little more than inside the compiled loop (each call crosses from Python); the shares are what
it is for. The first run compiles each stage for a call from Python (cached after).
"""
import argparse
import time
from collections import defaultdict

import numpy as np

import springsim
from springsim.collision.ccd.crossing_check import carried_through
from springsim.collision.contact_sets.solve import find_solve_contacts
from springsim.collision.pair_lists.own_pairs import any_self_collision, own_pairs_touching
from springsim.collision.response.penalty import (newton_iterations_needed,
                                                  update_active_contacts)
from springsim.implicit import cg, constraints
from springsim.implicit.step_record import no_record
from springsim.integrators import _steps
from springsim.integrators import implicit_euler as method
from springsim.world import aim_pins, move_world, step_end

CONTACT, FREE = constraints.CONTACT, constraints.FREE


class Timer:
    """Seconds spent in each named stage."""

    def __init__(self):
        self.seconds = defaultdict(float)

    def __call__(self, name, function, *arguments):
        start = time.perf_counter()
        result = function(*arguments)
        self.seconds[name] += time.perf_counter() - start
        return result


def solve(timer, model, scratch, state, contacts, h):
    """implicit_euler.solve_with_contacts, stage by stage; returns each solve's (iterations,
    contacts released, contacts joined, the friction dampers' change over their sum) by the
    update before it."""
    x, v, memory = state
    work, settings, layout = scratch.work, scratch.settings, scratch.layout
    pattern, kind, normal, floor = layout.diagonal, memory.kind, work.normal, memory.normal_floor
    system = (pattern, work.blocks, work.terms, contacts)
    timer("first guess", cg.mass_start, cg.FilteredSystem(*system, layout.coarse, kind, normal),
          work.rhs, model.inv_mass, memory.velocity_change, work.ddv,
          cg.CGWork(work.r, work.s, work.c, work.q))
    reference, log = 0.0, []
    released = joined = 0
    friction = 0.0
    for update in range(method.MAX_CONTACT_UPDATES + 1):
        if update > 0:
            cg.system_multiply(*system, work.ddv, work.q)
            _steps.add_scaled(work.reaction, work.q, -1.0, work.rhs)
            before, dampers = kind.copy(), memory.friction_damping.copy()
            changed = timer("terrain contact updates", constraints.update_contacts, model, pattern,
                            work.blocks, work.rhs, x, v, work.dv, work.ddv, h,
                            method.contact_slots(state, work), work.reaction, work.lookups)
            changed = update_active_contacts(contacts, h, work.ddv, work.rhs) > 0 or changed
            released = int(np.sum((before == CONTACT) & (kind == FREE)))
            joined = int(np.sum((before == FREE) & (kind == CONTACT)))
            moved = np.abs(memory.friction_damping - dampers).sum()
            friction = round(float(moved / max(memory.friction_damping.sum(), 1e-300)), 2)
            if not changed:
                break
        iterations, reference = timer(
            "conjugate gradients", cg.contact_cg,
            cg.FilteredSystem(*system, layout.coarse, kind, normal), work.rhs, work.ddv,
            settings.tolerance, settings.max_iterations, reference,
            cg.CGWork(work.r, work.s, work.c, work.q))
        cg.conserve_momentum(*system, work.rhs, kind, work.ddv, work.q)
        constraints.hold_all_constrained(kind, normal, floor, v, work.dv, work.ddv)
        log.append((iterations, released, joined, friction))
    return log


def step(timer, model, scratch, state, start, h, done, pairs):
    """One step as _steps.drive and backward_euler_step take it; returns (pairs, (terrain
    contacts at its start, its solves' log))."""
    x, v, memory = state
    work = scratch.work
    _steps.start_step(model, x, v, done, h)
    _steps.copy_positions(start, x)
    method.copy_state(scratch.start, state)
    timer("world at the step's end", move_world, model, step_end(model, h))
    aim_pins(model, x, v, h)
    timer("contact search", constraints.find_constraints, model, x, v, h,
          method.contact_slots(state, work), work.lookups)
    at_start = int(np.sum(memory.kind == CONTACT))
    own, pairs = timer("own pairs", own_pairs_touching, model, x, pairs)
    contacts = timer("body contacts", find_solve_contacts, model, x, v, h, scratch.solve_pairs,
                     own)
    method.start_estimate(state, work)
    if newton_iterations_needed(model, contacts, v, h, scratch.settings.newton_iterations) != 1:
        raise SystemExit("this driver takes one Newton iteration a step")
    timer("assembly", method.assemble_system, model, scratch.layout, state, work, contacts, h,
          True)
    log = solve(timer, model, scratch, state, contacts, h)
    if any_self_collision(model):
        grew, _, pairs = timer("own pairs", method.own_pairs_met, model, state, work, h, own,
                               pairs, True)
        if grew:
            raise SystemExit("a self-contact made a step solve again, which this driver does "
                             "not take")
    method.update_estimate(state, work, work.ddv, h)
    timer("end of step", method.end_step, model, state, work, contacts, h)
    if timer("crossing check", carried_through, model, scratch.start.x, x, pairs,
             scratch.solve_pairs):
        raise SystemExit("a step needed halving, which this driver does not take")
    pairs = timer("pass after the step", _steps.collide, model, x, v, start, pairs, h)
    return pairs, (at_start, log)


def scene_of(arguments):
    """The scene asked for, with the tolerance asked for."""
    scene = springsim.load_scene(arguments.scene)
    if arguments.tolerance is not None:
        scene.implicit.cg_tolerance = arguments.tolerance
    return scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scene", nargs="?", default="cape")
    parser.add_argument("--at", type=float, default=1.0, help="simulated seconds first (s)")
    parser.add_argument("--steps", type=int, default=30, help="steps timed")
    parser.add_argument("--tolerance", type=float,
                        help="the conjugate-gradient tolerance, instead of the scene's "
                             "([implicit] cg_tolerance)")
    arguments = parser.parse_args()
    simulation = springsim.Simulation(scene_of(arguments))
    if simulation.integrator.name != "implicit_euler":
        raise SystemExit(f"{arguments.scene} is not an implicit_euler scene")
    simulation.advance(arguments.at)
    integrator, state, model = simulation.integrator, simulation.state, simulation.model.arrays
    layout = integrator.solve_layout(simulation.model)
    settings = method.Settings(integrator.newton_iterations, integrator.cg_tolerance,
                               integrator.cg_max_iterations)
    h = float(simulation.dt)
    model.clock[0] = state.time
    implicit = method.ImplicitState(state.positions, state.velocities, state.contacts)
    work = method.workspace(layout, implicit.x, model.terrain_epsilon.shape[0])
    scratch = method.Scratch(layout, settings, work, state.solve_pairs, method.Statistics.zeros(),
                             method.saved_state(implicit), method.saved_state(implicit),
                             no_record())
    pairs = _steps.pairs_now(model, implicit.x, state.pairs)
    start = _steps.step_start(model, implicit.x)
    timer, logs = Timer(), []
    began = time.perf_counter()
    for done in range(arguments.steps):
        pairs, log = step(timer, model, scratch, implicit, start, h, done, pairs)
        logs.append(log)
    wall = time.perf_counter() - began
    same = springsim.Simulation(scene_of(arguments))
    same.advance(arguments.at)
    same.step(arguments.steps)
    if not (np.array_equal(same.positions, implicit.x)
            and np.array_equal(same.velocities, implicit.v)
            and np.array_equal(same.state.contacts.kind, implicit.memory.kind)):
        raise SystemExit("the stages did not take the simulation's own steps")
    steps = arguments.steps
    print(f"{arguments.scene}, {steps} steps from {arguments.at:g} s, conjugate-gradient "
          f"tolerance {settings.tolerance:g}: {wall / steps * 1e3:.1f} ms a step")
    for name, seconds in sorted(timer.seconds.items(), key=lambda item: -item[1]):
        print(f"  {name:26s} {seconds / steps * 1e3:8.2f} ms a step")
    solves = np.mean([len(log) for _, log in logs])
    iterations = np.mean([sum(entry[0] for entry in log) for _, log in logs])
    print(f"{solves:.2f} linear solves and {iterations:.0f} conjugate-gradient iterations a step")
    print("the first steps: terrain contacts at the start; each solve's (iterations, and of "
          "the update before it: contacts released, joined, the friction dampers' change over "
          "their sum)")
    for at_start, log in logs[:4]:
        print(f"   {at_start}: {log}")


if __name__ == "__main__":
    main()
