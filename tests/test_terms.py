"""Every registered term (terms/) against its adjoint (gradients/terms.py), on one model where
each acts: the soft pins of test_gradients_pins, the soft stitch of test_gradients_attachments
and the gusty wind on a cloth and two balls of test_gradients_wind, and an attractor
(terms/attractor.py), together. For each term, the
forward kernels and the adjoint's NumPy give the same force, the same share of backward Euler's
matrix and right-hand side; and the adjoint's vector-Jacobian products agree with central
finite differences of its own force and blocks. A new term is held to all of it by being
registered."""
import numpy as np
import pytest

from springsim.gradients.clock import FORCE_TIME
from springsim.gradients.physics import Cotangents, Physical
from springsim.gradients.terms import adjoint_terms
from springsim.terms import TERMS

T, H = 0.37, 0.01   # an arbitrary time (s), and a step (s)


def every_term_scene():
    from springsim.attachments import Attachment
    from springsim.bodies.balls import Ball, Balls
    from springsim.bodies.cloth import Cloth
    from springsim.bodies.pins import Pin, Region
    from springsim.motion import Motion
    from springsim.scene import Scene
    from springsim.terms.attractor import Attractor
    from springsim.wind import Gusts, Wind

    first = Cloth(particles_per_edge=4, width=1.0, height=1.0, pinned="none",
                  self_collision=False)
    first.pins = [Pin(particles=[0], stiffness=400.0, damping=2.0),
                  Pin(particles=[15], stiffness=250.0, damping=1.0,
                      motion=Motion(velocity=(0.5, 0.0, 0.0)))]
    second = Cloth(particles_per_edge=4, width=1.0, height=1.0, pinned="none",
                   self_collision=False, position=(0.0, 0.0, 1.0))
    seam = Region(min=(-1.0, -0.1, 0.49), max=(1.0, 0.1, 0.51))
    stitch = Attachment(body=1, to=0, region=seam, stiffness=60.0, damping=0.5)
    balls = Balls(balls=[Ball(position=(0.0, 1.0, 0.0), radius=0.1, mass=0.2),
                         Ball(position=(0.5, 1.2, 0.3), radius=0.05, mass=0.1)])
    wind = Wind(velocity=(8.0, 1.0, -3.0), density=1.2, drag=1.2, friction=0.05,
                gusts=Gusts(strength=0.4, length=0.7, seed=3))
    pull = Attractor(point=(0.2, 0.5, 0.4), stiffness=30.0, damping=0.3, bodies=[1, 2])
    return Scene(bodies=[first, second, balls], attachments=[stitch], terrains=[], wind=wind,
                 forces=[pull])


@pytest.fixture(scope="module")
def setting():
    from springsim.model import build_model

    model = build_model(every_term_scene())
    rng = np.random.default_rng(7)
    x = model.initial_positions + rng.normal(0.0, 0.02, model.initial_positions.shape)
    v = rng.normal(0.0, 1.0, x.shape)
    from springsim.clock import WORLD_TIME
    from springsim.world import move_world
    move_world(model.arrays, T)
    assert model.arrays.clock[WORLD_TIME] == T
    physical = Physical.of(model)
    physical.clock[FORCE_TIME] = T
    return model, physical, x, v


def table(model, term):
    return model.arrays.term_tables[term.slot]


def pairs():
    return list(zip(TERMS, adjoint_terms()))


def test_every_term_has_an_adjoint_and_acts_in_the_model(setting):
    from springsim.gradients.terms import AdjointTerm

    _, physical, _, _ = setting
    assert [term.name for term in TERMS] == ["soft_pins", "soft_attachments", "wind",
                                             "attractor"]
    for term, adjoint in pairs():
        assert issubclass(adjoint, AdjointTerm), term.name
        assert adjoint.acts(physical), term.name


@pytest.mark.parametrize("number", range(4))
def test_forward_and_adjoint_forces_agree(setting, number):
    model, physical, x, v = setting
    term, adjoint = pairs()[number]
    forward = np.zeros_like(x)
    term.add_forces(model.arrays, table(model, term), x, v, np.ones(1), forward)
    assert np.abs(forward).max() > 0.0
    np.testing.assert_allclose(adjoint.forces(physical, x, v), forward, rtol=1e-12, atol=1e-13)


def dense(rows, columns, values, size):
    matrix = np.zeros((size, size))
    np.add.at(matrix, (rows, columns), values)
    return matrix


