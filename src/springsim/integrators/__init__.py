"""Integrators, chosen by name: one file per method, each registering itself (base.py)."""
from .base import (REGISTRY, Integrator, KernelIntegrator, available_threads, get_integrator,
                   integrator_names, register)

# The registry: one line per integrator file.
from . import explicit_euler, symplectic_euler, midpoint, rk4, implicit_euler, predict_reevaluate, vbd  # noqa: E402,F401,E501

__all__ = ["REGISTRY", "Integrator", "KernelIntegrator", "available_threads", "get_integrator",
           "integrator_names", "register"]
