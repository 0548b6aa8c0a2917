"""The wind as a term: drag and lift of the moving air on the cloth's triangles and the balls
(wind.py packs it and writes the kernels; gradients/wind.py differentiates them). Under backward
Euler its force at the estimate comes with its Jacobian, in one pass over the triangles. Its
parameters are the model's wind arrays (the scene's ``[wind]``): no table of its own."""
from .._jit import inline_kernel
from ..wind import ON, add_wind_forces, add_wind_with_jacobian
from .base import Term, register


@inline_kernel
def wind_forces(model, table, x, v, scale, out):
    add_wind_forces(model, x, v, scale, out)


@inline_kernel
def wind_jacobian(model, table, layout, h, first, x_k, v_k, v, blocks, rhs):
    add_wind_with_jacobian(model, layout.diagonal.diagonal_slot, x_k, v_k, h, rhs, blocks)


@register
class Air(Term):
    name = "wind"
    add_forces = wind_forces
    add_jacobian = wind_jacobian
    adjoint = "springsim.gradients.wind:WindAdjoint"
    order = 30

    @classmethod
    def used(cls, arrays) -> bool:
        return arrays.wind_settings[ON] != 0.0
