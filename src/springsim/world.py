"""The world at a time: where the moving terrains and pins are, and contact looked up in the
terrains' frames.

Motion is a function of time alone (motion.py), so the kernels never carry it from step to
step: a step (or a stage of one) calls ``move_world(model, t)`` for its own time, which writes
every motion's pose into ``model.motion_pose``, and the contact kernels then call, with
``terrains = terrain_view(model)`` taken once per kernel call,

- ``terrain_at(terrains, t, x0, x1, x2, radius) -> (phi, nx, ny, nz)``: the signed distance and
  normal of terrain t at the point, looked up in the terrain's own frame (x placed = R^T (y - c)
  + pivot) so that any kind, a mesh's distance grid included, moves without being rebuilt;
- ``surface_velocity(terrains, t, x0, x1, x2) -> (ux, uy, uz)``: how fast the terrain's surface
  moves there, c' + w x (y - c) (zero for a still terrain), which restitution and friction are
  relative to.

A still terrain (terrain_motion -1) is looked up directly, as before motion existed: the same
arithmetic, the same bits.

Which time each integrator asks for: every step starts the world at the step's start
(integrators/_steps.drive); the explicit methods move it to each stage's time before that
stage's forces (midpoint: t + h/2; rk4: t + h/2, t + h/2, t + h); backward Euler moves it to the
step's end, t + h, before it finds its constraints (the constraint uses the collider where it is
at the step's end); the impact pass after every step is at t + h.

Pins that move (bodies/pins.py) are hard: their particles have no inverse mass, so no force
moves them; ``place_pins`` puts each exactly on its path (at the path's velocity) at the start
of every step and again at its end, whatever the integrator did in between (an explicit method's
stages carry it along at that velocity). Backward Euler holds a pinned particle's velocity as
the solve finds it, so ``aim_pins`` first gives it the velocity that reaches the path's point
at the step's end: the springs feel the pin move within the step.

The tables of the moving world are built once per model by world_tables.pack_world.

A soft pin (``stiffness``, ``damping``) is a spring of its own from the particle to its path's
point, with a damper against the velocity relative to the path: a force k (p - x) + d (u - v),
in every stage's forces at the stage's time (``add_pin_forces``) and in backward Euler's solve
at the step's end with its derivative (``add_pin_jacobian``).
"""
from typing import NamedTuple

import numpy as np

from ._jit import inline_kernel, kernel
from .clock import CALL_START, STAGE_TIME, STEP_END, STEP_SIZE, STEP_START, WORLD_TIME
from .motion import (ANGULAR_VELOCITY, CENTRE, CENTRE_VELOCITY, PIVOT, pose_into, pose_rotation,
                     pose_vector)
from .terrains.deforming_mesh import deform, deformed_velocity
from .terrains import still_terrain_distance, terrain_distance


@kernel
def move_world(model, t):
    """Write every motion's pose at time t (s) into model.motion_pose; the wind reads t from
    model.clock[WORLD_TIME]."""
    model.clock[WORLD_TIME] = t
    for m in range(model.motion_info.shape[0]):
        pose_into(model.motion_info, model.motion_keys, m, t, model.motion_pose[m])
    for terrain in range(model.terrain_deforming.shape[0]):
        if model.terrain_deforming[terrain] >= 0:
            deform(model.terrain_data, model.terrain_deforming[terrain], t)


@kernel
def step_time(model):
    """The time of the step being taken (s)."""
    return model.clock[STAGE_TIME]


@kernel
def step_end(model, h):
    """The time at the end of the step (or part of one) of size h begun at step_time. For a
    whole step it is the next step's start time itself, as start_step has it: the start plus h
    rounds differently, and a deforming terrain moved to the step's end would be refitted
    again, at a cost of its own, for the next start."""
    if model.clock[STAGE_TIME] == model.clock[STEP_START] and h == model.clock[STEP_SIZE]:
        return model.clock[STEP_END]
    return model.clock[STAGE_TIME] + h


@kernel
def start_step(model, x, v, done, h):
    """Set the clock to step ``done`` of this call (step size h), move the world there and put
    the moving pins on their paths. The time is the call's start plus done h: a function of
    the state's time alone."""
    t = model.clock[CALL_START] + done * h
    model.clock[STAGE_TIME] = model.clock[STEP_START] = t
    model.clock[STEP_END] = model.clock[CALL_START] + (done + 1) * h   # step_end's
    model.clock[STEP_SIZE] = h
    move_world(model, t)
    place_pins(model, x, v)


