"""Soft pins as a term: a spring and damper from each soft pin's particle to its path (world.py
places the path and writes the kernels, world_tables.py packs the pins; gradients/pins.py
differentiates them). Their parameters are the model's pin arrays: no table of their own."""
from .._jit import inline_kernel
from ..world import add_pin_forces, add_pin_jacobian
from .base import Term, register


@inline_kernel
def pin_forces(model, table, x, v, scale, out):
    add_pin_forces(model, x, v, scale, out)


@inline_kernel
def pin_jacobian(model, table, layout, h, first, x_k, v_k, v, blocks, rhs):
    add_pin_jacobian(model, layout.diagonal.diagonal_slot, h, first, v, blocks, rhs)


@register
class SoftPins(Term):
    name = "soft_pins"
    add_forces = pin_forces
    add_step_end_forces = pin_forces
    add_jacobian = pin_jacobian
    adjoint = "springsim.gradients.pins:SoftPinsAdjoint"
    order = 10

    @classmethod
    def used(cls, arrays) -> bool:
        return bool((arrays.pin_stiffness > 0.0).any())
