"""The two-level preconditioner (implicit/coarse.py): its aggregates, its coarse matrix against
the Galerkin product computed densely, its band Cholesky against NumPy, and the solves it
preconditions, which must agree with block Jacobi's and take fewer iterations."""
import dataclasses
import tomllib

import numpy as np
import pytest
import scipy.sparse

from springsim import SceneError, Simulation
from springsim.bodies.cloth import Cloth
from springsim.bodies.cloth_material import ClothMaterial
from springsim.bodies.pins import Pin, Region
from springsim.collision.contact_sets.solve import no_contacts
from springsim.implicit.cg import system_multiply
from springsim.implicit.coarse import (aggregates, band_cholesky, band_solve, build_coarse_space,
                                       coarse_matrix)
from springsim.implicit.constraints import CONTACT, FREE, PINNED, filter_constrained
from springsim.implicit.jacobian import assemble_diagonal_and_terms
from springsim.implicit.pattern import build_solve_layout
from springsim.implicit.spring_terms import spring_terms_like
from springsim.motion import Motion
from springsim.scene import Scene
from springsim.scenefile import scene_from_table

H = 1.0 / 60.0


def cloth_scene(preconditioner="two_level", motion=None, edge=32):
    """A stiff cloth (``edge`` particles a side) hanging from its top edge, which ``motion``
    may move."""
    cloth = Cloth(particles_per_edge=edge, width=0.5, height=0.5, pinned="none",
                  rotation_degrees=90.0, rotation_axis=(1.0, 0.0, 0.0),
                  material=ClothMaterial(),
                  pins=[Pin(region=Region(min=(-1.0, 0.24, -1.0), max=(1.0, 0.26, 1.0)),
                            motion=motion)])
    scene = Scene(name="hang", bodies=[cloth], integrator="implicit_euler", dt=H)
    scene.implicit.preconditioner = preconditioner
    return scene


def test_aggregates_cover_every_connected_particle_once_and_each_is_connected():
    springs = np.array([(i, i + 1) for i in range(29)] + [(i, i + 10) for i in range(20)])
    springs = springs[(springs[:, 0] % 10 != 9) | (springs[:, 1] != springs[:, 0] + 1)]
    graph = scipy.sparse.coo_matrix((np.ones(len(springs)), tuple(springs.T)),
                                    shape=(31, 31))
    graph = (graph + graph.T).tocsr()
    aggregate = aggregates(graph)
    assert aggregate[30] == -1   # on no spring
    assert (aggregate[:30] >= 0).all()
    for g in range(aggregate.max() + 1):
        members = np.flatnonzero(aggregate == g)
        inside = graph[members][:, members]
        count, _ = scipy.sparse.csgraph.connected_components(inside, directed=False)
        assert count == 1


def test_band_cholesky_and_solve_agree_with_numpy():
    rng = np.random.default_rng(3)
    n, width = 40, 7
    matrix = np.zeros((n, n))
    for i in range(n):
        for j in range(max(0, i - width), min(n, i + width + 1)):
            matrix[i, j] = rng.standard_normal()
    matrix = matrix @ matrix.T + 0.1 * np.eye(n)   # banded, twice the width
    width *= 2
    band = np.zeros((n, width + 1))
    for i in range(n):
        for d in range(min(width, n - 1 - i) + 1):
            band[i, d] = matrix[i, i + d]
    assert band_cholesky(band)
    upper = np.zeros((n, n))
    for i in range(n):
        for d in range(min(width, n - 1 - i) + 1):
            upper[i, i + d] = band[i, d]
    assert np.allclose(upper.T @ upper, matrix, rtol=0, atol=1e-12 * np.abs(matrix).max())
    y = rng.standard_normal(n)
    x = y.copy()
    band_solve(band, x)
    assert np.allclose(x, np.linalg.solve(matrix, y), rtol=1e-9, atol=0)
    indefinite = np.zeros((2, 2))
    indefinite[:, 0] = (1.0, -1.0)   # [[1, 0], [0, -1]]
    assert not band_cholesky(indefinite)


