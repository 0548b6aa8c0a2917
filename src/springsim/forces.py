"""Forces and accelerations: the Numba kernels every integrator evaluates.

For a spring (a, b) with d = x_a - x_b, l = d / |d| and rest length r:
    spring  f_a = -ks (|d| - r) l
    damper  f_a = -kd ((v_a - v_b) . l) l
    f_b = -f_a
plus gravity m g and viscous drag -c v on every particle.
"""
import math

import numpy as np

from ._jit import kernel
from .contact import apply_contact_forces


@kernel
def add_spring_forces(model, x, v, force):
    """Add the spring and damper force of every spring to both of its particles."""
    springs, rest_length, group = model.springs, model.rest_length, model.spring_group
    for s in range(springs.shape[0]):
        a, b = springs[s, 0], springs[s, 1]
        dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            continue  # coincident particles: the direction is undefined, so no force
        inverse_length = 1.0 / length
        # along l = d / |d|: f_a = (-ks (|d| - r) - kd (v_a - v_b) . l) l
        closing_speed = ((v[a, 0] - v[b, 0]) * dx + (v[a, 1] - v[b, 1]) * dy
                         + (v[a, 2] - v[b, 2]) * dz) * inverse_length
        g = group[s]
        magnitude = -model.group_ks[g] * (length - rest_length[s]) - model.group_kd[g] * closing_speed
        scale = magnitude * inverse_length
        fx, fy, fz = scale * dx, scale * dy, scale * dz
        force[a, 0] += fx
        force[a, 1] += fy
        force[a, 2] += fz
        force[b, 0] -= fx
        force[b, 1] -= fy
        force[b, 2] -= fz


@kernel
def accelerations(model, x, v, h, out):
    """out = dv/dt at (x, v): internal and external forces over mass, then terrain contact.

    ``h`` is the step the integrator is taking; static friction uses it (see contact.py).
    Pinned particles have zero inverse mass and so zero acceleration.
    """
    out[:] = 0.0
    add_spring_forces(model, x, v, out)
    inv_mass, gravity, drag = model.inv_mass, model.gravity, model.drag
    for i in range(x.shape[0]):
        w = inv_mass[i]
        for c in range(3):
            out[i, c] = w * (out[i, c] - drag[i] * v[i, c]) + (gravity[c] if w > 0.0 else 0.0)
    apply_contact_forces(model, x, v, h, out)


@kernel
def forces(model, x, v):
    """Net force (N) on every particle before contact, for tests and diagnostics."""
    out = np.zeros_like(x)
    add_spring_forces(model, x, v, out)
    mass = np.zeros(x.shape[0])
    for i in range(x.shape[0]):
        if model.inv_mass[i] > 0.0:
            mass[i] = 1.0 / model.inv_mass[i]
        for c in range(3):
            out[i, c] += mass[i] * model.gravity[c] - model.drag[i] * v[i, c]
    return out
