"""Whether a sparse Cholesky factorization could take the cape's solve below its share of a
real-time step (issue 30's bar: a 1/60 s step in at most 16.7 ms, the figure's contact included):
CHOLMOD (SuiteSparse, through scikit-sparse) on the system the cape solves one second in, and
the same factor kept as a preconditioner for the systems of the steps after it.

    apt-get install libsuitesparse-dev          # SuiteSparse, which scikit-sparse builds on
    .venv/bin/pip install "scikit-sparse<0.4.15"
    .venv/bin/python benchmarks/cape_direct_solve.py

For each of CHOLMOD's simplicial and supernodal factorizations in nested-dissection order: the
time to factor (best of 5) and to solve, the factor's entries, and the factorization's floating
point operations (the sum of its columns' squared entry counts), which bound its time on any
machine by its speed. Then conjugate gradients to a relative residual of 1e-5 on the systems
1, 5 and 10 steps later, preconditioned by the factor of the first: how long a factor stays
useful as the cape moves.
"""
import time

import numpy as np
import scipy.sparse as sparse

import springsim
from springsim.implicit.jacobian import assemble_system
from springsim.implicit.pattern import build_block_pattern
from springsim.reference import reference_forces

from preconditioner_options import iterations   # CG to TOLERANCE, counted

H = 1 / 60
LATER = (1, 5, 10)   # steps after the factored system


def cape_systems(first: float = 1.0):
    """(A, b) of the cape's free particles at ``first`` s and LATER steps after it."""
    simulation = springsim.Simulation(springsim.load_scene("cape"))
    arrays = simulation.model.arrays
    pattern = build_block_pattern(arrays)
    blocks = np.empty((pattern.block_count, 3, 3))
    masses = 1.0 / np.where(arrays.inv_mass > 0, arrays.inv_mass, 1.0)
    rows = np.repeat(~simulation.model.pinned, 3)
    systems, done = [], 0
    simulation.advance(first)
    for steps in (0, *LATER):
        if steps > done:
            simulation.step(steps - done)
            done = steps
        x, v = simulation.positions, simulation.velocities
        assemble_system(arrays, pattern, x, 1.0, H, H * H, blocks)
        matrix = sparse.bsr_matrix((blocks, pattern.column, pattern.row_start)).tocsc()
        load = H * (reference_forces(simulation.model, x, v) + masses[:, None] * arrays.gravity)
        matrix = matrix[rows][:, rows]
        systems.append((((matrix + matrix.T) * 0.5).tocsc(), load.ravel()[rows]))
    return systems


def factor_times(matrix, b, mode: str) -> str:
    from sksparse.cholmod import analyze

    symbolic = analyze(matrix, mode=mode, ordering_method="nesdis")
    best = np.inf
    for _ in range(5):
        start = time.perf_counter()
        symbolic.cholesky_inplace(matrix)
        best = min(best, time.perf_counter() - start)
    start = time.perf_counter()
    symbolic(b)
    solve = time.perf_counter() - start
    columns = np.diff(symbolic.L().tocsc().indptr).astype(float)
    return (f"{mode}: factor {best * 1e3:.1f} ms, solve {solve * 1e3:.2f} ms, "
            f"{symbolic.L().nnz:,} entries, {np.sum(columns ** 2) / 1e6:.0f} M flops")


def main():
    try:
        from sksparse.cholmod import cholesky
    except ImportError:
        print("cape_direct_solve: scikit-sparse is not installed (see this file's doc)")
        return
    systems = cape_systems()
    matrix, b = systems[0]
    print(f"cape at 1 s: {matrix.shape[0]} unknowns, {matrix.nnz:,} entries", flush=True)
    for mode in ("simplicial", "supernodal"):
        print(factor_times(matrix, b, mode), flush=True)
    factor = cholesky(matrix, mode="simplicial", ordering_method="nesdis")
    for steps, (later, load) in zip(LATER, systems[1:]):
        print(f"{steps} steps later, preconditioned by the factor at 1 s: "
              f"{iterations(later, load, factor)} iterations", flush=True)


if __name__ == "__main__":
    main()