def forward_matrix(model, layout, term, x, v, first):
    """The term's share of A (3P, 3P) and of the right-hand side, from its forward kernels."""
    pattern = layout.diagonal
    blocks = np.zeros((len(pattern.column), 3, 3))
    rhs = np.zeros_like(x)
    term.add_jacobian(model.arrays, table(model, term), layout, H, first, x, v, v, blocks, rhs)
    if term.add_step_end_forces is not None:
        term.add_step_end_forces(model.arrays, table(model, term), x, v, np.full(1, H), rhs)
    row_of_slot = np.repeat(np.arange(len(x)), np.diff(pattern.row_start))
    rows = (3 * row_of_slot[:, None, None] + np.arange(3)[None, :, None]).repeat(3, axis=2)
    columns = (3 * pattern.column[:, None, None] + np.arange(3)[None, None, :]).repeat(3, 1)
    return dense(rows.ravel(), columns.ravel(), blocks.ravel(), 3 * len(x)), rhs


@pytest.mark.parametrize("number", range(4))
def test_forward_and_adjoint_system_shares_agree(setting, number):
    """Matrix: the forward's blocks against the adjoint's entries; right-hand side: the
    forward's h F + (first iteration) its h^2 dF/dx v against the adjoint's."""
    from springsim.implicit.pattern import build_solve_layout

    model, physical, x, v = setting
    term, adjoint = pairs()[number]
    layout = build_solve_layout(model.arrays, model.spring_kind)
    for first in (False, True):
        matrix, rhs = forward_matrix(model, layout, term, x, v, first)
        expected = dense(*adjoint.matrix_entries(physical, x, v, H), 3 * len(x))
        np.testing.assert_allclose(expected, matrix, rtol=1e-12, atol=1e-13)
        wanted = H * adjoint.forces(physical, x, v)
        if first:
            wanted += adjoint.first_iteration_rhs(physical, v, H)
        np.testing.assert_allclose(wanted, rhs, rtol=1e-12, atol=1e-13)
    diagonal = adjoint.diagonal_blocks(physical, x, v, H)
    for i in range(len(x)):
        np.testing.assert_allclose(diagonal[i], matrix[3 * i:3 * i + 3, 3 * i:3 * i + 3],
                                   rtol=1e-12, atol=1e-13)


def central(function, value, direction, step=1e-6):
    return (function(value + step * direction) - function(value - step * direction)) / (2 * step)


@pytest.mark.parametrize("number", range(4))
def test_adjoint_products_match_finite_differences(setting, number):
    """forces_vjp and product_vjp against central differences in x and v, and
    first_iteration_rhs_vjp in v."""
    _, physical, x, v = setting
    _, adjoint = pairs()[number]
    rng = np.random.default_rng(11 + number)
    g, u, dx, dv = (rng.normal(size=x.shape) for _ in range(4))

    x_bar, v_bar = np.zeros_like(x), np.zeros_like(x)
    adjoint.forces_vjp(physical, x, v, g, x_bar, v_bar, Cotangents.zeros(physical))
    force_dot = np.sum(g * central(lambda y: adjoint.forces(physical, y, v), x, dx))
    force_dot += np.sum(g * central(lambda w: adjoint.forces(physical, x, w), v, dv))
    assert np.sum(x_bar * dx) + np.sum(v_bar * dv) == pytest.approx(force_dot, rel=1e-6,
                                                                     abs=1e-9)

    def product(y, w):
        matrix = dense(*adjoint.matrix_entries(physical, y, w, H), 3 * len(x))
        return np.sum(g * (matrix @ u.ravel()).reshape(x.shape))

    x_bar, v_bar = np.zeros_like(x), np.zeros_like(x)
    adjoint.product_vjp(physical, x, v, H, u, g, x_bar, v_bar, Cotangents.zeros(physical))
    product_dot = (central(lambda y: product(y, v), x, dx) + central(lambda w: product(x, w), v,
                                                                     dv))
    assert np.sum(x_bar * dx) + np.sum(v_bar * dv) == pytest.approx(product_dot, rel=1e-6,
                                                                    abs=1e-9)

    v_bar = np.zeros_like(x)
    adjoint.first_iteration_rhs_vjp(physical, v, H, g, v_bar, Cotangents.zeros(physical))
    rhs_dot = np.sum(g * central(lambda w: adjoint.first_iteration_rhs(physical, w, H), v, dv))
    assert np.sum(v_bar * dv) == pytest.approx(rhs_dot, rel=1e-6, abs=1e-9)
