"""Soft attachments as a term: a spring and damper between a bound particle and the point of
the triangle it is bound to (attachments.py packs them and writes the kernels;
gradients/attachments.py differentiates them). Their parameters are the model's attachment
arrays: no table of their own."""
from .._jit import inline_kernel
from ..attachments import add_attachment_forces, add_attachment_jacobian
from .base import Term, register


@inline_kernel
def attachment_forces(model, table, x, v, scale, out):
    add_attachment_forces(model, x, v, scale, out)


@inline_kernel
def attachment_jacobian(model, table, layout, h, first, x_k, v_k, v, blocks, rhs):
    add_attachment_jacobian(model, layout.attachment_slots, h, first, v, blocks, rhs)


@register
class SoftAttachments(Term):
    name = "soft_attachments"
    add_forces = attachment_forces
    add_step_end_forces = attachment_forces
    add_jacobian = attachment_jacobian
    adjoint = "springsim.gradients.attachments:SoftAttachmentsAdjoint"
    order = 20

    @classmethod
    def used(cls, arrays) -> bool:
        return arrays.attachment_nodes.shape[0] > 0
