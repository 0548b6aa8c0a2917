"""Pins that move and soft pins (world.py) in the adjoint, as differentiable NumPy.

Every pin of model.pin_particles has a path, a rigid motion (motion.py) that holds, moves or
follows a terrain; a pin that holds hard is a pinned particle, in none of this.

- A hard pin on a path is put on it at every step's start and end (world.place_pins), whatever
  the step did: its particle's position and velocity at either come from the path, not from
  the state before, so their cotangents stop at both (``release``). Under backward Euler,
  ``aim_pins`` sets its velocity to (the path's point at the step's end - x) / h (``aim``);
  that x was placed at the step's start, so the cotangent it passes on stops there too.
- A soft pin is a force k (p - x) + d (u - v), p and u the path's point and velocity at the
  force evaluation's time (clock.py): in every explicit stage, and in backward Euler's solve
  at the step's end, with h d + h^2 k on the particle's diagonal block and -h^2 k v in the first
  iteration's right-hand side (world.add_pin_jacobian). Its stiffness and damping are
  parameters (``bodies.N.pins.M.stiffness``, ``.damping``).
"""
import numpy as np

from ..motion import (ANGULAR_VELOCITY_PART, CENTRE_PART, CENTRE_VELOCITY_PART, PIVOT_PART, POSE,
                      ROTATION_PART, pose_into)
from .clock import FORCE_TIME
from ..terms.adjoint import AdjointTerm


def soft(physical):
    return physical.pin_stiffness > 0.0


def targets(physical, t):
    """Every pin's path point and velocity at time t, (Q, 3) each (world.pin_target)."""
    count = len(physical.pin_particles)
    points, velocities = np.empty((count, 3)), np.empty((count, 3))
    poses = {}
    for q in range(count):
        m = int(physical.pin_motion[q])
        if m not in poses:
            poses[m] = np.empty(POSE)
            pose_into(physical.motion_info, physical.motion_keys, m, t, poses[m])
        p = poses[m]
        r = p[ROTATION_PART].reshape(3, 3) @ (physical.pin_placed[q] - p[PIVOT_PART])
        points[q] = p[CENTRE_PART] + r
        velocities[q] = p[CENTRE_VELOCITY_PART] + np.cross(p[ANGULAR_VELOCITY_PART], r)
    return points, velocities


def release(physical, x_bar, v_bar):
    """Zero the cotangents of the hard pins on paths (place_pins overwrote their state)."""
    if not len(physical.pin_particles):   # most scenes: at every step, twice
        return
    moving = physical.pin_particles[~soft(physical)]
    x_bar[moving] = 0.0
    v_bar[moving] = 0.0


def place(physical, x, v):
    """(x, v) with each hard pin on a path put on it at the force time (place_pins): the first
    state of a run may have them elsewhere (a start of its own), and step 0 moved them."""
    if not len(physical.pin_particles):
        return x, v
    hard = ~soft(physical)
    if not hard.any():
        return x, v
    points, velocities = targets(physical, physical.clock[FORCE_TIME])
    x, v = x.copy(), v.copy()
    rows = physical.pin_particles[hard]
    x[rows], v[rows] = points[hard], velocities[hard]
    return x, v


def aim(physical, x, v, h):
    """v with each hard pin on a path aimed at its point at the force time (aim_pins)."""
    hard = ~soft(physical)
    if not hard.any():
        return v
    points, _ = targets(physical, physical.clock[FORCE_TIME])
    v = v.copy()
    rows = physical.pin_particles[hard]
    v[rows] = (points[hard] - x[rows]) / h
    return v


def pin_forces(physical, x, v):
    """Every soft pin's force (N), (P, 3), at the force time (world.add_pin_forces)."""
    out = np.zeros_like(x)
    on = soft(physical)
    if not on.any():
        return out
    points, velocities = targets(physical, physical.clock[FORCE_TIME])
    rows = physical.pin_particles[on]
    force = (physical.pin_stiffness[on, None] * (points[on] - x[rows])
             + physical.pin_damping[on, None] * (velocities[on] - v[rows]))
    np.add.at(out, rows, force)
    return out


def pin_forces_vjp(physical, x, v, g, x_bar, v_bar, bar) -> None:
    """Add g . d(pin_forces)/d(x, v, stiffness, damping)."""
    on = np.flatnonzero(soft(physical))
    if not len(on):
        return
    points, velocities = targets(physical, physical.clock[FORCE_TIME])
    rows = physical.pin_particles[on]
    gi = g[rows]
    np.add.at(x_bar, rows, -physical.pin_stiffness[on, None] * gi)
    np.add.at(v_bar, rows, -physical.pin_damping[on, None] * gi)
    bar.pin_stiffness[on] += np.einsum("ij,ij->i", gi, points[on] - x[rows])
    bar.pin_damping[on] += np.einsum("ij,ij->i", gi, velocities[on] - v[rows])


def first_iteration_rhs(physical, v, h):
    """The soft pins' share of the first Newton iteration's right-hand side, -h^2 k v."""
    out = np.zeros_like(v)
    on = soft(physical)
    rows = physical.pin_particles[on]
    np.add.at(out, rows, -h * h * physical.pin_stiffness[on, None] * v[rows])
    return out


def first_iteration_rhs_vjp(physical, v, h, g, v_bar, bar) -> None:
    on = np.flatnonzero(soft(physical))
    rows = physical.pin_particles[on]
    np.add.at(v_bar, rows, -h * h * physical.pin_stiffness[on, None] * g[rows])
    bar.pin_stiffness[on] -= h * h * np.einsum("ij,ij->i", g[rows], v[rows])


def pin_blocks(physical, count, h):
    """Each particle's share of backward Euler's matrix from its soft pins, (P, 3, 3):
    (h d + h^2 k) I."""
    out = np.zeros((count, 3, 3))
    on = soft(physical)
    size = h * physical.pin_damping[on] + h * h * physical.pin_stiffness[on]
    np.add.at(out, physical.pin_particles[on], size[:, None, None] * np.eye(3))
    return out


def pin_blocks_vjp(physical, h, weights, bar) -> None:
    """Add d(sum_i weights_i : pin_blocks_i)/d(stiffness, damping) (weights (P, 3, 3))."""
    on = np.flatnonzero(soft(physical))
    trace = np.einsum("kii->k", weights[physical.pin_particles[on]])
    bar.pin_stiffness[on] += h * h * trace
    bar.pin_damping[on] += h * trace


class SoftPinsAdjoint(AdjointTerm):
    """The soft pins' derivative (terms/soft_pins.py): (h d + h^2 k) I on the diagonal."""

    @classmethod
    def acts(cls, physical) -> bool:
        return bool(soft(physical).any())

    # the functions above, whose arguments are the protocol's (terms/adjoint.py)
    forces, forces_vjp = staticmethod(pin_forces), staticmethod(pin_forces_vjp)
    first_iteration_rhs = staticmethod(first_iteration_rhs)
    first_iteration_rhs_vjp = staticmethod(first_iteration_rhs_vjp)

    @classmethod
    def diagonal_blocks(cls, physical, x, v, h):
        return pin_blocks(physical, len(x), h)

    @classmethod
    def diagonal_blocks_vjp(cls, physical, x, v, h, weights, x_bar, v_bar, bar) -> None:
        pin_blocks_vjp(physical, h, weights, bar)
