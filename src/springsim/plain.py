"""The plain kernels: a serial step compiled without what a plain model does not have.

A step kernel is compiled whole, for every feature a scene may use: body and self contact with
their pair lists, the balls, pins and attachments, the terms (soft pins, wind, ``[[forces]]``),
the mesh terrains' lookups, the deforming terrains' refits. A model that has none of them (a
jelly cube alone on the plane, the sphere or the bowl, moving or not: ``is_plain``) runs
the plain twin of its integrator's serial kernel, in which each of those is replaced by a
kernel that does nothing (or, for the terrains, a dispatcher that knows only the short
lookups). What is left is the same code, so a plain model moves bit for bit as under the whole
kernel (tests/test_plain.py), and the default scene's first compile takes a fraction of the
time (`springsim warmup --scene jelly-plane`; the performance page).

``plain_twin(kernel)`` makes the twin: a copy of the kernel whose globals name the
replacements, and of every kernel it calls that reaches one (_jit.twin), so that the kernels
the serial steps share (the force evaluation, the pass after the step) have one plain twin
each, compiled once for every integrator.
"""
import numpy as np

from ._jit import inline_kernel, kernel, twin
from .attachments import hold_attachments
from .collision.pipeline import resolve_contacts
from .integrators._steps import pairs_now
from .terms import add_external_forces, add_external_jacobians, add_step_end_forces
from .terms.base import TERMS
from .terms.dispatch import build_loop
from .terrains import KINDS, still_terrain_distance, terrain_distance
from .terrains.deforming_mesh import deform, deformed_velocity
from .terrains.dispatch import short_terrain_distance
from .world import place_pins


@kernel
def unchanged_pairs(model, x, pairs):
    """pairs_now of a model with no surfaces: the list as it is."""
    return pairs


@inline_kernel
def no_body_contacts(model, x, v, start, pairs):
    """resolve_contacts of a model with no surfaces and no balls: nothing touches."""
    return pairs


@kernel
def no_pins(model, x, v):
    """place_pins of a model with no pins."""
    return


@kernel
def no_attachments(model, x, v):
    """hold_attachments of a model with no attachments: no sweeps."""
    return 0


@kernel
def no_deformation(data, s, t):
    """deform of a model with no deforming terrain."""
    return


@kernel
def no_deformed_velocity(data, s, x0, x1, x2):
    """deformed_velocity of a model with no deforming terrain."""
    return 0.0, 0.0, 0.0


REPLACEMENTS = {
    pairs_now: unchanged_pairs,
    resolve_contacts: no_body_contacts,
    place_pins: no_pins,
    hold_attachments: no_attachments,
    add_external_forces: build_loop("add_external_forces", []),
    add_step_end_forces: build_loop("add_step_end_forces", []),
    add_external_jacobians: build_loop("add_external_jacobians", []),
    terrain_distance: short_terrain_distance,
    still_terrain_distance: short_terrain_distance,
    deform: no_deformation,
    deformed_velocity: no_deformed_velocity,
}
_twins: dict = {}   # the twins made so far, by id of the kernel twinned (shared by every twin)


def plain_twin(dispatcher):
    """The plain twin of a kernel (module doc)."""
    return twin(dispatcher, REPLACEMENTS, "_plain", _twins)


def plain_parts(calls: dict, model) -> dict:
    """Integrator.parts' ``calls`` of a serial step as the plain twin of the step calls them,
    where the model is plain."""
    if not is_plain(model.arrays):
        return calls
    return {name: call._replace(kernel=REPLACEMENTS.get(call.kernel)
                                or plain_twin(call.kernel))
            for name, call in calls.items()}


def is_plain(arrays) -> bool:
    """Whether a model (its ModelArrays) has none of what the plain kernels leave out."""
    long_lookups = {number for number, cls in enumerate(KINDS)
                    if getattr(cls, "look_ahead", False) or getattr(cls, "never_still", False)}
    return (arrays.surface_triangles.shape[0] == 0 and arrays.balls.shape[0] == 0
            and arrays.pin_particles.shape[0] == 0 and arrays.attachment_nodes.shape[0] == 0
            and bool(np.all(arrays.terrain_deforming < 0))
            and not any(int(kind) in long_lookups for kind in arrays.terrain_kind)
            and not any(term.used(arrays) for term in TERMS))
