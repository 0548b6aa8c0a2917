"""What a term's adjoint gives (gradients/terms.py lists it), with the defaults that add
nothing. NumPy alone, so that a term's file can hold its adjoint beside its kernels."""
import numpy as np


def outer_weights(left, right):
    """Per particle, left_i right_i^T (P, 3, 3): the weights of g . (B u) on B's blocks."""
    return left[:, :, None] * right[:, None, :]


class AdjointTerm:
    """The defaults: a term with no force, and the block parts from ``diagonal_blocks``."""

    @classmethod
    def acts(cls, physical) -> bool:
        return False

    @classmethod
    def forces(cls, physical, x, v):
        return np.zeros_like(x)

    @classmethod
    def forces_vjp(cls, physical, x, v, g, x_bar, v_bar, bar) -> None:
        pass

    @classmethod
    def first_iteration_rhs(cls, physical, v, h):
        return np.zeros_like(v)

    @classmethod
    def first_iteration_rhs_vjp(cls, physical, v, h, g, v_bar, bar) -> None:
        pass

    @classmethod
    def diagonal_blocks(cls, physical, x, v, h):
        return np.zeros((len(x), 3, 3))

    @classmethod
    def diagonal_blocks_vjp(cls, physical, x, v, h, weights, x_bar, v_bar, bar) -> None:
        pass

    @classmethod
    def matrix_entries(cls, physical, x, v, h):
        particle = 3 * np.arange(len(x))[:, None, None]
        rows = (particle + np.arange(3)[None, :, None]).repeat(3, axis=2)
        columns = (particle + np.arange(3)[None, None, :]).repeat(3, axis=1)
        return rows.ravel(), columns.ravel(), cls.diagonal_blocks(physical, x, v, h).ravel()

    @classmethod
    def product_vjp(cls, physical, x, v, h, u, g, x_bar, v_bar, bar) -> None:
        cls.diagonal_blocks_vjp(physical, x, v, h, outer_weights(g, u), x_bar, v_bar, bar)

    @classmethod
    def add_forward_blocks(cls, solver, physical, x, v, h) -> None:
        if cls.acts(physical):
            solver.blocks[solver.layout.diagonal.diagonal_slot] += cls.diagonal_blocks(
                physical, x, v, h)