@kernel
def place_pins(model, x, v):
    """Every moving pin's particle exactly where its motion has it now (the pose last moved
    to), at the motion's velocity there."""
    for q in range(model.pin_particles.shape[0]):
        if model.pin_stiffness[q] > 0.0:
            continue   # a soft pin: a spring to its path (pin_accelerations)
        i = model.pin_particles[q]
        x[i, 0], x[i, 1], x[i, 2], v[i, 0], v[i, 1], v[i, 2] = pin_target(model, q)


@kernel
def aim_pins(model, x, v, h):
    """Backward Euler's pins (world.py's doc): each moving pin's velocity for this step is the
    one that takes it from x to where its motion has it at the step's end (the pose last moved
    to), since the solve holds a pinned particle's velocity as it finds it."""
    for q in range(model.pin_particles.shape[0]):
        if model.pin_stiffness[q] > 0.0:
            continue
        i, p = model.pin_particles[q], model.motion_pose[model.pin_motion[q]]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = pose_rotation(p)
        c0, c1, c2 = pose_vector(p, CENTRE)
        d0, d1, d2 = from_pivot(model, q, p)
        v[i, 0] = (c0 + r00 * d0 + r01 * d1 + r02 * d2 - x[i, 0]) / h
        v[i, 1] = (c1 + r10 * d0 + r11 * d1 + r12 * d2 - x[i, 1]) / h
        v[i, 2] = (c2 + r20 * d0 + r21 * d1 + r22 * d2 - x[i, 2]) / h


class TerrainView(NamedTuple):
    """The model's tables that terrain_at and surface_velocity read. An inline kernel handed the
    whole model counts a reference to each of its arrays at every call: a microsecond per
    particle and terrain, fifty times the plane's own lookup."""

    kind: np.ndarray        # (T,) each terrain's kind number (terrains/dispatch.py)
    parameters: np.ndarray  # (T, K) each terrain's packed row
    data: np.ndarray        # the kinds' shared data buffer (a mesh's grid)
    motion: np.ndarray      # (T,) the terrain's row of pose, or -1 for a still terrain
    pose: np.ndarray        # (M, POSE) every motion's pose now (move_world)
    deforming: np.ndarray   # (T,) the terrain's deforming surface, or -1


@inline_kernel
def terrain_view(model):
    return TerrainView(model.terrain_kind, model.terrain_parameters, model.terrain_data,
                       model.terrain_motion, model.motion_pose, model.terrain_deforming)


@inline_kernel
def terrain_at(terrains, t, x0, x1, x2, radius):
    """Signed distance (m) from a particle's surface to terrain t at its current pose, and the
    unit normal (world frame)."""
    if terrains.deforming[t] >= 0:   # a deforming mesh, which has no rigid motion
        return terrain_distance(terrains.kind[t], terrains.parameters[t], terrains.data,
                                x0, x1, x2, radius)
    # the others never deform by themselves: the dispatcher without the deforming kinds, whose
    # kernel inlined beside the others makes every kind's lookup slower
    if terrains.motion[t] < 0:
        return still_terrain_distance(terrains.kind[t], terrains.parameters[t], terrains.data,
                                      x0, x1, x2, radius)
    p = terrains.pose[terrains.motion[t]]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = pose_rotation(p)
    c0, c1, c2 = pose_vector(p, CENTRE)
    q0, q1, q2 = pose_vector(p, PIVOT)
    # y - c, then R^T (y - c) + pivot: the point where the terrain was placed in the scene
    d0, d1, d2 = x0 - c0, x1 - c1, x2 - c2
    l0 = r00 * d0 + r10 * d1 + r20 * d2 + q0
    l1 = r01 * d0 + r11 * d1 + r21 * d2 + q1
    l2 = r02 * d0 + r12 * d1 + r22 * d2 + q2
    phi, m0, m1, m2 = still_terrain_distance(terrains.kind[t], terrains.parameters[t],
                                             terrains.data, l0, l1, l2, radius)
    return (phi, r00 * m0 + r01 * m1 + r02 * m2, r10 * m0 + r11 * m1 + r12 * m2,
            r20 * m0 + r21 * m1 + r22 * m2)


