"""One conjugate-gradient iteration's product on the 100 x 100 cloth, two ways, in one run:
the fused ``cg.search_product`` (three passes over the particles) against the separate kernels
it replaced (new direction, system_multiply, filter_and_dot: five passes).

    .venv/bin/python benchmarks/cg_passes.py [--edge 100] [--repeats 5]

Each way runs 200 times inside one compiled loop (no Python call per product), alternating, best
of ``--repeats``; the ratio is what the change saves per iteration (issue 14).
"""
import argparse
import time

import numpy as np
from numba import njit

from springsim.collision.contact_sets.solve import no_contacts
from springsim.implicit.cg import filter_and_dot, search_product, system_multiply
from springsim.implicit.jacobian import assemble_diagonal_and_terms
from springsim.implicit.spring_terms import spring_terms_like
from springsim.scenefile import load_scene
from springsim.simulation import Simulation

LOOPS = 200


@njit
def fused(loops, pattern, blocks, terms, contacts, kind, normal, s, c, q):
    for _ in range(loops):
        search_product(pattern, blocks, terms, contacts, kind, normal, s, 0.5, c, q)


@njit
def separate(loops, pattern, blocks, terms, contacts, kind, normal, s, c, q):
    for _ in range(loops):
        for i in range(s.shape[0]):
            for k in range(3):
                c[i, k] = s[i, k] + 0.5 * c[i, k]
        system_multiply(pattern, blocks, terms, contacts, c, q)
        filter_and_dot(kind, normal, q, c)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--edge", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    scene = load_scene("cloth-hang", [f"bodies.0.particles_per_edge={args.edge}"])
    simulation = Simulation(scene, integrator="implicit_euler", dt=1 / 60)
    simulation.step(2)
    layout = simulation.integrator.pattern(simulation.model)
    x = simulation.state.positions
    blocks = np.empty((len(x), 3, 3))
    terms = spring_terms_like(layout.runs, layout.run_entries, layout.loose_pairs, x)
    assemble_diagonal_and_terms(simulation.model.arrays, layout, x, 1.0, 1 / 60,
                                1 / 3600, blocks, terms)
    kind, normal = simulation.state.contacts.kind, np.zeros_like(x)
    rng = np.random.default_rng(1)
    s, c, q = rng.standard_normal(x.shape), rng.standard_normal(x.shape), np.empty_like(x)
    arguments = (layout.diagonal, blocks, terms, no_contacts(), kind, normal, s)
    best = {}
    for name, way in (("fused", fused), ("separate", separate)):
        way(1, *arguments, c.copy(), q)   # compile
    for _ in range(args.repeats):
        for name, way in (("fused", fused), ("separate", separate)):
            start = c.copy() * 1e-3
            began = time.perf_counter()
            way(LOOPS, *arguments, start, q)
            best[name] = min(best.get(name, np.inf), (time.perf_counter() - began) / LOOPS)
    print(f"{len(x):,} particles, one CG product (best of {args.repeats} x {LOOPS}): "
          f"fused {1e3 * best['fused']:.4f} ms, separate {1e3 * best['separate']:.4f} ms, "
          f"ratio {best['fused'] / best['separate']:.2f}")


if __name__ == "__main__":
    main()
