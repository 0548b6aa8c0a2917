"""The forces every integrator applies the same way, as terms (base.py says what a term gives).

Every module of this package is imported here, so a new term is a new file; the loops the
integrators call (dispatch.py) are then generated over the registered terms, in their order.
"""
import importlib
import pkgutil

from .base import FORCE_TYPES, TERMS, Term, register, registered_terms

for _module in pkgutil.iter_modules(__path__):
    if _module.name not in ("adjoint", "base", "dispatch"):
        importlib.import_module(f"{__name__}.{_module.name}")
registered_terms()

from .dispatch import build_loop  # noqa: E402

add_external_forces = build_loop("add_external_forces", TERMS)
add_step_end_forces = build_loop("add_step_end_forces", TERMS)
add_external_jacobians = build_loop("add_external_jacobians", TERMS)

__all__ = ["FORCE_TYPES", "TERMS", "Term", "register", "add_external_forces", "add_step_end_forces",
           "add_external_jacobians"]