@inline_kernel
def surface_velocity(terrains, t, x0, x1, x2):
    """Velocity (m/s) of terrain t's material at the world point (x0, x1, x2): c' + w x (y - c),
    or a deforming terrain's at its closest point."""
    if terrains.deforming[t] >= 0:
        return deformed_velocity(terrains.data, terrains.deforming[t], x0, x1, x2)
    if terrains.motion[t] < 0:
        return 0.0, 0.0, 0.0
    p = terrains.pose[terrains.motion[t]]
    c0, c1, c2 = pose_vector(p, CENTRE)
    u0, u1, u2 = pose_vector(p, CENTRE_VELOCITY)
    w0, w1, w2 = pose_vector(p, ANGULAR_VELOCITY)
    d0, d1, d2 = x0 - c0, x1 - c1, x2 - c2
    return (u0 + w1 * d2 - w2 * d1, u1 + w2 * d0 - w0 * d2, u2 + w0 * d1 - w1 * d0)


@kernel
def terrain_clearances(model, x, radius, t, out):
    """out[k]: the least signed distance (m) from any particle's surface (radius[i] from its
    centre) to terrain k where it is at time t (s): the world moved to t as a step moves it
    (``move_world``), then looked up as the contact kernels look it up (``terrain_at``). A
    deforming terrain answers infinity beyond its reach (terrains/deforming_mesh.py)."""
    move_world(model, t)
    terrains = terrain_view(model)
    for k in range(out.shape[0]):
        least = np.inf
        for i in range(x.shape[0]):
            phi, _, _, _ = terrain_at(terrains, k, x[i, 0], x[i, 1], x[i, 2], radius[i])
            least = min(least, phi)
        out[k] = least


@kernel
def pin_target(model, q):
    """Where moving pin q's path is now (the pose last moved to), and its velocity there."""
    p = model.motion_pose[model.pin_motion[q]]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = pose_rotation(p)
    c0, c1, c2 = pose_vector(p, CENTRE)
    u0, u1, u2 = pose_vector(p, CENTRE_VELOCITY)
    w0, w1, w2 = pose_vector(p, ANGULAR_VELOCITY)
    d0, d1, d2 = from_pivot(model, q, p)
    r0 = r00 * d0 + r01 * d1 + r02 * d2   # R (x_start - pivot)
    r1 = r10 * d0 + r11 * d1 + r12 * d2
    r2 = r20 * d0 + r21 * d1 + r22 * d2
    return (c0 + r0, c1 + r1, c2 + r2, u0 + w1 * r2 - w2 * r1, u1 + w2 * r0 - w0 * r2,
            u2 + w0 * r1 - w1 * r0)


@inline_kernel
def from_pivot(model, q, p):
    """Where moving pin q was placed, from its pose's pivot."""
    q0, q1, q2 = pose_vector(p, PIVOT)
    return (model.pin_placed[q, 0] - q0, model.pin_placed[q, 1] - q1,
            model.pin_placed[q, 2] - q2)


@kernel
def add_pin_forces(model, x, v, scale, out):
    """out[i] += scale_i (k (target - x_i) + d (target velocity - v_i)) for every soft pin's
    particle i: ``scale`` per particle (the inverse masses, for accelerations) or, with one
    entry, for all (the step h, for backward Euler's impulses)."""
    for q in range(model.pin_particles.shape[0]):
        k, d = model.pin_stiffness[q], model.pin_damping[q]
        if k == 0.0:
            continue
        i = model.pin_particles[q]
        t0, t1, t2, u0, u1, u2 = pin_target(model, q)
        w = scale[i] if scale.shape[0] > 1 else scale[0]
        out[i, 0] += w * (k * (t0 - x[i, 0]) + d * (u0 - v[i, 0]))
        out[i, 1] += w * (k * (t1 - x[i, 1]) + d * (u1 - v[i, 1]))
        out[i, 2] += w * (k * (t2 - x[i, 2]) + d * (u2 - v[i, 2]))


@kernel
def add_pin_jacobian(model, diagonal_slot, h, first, v, blocks, rhs):
    """Backward Euler's soft pins: A gains h d + h^2 k on each pinned particle's diagonal (the
    pin's -h dF/dv - h^2 dF/dx), and the first iteration's right-hand side its h^2 dF/dx v."""
    for q in range(model.pin_particles.shape[0]):
        k, d = model.pin_stiffness[q], model.pin_damping[q]
        if k == 0.0:
            continue
        i = model.pin_particles[q]
        slot = diagonal_slot[i]
        for c in range(3):
            blocks[slot, c, c] += h * d + h * h * k
            if first:
                rhs[i, c] -= h * h * k * v[i, c]
