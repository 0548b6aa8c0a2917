"""Forces and accelerations: the Numba kernels every integrator evaluates.

For a spring (a, b) with d = x_a - x_b, l = d / |d| and rest length r:
    spring  f_a = -ks (|d| - r) l
    damper  f_a = -kd ((v_a - v_b) . l) l
    f_b = -f_a
(springs.spring_force_factor), plus gravity m g and viscous drag -c v on every particle.
"""
import numpy as np
from numba import prange

from ._jit import inline_kernel, kernel
from .collision.response.terrain import apply_contact_forces
from .spring_runs import COLUMNS, add_run_forces, from_columns, to_columns
from .springs import spring_force_factor
from .terms import add_external_forces


@kernel
def force_columns(x):
    """The work rows spring_forces needs for states shaped like x; allocate once per advance."""
    return np.empty((COLUMNS, x.shape[0]))


@inline_kernel
def spring_forces(model, x, v, columns, out):
    """out = the spring and damper force on every particle (N).

    The springs in runs (spring_runs.py) take the vectorized loop over columns; the few loose
    springs take the plain loop below."""
    to_columns(x, v, columns)
    add_run_forces(model, columns)
    from_columns(columns, out)
    add_loose_spring_forces(model, x, v, out)


@kernel
def add_loose_spring_forces(model, x, v, force):
    """Add the force of each loose spring (one in no run) to both of its particles."""
    springs, rest_length, group = model.springs, model.rest_length, model.spring_group
    for s in model.loose_springs:
        a, b = springs[s, 0], springs[s, 1]
        dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
        factor = spring_force_factor(dx, dy, dz, v[a, 0] - v[b, 0], v[a, 1] - v[b, 1],
                                     v[a, 2] - v[b, 2], rest_length[s],
                                     model.group_ks[group[s]], model.group_kd[group[s]])
        fx, fy, fz = factor * dx, factor * dy, factor * dz
        force[a, 0] += fx
        force[a, 1] += fy
        force[a, 2] += fz
        force[b, 0] -= fx
        force[b, 1] -= fy
        force[b, 2] -= fz


@kernel
def accelerations(model, x, v, h, out, columns):
    """out = dv/dt at (x, v): internal and external forces over mass, then terrain contact.

    ``h`` is the step the integrator is taking; static friction uses it (see
    collision/response/terrain.py). ``columns`` is work space from force_columns. Pinned particles
    have zero inverse mass and so zero acceleration.
    """
    free_accelerations(model, x, v, out, columns)
    apply_contact_forces(model, x, v, h, out)


# accelerations as the threaded kernels inline it: a kernel's prange loops run on threads only in
# the kernel compiled with them (integrators/_steps.threaded). The serial kernels call the one
# compiled above instead, shared by every method and stage: inlined at every call site of the
# explicit methods, it was compiled once per site, most of the first compile's length.
threaded_accelerations = inline_kernel(accelerations.py_func)


@inline_kernel
def free_accelerations(model, x, v, out, columns):
    """out = dv/dt at (x, v) before terrain contact: springs, dampers, drag, gravity and the
    terms."""
    spring_forces(model, x, v, columns, out)
    inv_mass, gravity, drag = model.inv_mass, model.gravity, model.drag
    for i in prange(x.shape[0]):
        w = inv_mass[i]
        for c in range(3):
            out[i, c] = w * (out[i, c] - drag[i] * v[i, c]) + (gravity[c] if w > 0.0 else 0.0)
    add_external_forces(model, x, v, inv_mass, out)   # the terms: soft pins, wind, ... (terms/)


@kernel
def forces(model, x, v):
    """Net force (N) on every particle before contact, for tests and diagnostics."""
    out = np.empty_like(x)
    spring_forces(model, x, v, force_columns(x), out)
    mass = np.zeros(x.shape[0])
    for i in range(x.shape[0]):
        if model.inv_mass[i] > 0.0:
            mass[i] = 1.0 / model.inv_mass[i]
        for c in range(3):
            out[i, c] += mass[i] * model.gravity[c] - model.drag[i] * v[i, c]
    return out
