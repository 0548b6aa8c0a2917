"""The terms' derivatives (terms/base.py gives their forward): what the adjoints loop over.

Each term names its adjoint class ("module:Class", ``Term.adjoint``); the class gives, as NumPy
functions of the differentiable model (physics.Physical), what the adjoints need of it:

- ``acts(physical)``: whether the term exerts any force in this model;
- ``forces(physical, x, v)`` (P, 3) N, at the force time (clock.py), and ``forces_vjp``;
- ``first_iteration_rhs(physical, v, h)``: its h^2 dF/dx v in backward Euler's first Newton
  iteration, and its ``first_iteration_rhs_vjp``;
- ``diagonal_blocks(physical, x, v, h)`` (P, 3, 3): its share of each particle's diagonal block
  of A = M - h dF/dv - h^2 dF/dx, and ``diagonal_blocks_vjp`` with weights (P, 3, 3) on them;
- ``matrix_entries(physical, x, v, h)``: (rows, columns, values) of its share of A as a
  (3P, 3P) matrix (from its diagonal blocks unless it couples particles);
- ``product_vjp(physical, x, v, h, u, g, x_bar, v_bar, bar)``: the cotangents of g . (A_term u),
  u held fixed (from its diagonal blocks unless it couples particles);
- ``add_forward_blocks(solver, physical, x, v, h)``: its share of the forward's own block
  matrix, for solve.ForwardSolver (from its diagonal blocks unless it couples particles).

A part a term lacks keeps the default of terms/adjoint.py.AdjointTerm, which adds nothing.
The adjoint reads a term's own table as ``physical.term_tables[slot]``.
"""
import importlib

from ..terms import TERMS
from ..terms.adjoint import AdjointTerm  # noqa: F401 (the adjoint classes' base, importable here)

_adjoints: dict = {}


def adjoint_terms() -> list:
    """The adjoint class of every registered term, in the terms' order."""
    if len(_adjoints) != len(TERMS):
        for term in TERMS:
            module, name = term.adjoint.split(":")
            _adjoints[term.name] = getattr(importlib.import_module(module), name)
    return [_adjoints[term.name] for term in TERMS]


def any_acts(physical) -> bool:
    return any(term.acts(physical) for term in adjoint_terms())


def external_forces(physical, x, v):
    """Every term's force (P, 3) N."""
    return sum(term.forces(physical, x, v) for term in adjoint_terms())


def external_forces_vjp(physical, x, v, g, x_bar, v_bar, bar) -> None:
    for term in adjoint_terms():
        term.forces_vjp(physical, x, v, g, x_bar, v_bar, bar)


def first_iteration_rhs(physical, v, h):
    return sum(term.first_iteration_rhs(physical, v, h) for term in adjoint_terms())


def first_iteration_rhs_vjp(physical, v, h, g, v_bar, bar) -> None:
    for term in adjoint_terms():
        term.first_iteration_rhs_vjp(physical, v, h, g, v_bar, bar)


def diagonal_blocks(physical, x, v, h):
    return sum(term.diagonal_blocks(physical, x, v, h) for term in adjoint_terms())


def diagonal_blocks_vjp(physical, x, v, h, weights, x_bar, v_bar, bar) -> None:
    for term in adjoint_terms():
        term.diagonal_blocks_vjp(physical, x, v, h, weights, x_bar, v_bar, bar)


def matrix_entries(physical, x, v, h) -> list:
    return [term.matrix_entries(physical, x, v, h) for term in adjoint_terms()]


def product_vjp(physical, x, v, h, u, g, x_bar, v_bar, bar) -> None:
    for term in adjoint_terms():
        term.product_vjp(physical, x, v, h, u, g, x_bar, v_bar, bar)


def add_forward_blocks(solver, physical, x, v, h) -> None:
    for term in adjoint_terms():
        term.add_forward_blocks(solver, physical, x, v, h)
