"""Which preconditioner would cut the cape's conjugate-gradient iterations, tried in SciPy on the
system the cape solves one second in (implicit_euler at 1/60 s, the pinned shoulders removed),
before any of them is built into the kernels (implicit/coarse.py has the first two):

- block Jacobi;
- two-level additive, the aggregates' piecewise-constant prolongation P (implicit_euler's
  ``two_level``);
- the same with P smoothed once by damped Jacobi (smoothed aggregation, Vanek et al. 1996);
- a symmetric two-level V-cycle: ``nu`` damped block-Jacobi sweeps, the coarse correction,
  ``nu`` sweeps again (each sweep one more product with A per iteration);
- and SuperLU's sparse LU of the whole system (SciPy's only sparse direct solver), timed.

    .venv/bin/python benchmarks/preconditioner_options.py

Iterations to a relative residual of 1e-5, the integrator's default tolerance.
"""
import time

import numpy as np
import scipy.sparse as sparse
import scipy.sparse.linalg as linalg

import springsim
from springsim.implicit.jacobian import assemble_system
from springsim.implicit.pattern import build_block_pattern
from springsim.reference import reference_forces

H = 1 / 60
TOLERANCE = 1e-5


def cape_system():
    """(A, b) of the cape's free particles at 1 s, and their aggregates."""
    simulation = springsim.Simulation(springsim.load_scene("cape"))
    simulation.advance(1.0)
    model, x, v = simulation.model, simulation.positions, simulation.velocities
    arrays = model.arrays
    pattern = build_block_pattern(arrays)
    blocks = np.empty((pattern.block_count, 3, 3))
    assemble_system(arrays, pattern, x, 1.0, H, H * H, blocks)
    matrix = sparse.bsr_matrix((blocks, pattern.column, pattern.row_start)).tocsr()
    free = ~model.pinned & (simulation.state.contacts.kind == 0)
    masses = 1.0 / np.where(arrays.inv_mass > 0, arrays.inv_mass, 1.0)
    load = H * (reference_forces(model, x, v) + masses[:, None] * arrays.gravity)
    rows = np.repeat(free, 3)
    aggregate = simulation.integrator.solve_layout(model).coarse.aggregate[free]
    return matrix[rows][:, rows].tocsr(), load.ravel()[rows], aggregate


def block_jacobi(matrix):
    count = matrix.shape[0] // 3
    dense_rows = [matrix[3 * i:3 * i + 3, 3 * i:3 * i + 3].toarray() for i in range(count)]
    return sparse.block_diag([np.linalg.inv(block) for block in dense_rows], format="csr")


def prolongation(aggregate):
    count = len(aggregate)
    columns = 3 * np.repeat(aggregate, 3) + np.tile([0, 1, 2], count)
    p = sparse.csr_matrix((np.ones(3 * count), (np.arange(3 * count), columns)))
    return p[:, np.asarray(p.sum(axis=0)).ravel() > 0]


def iterations(matrix, b, apply):
    count = [0]

    def counted(_):
        count[0] += 1

    linalg.cg(matrix, b, rtol=TOLERANCE, maxiter=5000, callback=counted,
              M=linalg.LinearOperator(matrix.shape, apply))
    return count[0]


def additive(matrix, inverse, p):
    coarse = linalg.splu((p.T @ matrix @ p).tocsc())
    return lambda r: inverse @ r + p @ coarse.solve(p.T @ r)


def v_cycle(matrix, inverse, p, sweeps, weight=0.7):
    coarse = linalg.splu((p.T @ matrix @ p).tocsc())

    def apply(r):
        z = np.zeros_like(r)
        for _ in range(sweeps):
            z = z + weight * (inverse @ (r - matrix @ z))
        z = z + p @ coarse.solve(p.T @ (r - matrix @ z))
        for _ in range(sweeps):
            z = z + weight * (inverse @ (r - matrix @ z))
        return z
    return apply


def main():
    matrix, b, aggregate = cape_system()
    inverse = block_jacobi(matrix)
    plain = prolongation(aggregate)
    radius = abs(linalg.eigs(linalg.LinearOperator(matrix.shape, lambda u: inverse @ (matrix @ u)),
                             k=1, which="LM", return_eigenvectors=False)[0])
    smoothed = sparse.csr_matrix(plain - (4.0 / (3.0 * radius)) * (inverse @ (matrix @ plain)))
    print(f"cape at 1 s: {matrix.shape[0]} unknowns, {plain.shape[1]} coarse", flush=True)
    options = [("block Jacobi", lambda r: inverse @ r),
               ("two-level additive", additive(matrix, inverse, plain)),
               ("two-level additive, smoothed P", additive(matrix, inverse, smoothed)),
               ("V-cycle, 1 sweep", v_cycle(matrix, inverse, plain, 1)),
               ("V-cycle, 1 sweep, smoothed P", v_cycle(matrix, inverse, smoothed, 1)),
               ("V-cycle, 2 sweeps, smoothed P", v_cycle(matrix, inverse, smoothed, 2))]
    for name, apply in options:
        print(f"{name}: {iterations(matrix, b, apply)} iterations", flush=True)
    start = time.perf_counter()
    factor = linalg.splu(matrix.tocsc(), permc_spec="COLAMD")
    factored = time.perf_counter() - start
    start = time.perf_counter()
    factor.solve(b)
    print(f"SuperLU (COLAMD): factor {factored * 1e3:.0f} ms, solve "
          f"{(time.perf_counter() - start) * 1e3:.1f} ms, {factor.L.nnz + factor.U.nnz} entries",
          flush=True)


if __name__ == "__main__":
    main()
