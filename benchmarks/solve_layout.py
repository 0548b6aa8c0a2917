"""What one conjugate-gradient iteration of implicit_euler costs on a material cloth, two ways
each, alternately in one process:

- the springs' product (cg.search_product) over runs cut where the springs' constants change
  (the force loop's runs, one parameter group each) against the solve's own runs, which take
  each spring's constants by its number (pattern.SolveLayout);
- the coarse space's band solve (coarse.band_solve) against the same sweeps in plain loops.

    .venv/bin/python benchmarks/solve_layout.py [--repeats 5] [SCENE ...]

Scenes as in benchmarks/preconditioner.py (default: cape, swing, swing-100). Each way runs 200
times inside one compiled loop, best of ``--repeats``; the products must agree to rounding.
"""
import argparse
import time

import numpy as np
from numba import njit

from cg_passes import fused as products
from preconditioner import scene_named
from springsim.collision.contact_sets.solve import no_contacts
from springsim.implicit.coarse import band_cholesky, band_solve, band_width
from springsim.implicit.jacobian import assemble_diagonal_and_terms
from springsim.implicit.spring_terms import spring_terms_like
from springsim.simulation import Simulation
from springsim.spring_runs import build_spring_runs

LOOPS = 200


@njit
def plain_band_solve(factor, y):
    """coarse.band_solve as it was: indexed loops, one running sum."""
    n, width = factor.shape[0], factor.shape[1] - 1
    for j in range(n):
        y[j] /= factor[j, 0]
        value = y[j]
        for d in range(1, min(width, n - 1 - j) + 1):
            y[j + d] -= factor[j, d] * value
    for j in range(n - 1, -1, -1):
        total = y[j]
        for d in range(1, min(width, n - 1 - j) + 1):
            total -= factor[j, d] * y[j + d]
        y[j] = total / factor[j, 0]


@njit
def solves(loops, factor, y, plain):
    for _ in range(loops):
        if plain:
            plain_band_solve(factor, y)
        else:
            band_solve(factor, y)


def grouped(layout, arrays):
    """The solve's layout with the force loop's runs: one parameter group each."""
    numbers = np.arange(len(arrays.springs), dtype=float)
    runs = build_spring_runs(arrays.springs, arrays.spring_group, numbers)
    loose = runs["loose_springs"].astype(np.int64)
    entries = runs["run_rest_length"].astype(np.int64)
    return layout._replace(runs=runs["spring_runs"], run_entries=len(entries),
                           entry_spring=entries, loose_springs=loose,
                           loose_pairs=arrays.springs[loose].astype(np.int64).reshape(-1, 2))


def best_of(repeats, timers):
    best = [np.inf] * len(timers)
    for _ in range(repeats):
        for k, timer in enumerate(timers):
            start = time.perf_counter()
            timer()
            best[k] = min(best[k], (time.perf_counter() - start) / LOOPS)
    return best


def product_timer(simulation, layout, s):
    x = simulation.state.positions
    blocks = np.empty((len(x), 3, 3))
    terms = spring_terms_like(layout.runs, layout.run_entries, layout.loose_pairs, x)
    assemble_diagonal_and_terms(simulation.model.arrays, layout, x, 1.0, 1 / 60, 1 / 3600,
                                blocks, terms)
    kind, normal = simulation.state.contacts.kind, np.zeros_like(x)
    c, q = np.zeros_like(x), np.empty_like(x)
    arguments = (layout.diagonal, blocks, terms, no_contacts(), kind, normal, s, c, q)
    products(1, *arguments)
    return (lambda: products(LOOPS, *arguments)), q


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scenes", nargs="*", default=["cape", "swing", "swing-100"])
    parser.add_argument("--repeats", type=int, default=5)
    arguments = parser.parse_args()
    rng = np.random.default_rng(1)
    for name in arguments.scenes:
        simulation = Simulation(scene_named(name))
        simulation.step(2)
        own = simulation.integrator.solve_layout(simulation.model)
        cut = grouped(own, simulation.model.arrays)
        s = rng.standard_normal(simulation.state.positions.shape)
        (fast, q_fast), (slow, q_slow) = (product_timer(simulation, layout, s)
                                          for layout in (own, cut))
        own_time, cut_time = best_of(arguments.repeats, [fast, slow])
        print(f"{name} ({len(s)} particles): product {own_time * 1e6:.0f} us over "
              f"{len(own.runs)} runs and {len(own.loose_pairs)} loose springs, against "
              f"{cut_time * 1e6:.0f} us over {len(cut.runs)} runs and {len(cut.loose_pairs)} "
              f"cut by constants: {cut_time / own_time:.2f}x faster; products differ by "
              f"{np.abs(q_fast - q_slow).max() / np.abs(q_slow).max():.1e} relative", flush=True)
        coarse = own.coarse
        if coarse.count:
            n = 3 * coarse.count
            factor = rng.random((n, band_width(coarse) + 1)) * 0.01
            factor[:, 0] += 10.0
            band_cholesky(factor)
            y, z = rng.random(n), rng.random(n)
            solves(1, factor, y, False)
            solves(1, factor, z, True)
            new, old = best_of(arguments.repeats, [lambda: solves(LOOPS, factor, y, False),
                                                   lambda: solves(LOOPS, factor, z, True)])
            y = rng.random(n)
            z = y.copy()
            band_solve(factor, y)
            plain_band_solve(factor, z)
            print(f"  coarse band solve ({n} unknowns, band {band_width(coarse)}): "
                  f"{new * 1e6:.0f} us against {old * 1e6:.0f} us in plain loops: "
                  f"{old / new:.2f}x faster; solutions differ by "
                  f"{np.abs(y - z).max() / np.abs(z).max():.1e} relative", flush=True)


if __name__ == "__main__":
    main()