def test_coarse_matrix_is_the_galerkin_product_of_the_constrained_matrix():
    """A_c = P^T (S A S + H) P, H = (I - S) times each constrained particle's diagonal scale,
    against the same product taken column by column from the solve's own matrix product."""
    simulation = Simulation(cloth_scene())
    model = simulation.model
    arrays, x = model.arrays, simulation.positions
    x += np.random.default_rng(5).normal(scale=0.002, size=x.shape)
    layout = build_solve_layout(arrays, model.spring_kind)
    coarse = layout.coarse
    assert coarse.count > 0 and (coarse.aggregate >= 0).all()
    count = model.particle_count
    blocks = np.empty((count, 3, 3))
    terms = spring_terms_like(layout.runs, layout.run_entries, layout.loose_pairs, x)
    assemble_diagonal_and_terms(arrays, layout, x, 1.0, H, H * H, blocks, terms)
    kind = np.where(model.pinned, PINNED, FREE).astype(np.int8)
    normal = np.zeros((count, 3))
    touching = np.arange(count) % 7 == 3
    kind[touching & ~model.pinned] = CONTACT
    normal[:] = (0.0, 0.6, 0.8)   # tilted: no coarse unknown lines up with it

    band = coarse_matrix(coarse, layout.diagonal, blocks, terms, kind, normal)
    n = 3 * coarse.count
    expected = np.zeros((n, n))
    for g in range(coarse.count):
        for c in range(3):
            u = np.zeros((count, 3))
            u[coarse.aggregate == g, c] = 1.0
            held = u.copy()
            filter_constrained(kind, normal, u)
            held -= u   # (I - S) P e
            product = np.zeros((count, 3))
            system_multiply(layout.diagonal, blocks, terms, no_contacts(), u, product)
            filter_constrained(kind, normal, product)
            scale = np.trace(blocks, axis1=1, axis2=2) / 3.0
            product += scale[:, None] * held
            for h in range(coarse.count):
                expected[3 * h:3 * h + 3, 3 * g + c] = product[coarse.aggregate == h].sum(0)
    found = np.zeros((n, n))
    for i in range(n):
        for d in range(min(band.shape[1] - 1, n - 1 - i) + 1):
            found[i, i + d] = found[i + d, i] = band[i, d]
    assert np.allclose(found, expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    assert np.linalg.eigvalsh(expected).min() > 0.0


def test_small_models_and_models_without_springs_have_no_coarse_space():
    assert build_coarse_space(999, np.array([[0, 1]]), np.array([True])).count == 0
    assert build_coarse_space(1000, np.zeros((0, 2), np.int64), np.zeros(0, bool)).count == 0


@pytest.mark.parametrize("motion", [None, Motion(velocity=(0.0, 0.0, 1.0))],
                         ids=["held", "moving"])
def test_two_level_solves_agree_with_block_jacobi_and_take_fewer_iterations(motion):
    """Solved tightly (relative residual 1e-10), both preconditioners give the same half second
    of a hanging cloth to 1e-6 m (at the default 1e-5 they differ by some 1e-5 m): the same
    backward-Euler steps. At the default tolerance a
    moving pin's stiff 32 x 32 cloth takes far fewer iterations with the coarse space
    (which joins a solve after cg.TWO_LEVEL_AFTER iterations of block Jacobi)."""
    positions, iterations = {}, {}
    for preconditioner in ("two_level", "block_jacobi"):
        tight = Simulation(cloth_scene(preconditioner, motion), cg_tolerance=1e-10,
                           cg_max_iterations=5000)
        tight.advance(0.5)
        positions[preconditioner] = tight.positions
        default = Simulation(cloth_scene(preconditioner, motion))
        default.advance(0.5)
        iterations[preconditioner] = int(default.integrator.statistics.cg_iterations[0])
    assert np.abs(positions["two_level"] - positions["block_jacobi"]).max() < 1e-6
    if motion is not None:
        assert iterations["two_level"] * 1.6 < iterations["block_jacobi"]


def test_the_preconditioner_is_a_scene_setting_and_a_wrong_one_is_refused_in_one_line():
    text = ('integrator = "implicit_euler"\n[implicit]\npreconditioner = "block_jacobi"\n'
            '[[bodies]]\ntype = "cloth"\n')
    scene = scene_from_table(tomllib.loads(text))
    assert scene.implicit.preconditioner == "block_jacobi"
    assert Simulation(scene).integrator.preconditioner == "block_jacobi"
    wrong = dataclasses.replace(scene, implicit=dataclasses.replace(scene.implicit,
                                                                    preconditioner="multigrid"))
    with pytest.raises(SceneError) as error:
        Simulation(wrong)
    message = str(error.value)
    assert "implicit.preconditioner" in message and "multigrid" in message
    assert '"two_level" or "block_jacobi"' in message and "\n" not in message
