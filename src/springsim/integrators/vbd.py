"""Vertex block descent (Chen, Macklin, et al., SIGGRAPH 2024): backward Euler's step found by
minimizing its incremental potential one particle at a time, at a fixed cost a step.

Backward Euler's new positions minimize E(x) (vbd/vertex.py: inertia, springs with their
dampers, drag, terrain contact with friction, and every term's force). Each iteration visits the
particles colour by colour (vbd/graph.py: no spring joins two particles of a colour); each
particle takes one Newton step on its own 3 x 3 block, f = -dE/dx_i, H = d2E/dx_i2 at the others'
latest positions, x_i += H^-1 f. A step is ``iterations`` such sweeps (a setting), whatever
touches what: no linear solve, no active set. Converged, the step is backward Euler's, nonlinear
in full (implicit_euler linearizes it); with few iterations it is a stable approximation of it
that loses energy, as backward Euler does.

The first guess is VBD's adaptive one: x0 + h v0 + h^2 a, with a the last step's acceleration
along gravity, kept to between zero and gravity itself (state.ContactMemory's velocity change).
The terms (terms/) are linearized once an iteration, at its start: their force and their
diagonal blocks of backward Euler's matrix, divided by h and h^2, join each particle's block (a
model without terms skips this: TermLayout.terms).
The particles of a colour share nothing they write, so they run on threads in the threaded
kernel with the same bits as on one.

After the step comes the pass every integrator runs (_steps.drive): the moving pins on their
paths, hard attachments held, impacts with restitution, body-body and self contact.
"""
import math
from typing import NamedTuple

import numpy as np
from numba import prange

from .._jit import inline_kernel, kernel, parallel_kernel
from ..errors import SceneError, require
from ..terms import TERMS, add_external_jacobians, add_step_end_forces
from ..terrains import still_terrain_distance
from ..vbd.contact import OFFSET_OF_BAND, contact_pressure, contact_share
from ..vbd.graph import vertex_graph
from ..vbd.vertex import added, solve_block, spring_share
from ..world import aim_pins, move_world, step_end, surface_velocity, terrain_at, terrain_view
from .base import KernelCall, KernelIntegrator, register
from ._steps import drive, drive_parts, threaded, threaded_drive
from .implicit_euler import ImplicitState, _is_number, _is_whole


class Settings(NamedTuple):
    """The integrator's options (VertexBlockDescent)."""

    iterations: int                  # sweeps over all particles a step
    contact_stiffness_ratio: float   # terrain contact stiffness over a particle's m / h^2
    friction_velocity: float         # m/s: sliding slower than this is held (static friction)


class DiagonalSlots(NamedTuple):
    diagonal_slot: np.ndarray   # (P,) int64: particle i's block is blocks[i]


class TermLayout(NamedTuple):
    """Where the terms' add_jacobian writes (terms/base.py), for blocks of (P + 1, 3, 3): each
    particle's own block at its number, every block between two particles at P, which is never
    read (the block step sees only its particle's own)."""

    diagonal: DiagonalSlots
    attachment_slots: np.ndarray   # (A, 4, 4) int64
    terms: bool                    # whether the model uses any term (vbd_step skips them if not)


def term_layout(arrays) -> TermLayout:
    count = arrays.inv_mass.shape[0]
    nodes = arrays.attachment_nodes.astype(np.int64)
    slots = np.full((len(nodes), 4, 4), count, np.int64)
    for j in range(4):
        slots[:, j, j] = nodes[:, j]
    used = any(term.used(arrays) for term in TERMS)
    return TermLayout(DiagonalSlots(np.arange(count, dtype=np.int64)), slots, used)


# --- the method ---------------------------------------------------------------------------------

@inline_kernel
def vbd_step(model, state, scratch, h, pairs):
    """One step: the world and the moving pins at the step's end, the first guess, the terrains
    near it, ``iterations`` sweeps colour by colour, then v = (x - x0) / h (module doc)."""
    graph, settings, layout, x0, y, v_k, term_force, term_blocks, planes, kd_over_h = scratch
    x, v, memory = state.x, state.v, state.memory
    move_world(model, step_end(model, h))
    aim_pins(model, x, v, h)
    start_guess(model, x, v, memory.velocity_change, h, x0, y)
    find_terrain_planes(model, x, planes)
    for _ in range(settings.iterations):
        if layout.terms:   # else term_force and term_blocks stay zero (vbd_scratch)
            linearize_terms(model, layout, x, x0, h, v_k, term_force, term_blocks)
        for colour in range(graph.colour_start.shape[0] - 1):
            sweep(model, scratch, colour, x, memory, h)
    end_velocities(model, planes, x, x0, v, memory.velocity_change, h)
    keep_friction(model, settings, x, planes, memory, h)
    return pairs


@inline_kernel
def start_guess(model, x, v, velocity_change, h, x0, y):
    """x0 = x; y = x + h v + h^2 g, the inertial target; x = the first guess (module doc). A
    pinned particle goes where its velocity takes it (aim_pins: its path's point) and stays."""
    g = model.gravity
    g0, g1, g2 = g[0], g[1], g[2]
    gravity = (g0 * g0 + g1 * g1 + g2 * g2) ** 0.5
    inv_mass = model.inv_mass   # locals: a threaded loop cannot take the model (_steps.py)
    for i in prange(x.shape[0]):
        along = 0.0
        if gravity > 0.0:   # the last acceleration along gravity, between 0 and gravity
            along = (velocity_change[i, 0] * g0 + velocity_change[i, 1] * g1
                     + velocity_change[i, 2] * g2) / (h * gravity)
            along = min(max(along, 0.0), gravity) / gravity
        free = 1.0 if inv_mass[i] > 0.0 else 0.0
        for c in range(3):
            x0[i, c] = x[i, c]
            y[i, c] = x[i, c] + h * v[i, c] + free * h * h * g[c]
            x[i, c] = x[i, c] + h * v[i, c] + free * along * h * h * g[c]


@inline_kernel
def find_terrain_planes(model, x, planes):
    """planes[i, t] = (n, c, w): terrain t near particle i as the plane phi(x) = n . x + c
    touching it at the particle's first guess, and its surface's velocity w there: contact is
    found once a step (as VBD finds it), and the sweeps read these planes, not the terrains. A
    lookup on a deforming mesh near its surface costs about 5 microseconds, which every block
    step of every iteration cannot pay (the cape: 321 ms a step, against 122 with the planes).
    c = inf: out of the terrain's reach (a deforming mesh answers infinity beyond it)."""
    inv_mass, offset = model.inv_mass, model.terrain_offset
    band = model.terrain_epsilon
    kind, parameters, data = model.terrain_kind, model.terrain_parameters, model.terrain_data
    motion, deforming = model.terrain_motion, model.terrain_deforming
    terrains = terrain_view(model)
    for i in prange(x.shape[0]):
        for t in range(band.shape[0]):
            for k in range(7):   # no plane: phi = 0 . x + inf
                planes[i, t, k] = np.inf if k == 3 else 0.0
            if inv_mass[i] == 0.0:
                continue
            still = motion[t] < 0 and deforming[t] < 0
            if still:   # looked up on the model's arrays, as collision/response/terrain.py does
                phi, nx, ny, nz = still_terrain_distance(kind[t], parameters[t], data, x[i, 0],
                                                         x[i, 1], x[i, 2], offset[i])
            else:
                phi, nx, ny, nz = terrain_at(terrains, t, x[i, 0], x[i, 1], x[i, 2], offset[i])
            if not phi < np.inf:
                continue
            u0 = u1 = u2 = 0.0
            if not still:
                u0, u1, u2 = surface_velocity(terrains, t, x[i, 0], x[i, 1], x[i, 2])
            planes[i, t, 0], planes[i, t, 1], planes[i, t, 2] = nx, ny, nz
            planes[i, t, 3] = phi - nx * x[i, 0] - ny * x[i, 1] - nz * x[i, 2]
            planes[i, t, 4], planes[i, t, 5], planes[i, t, 6] = u0, u1, u2


@kernel
def linearize_terms(model, layout, x, x0, h, v_k, force, blocks):
    """force = h F of every term at (x, (x - x0) / h), blocks = its share of backward Euler's
    matrix M - h dF/dv - h^2 dF/dx on each particle's diagonal (module doc)."""
    for i in range(x.shape[0]):
        for c in range(3):
            v_k[i, c] = (x[i, c] - x0[i, c]) / h
            force[i, c] = 0.0
    blocks[:] = 0.0
    add_step_end_forces(model, x, v_k, np.full(1, h), force)
    add_external_jacobians(model, layout, h, False, x, v_k, v_k, blocks, force)


@inline_kernel
def sweep(model, scratch, colour, x, memory, h):
    """One block step for each particle of ``colour`` (vbd/vertex.py), in parallel: they share
    no spring. The terrains are the step's planes (find_terrain_planes, in ``scratch``:
    vbd_scratch); friction is lagged from the last step (``memory``: vbd/contact.py);
    kd_over_h: each graph entry's kd / h (vbd_scratch). The model's arrays are read as locals, which a threaded loop can
    take, and arrays are indexed element by element, never sliced: a slice in the loop counts a
    reference to its array up and down for each particle."""
    graph, settings, _, x0, y, _, term_force, term_blocks, planes, kd_over_h = scratch
    inv_mass, drag, band = model.inv_mass, model.drag, model.terrain_epsilon
    start, other, rest_length, ks = graph.start, graph.other, graph.rest_length, graph.ks
    particles = graph.particles
    ratio, smoothing = settings.contact_stiffness_ratio, settings.friction_velocity * h
    rubbed, pressed = memory.terrain, memory.friction_damping
    for n in prange(graph.colour_start[colour], graph.colour_start[colour + 1]):
        i = particles[n]
        inertia = 1.0 / (inv_mass[i] * h * h)
        damping = drag[i] / h
        xi0, xi1, xi2 = x[i, 0], x[i, 1], x[i, 2]
        m0, m1, m2 = xi0 - x0[i, 0], xi1 - x0[i, 1], xi2 - x0[i, 2]
        diagonal, s = inertia + damping, 1.0 / (h * h)
        block = (-inertia * (xi0 - y[i, 0]) - damping * m0 + term_force[i, 0] / h,
                 -inertia * (xi1 - y[i, 1]) - damping * m1 + term_force[i, 1] / h,
                 -inertia * (xi2 - y[i, 2]) - damping * m2 + term_force[i, 2] / h,
                 diagonal + s * term_blocks[i, 0, 0], s * term_blocks[i, 0, 1],
                 s * term_blocks[i, 0, 2], diagonal + s * term_blocks[i, 1, 1],
                 s * term_blocks[i, 1, 2], diagonal + s * term_blocks[i, 2, 2])
        for k in range(start[n], start[n + 1]):   # the sweep's order (vbd/graph.py)
            j = other[k]
            block = added(block, spring_share((xi0, xi1, xi2), (m0, m1, m2),
                                              (x[j, 0], x[j, 1], x[j, 2]),
                                              (x0[j, 0], x0[j, 1], x0[j, 2]), rest_length[k],
                                              ks[k], kd_over_h[k]))
        for t in range(band.shape[0]):
            n0, n1, n2, offset = planes[i, t, 0], planes[i, t, 1], planes[i, t, 2], planes[i, t, 3]
            phi = n0 * xi0 + n1 * xi1 + n2 * xi2 + offset
            delta = OFFSET_OF_BAND * band[t]
            rubbing = pressed[i] if rubbed[i] == t else 0.0
            if not (phi < delta or (rubbing > 0.0 and phi < np.inf)):   # far, or out of reach
                continue
            block = added(block, contact_share(
                phi, n0, n1, n2, ratio * inertia, delta, rubbing, m0 - h * planes[i, t, 4],
                m1 - h * planes[i, t, 5], m2 - h * planes[i, t, 6], smoothing))
        d0, d1, d2 = solve_block(block)
        x[i, 0] = xi0 + d0
        x[i, 1] = xi1 + d1
        x[i, 2] = xi2 + d2


@inline_kernel
def keep_friction(model, settings, x, planes, memory, h):
    """For the next step's friction (vbd/contact.py): each particle's terrain pressed hardest at
    x (memory.terrain, -1 for none), by the step's planes, and mu lambda there
    (memory.friction_damping)."""
    inv_mass, band, friction = model.inv_mass, model.terrain_epsilon, model.terrain_friction
    ratio = settings.contact_stiffness_ratio
    rubbed, pressed = memory.terrain, memory.friction_damping
    for i in prange(x.shape[0]):
        rubbed[i], pressed[i] = -1, 0.0
        if inv_mass[i] == 0.0:
            continue
        hardest = 0.0
        for t in range(band.shape[0]):
            plane = planes[i, t]
            phi = plane[0] * x[i, 0] + plane[1] * x[i, 1] + plane[2] * x[i, 2] + plane[3]
            pressure = contact_pressure(phi, ratio / (inv_mass[i] * h * h),
                                        OFFSET_OF_BAND * band[t])
            if pressure > hardest:
                hardest, rubbed[i], pressed[i] = pressure, t, friction[t] * pressure


@inline_kernel
def end_velocities(model, planes, x, x0, v, velocity_change, h):
    """v = (x - x0) / h, the change kept for the next step's guess; then each impact's approach
    speed restored (``restored_impact``), for the pass after the step to reflect with the
    terrain's restitution."""
    inv_mass, band, g = model.inv_mass, model.terrain_epsilon, model.gravity
    resting = 2.0 * math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    for i in prange(x.shape[0]):
        for c in range(3):
            new = (x[i, c] - x0[i, c]) / h
            velocity_change[i, c] = new - v[i, c]
            v[i, c] = new
        if inv_mass[i] > 0.0:
            restored_impact(planes[i], band, resting, x[i], x0[i], v0_of(v, velocity_change, i),
                            v[i])


@inline_kernel
def v0_of(v, velocity_change, i):
    """The velocity particle i started the step with."""
    return (v[i, 0] - velocity_change[i, 0], v[i, 1] - velocity_change[i, 1],
            v[i, 2] - velocity_change[i, 2])


@inline_kernel
def restored_impact(planes, band, resting, x, x0, v0, v):
    """The minimization stops an approach dead (contact inside it is inelastic). Where a
    particle started the step out of terrain t's band, ends it inside, and approached faster
    than resting contact does (sqrt(2 |g| epsilon), the impact pass's own threshold), its
    normal velocity relative to the surface is put back to the approach's, as backward Euler
    restores it (implicit/constraints.restore_impact_speeds): the impact pass after the step
    then reflects it, v_n' = -e v_n. ``resting``: 2 |g|."""
    for t in range(band.shape[0]):
        n0, n1, n2, offset = planes[t, 0], planes[t, 1], planes[t, 2], planes[t, 3]
        if not offset < np.inf:
            continue
        start = n0 * x0[0] + n1 * x0[1] + n2 * x0[2] + offset
        end = n0 * x[0] + n1 * x[1] + n2 * x[2] + offset
        w0, w1, w2 = planes[t, 4], planes[t, 5], planes[t, 6]
        approach = (v0[0] - w0) * n0 + (v0[1] - w1) * n1 + (v0[2] - w2) * n2
        if not (start >= band[t] and end < band[t]
                and approach < -math.sqrt(resting * band[t])):
            continue
        now = (v[0] - w0) * n0 + (v[1] - w1) * n1 + (v[2] - w2) * n2
        if now > approach:
            change = approach - now
            v[0] += change * n0
            v[1] += change * n1
            v[2] += change * n2
        return


# --- the driver ---------------------------------------------------------------------------------

@kernel
def vbd_scratch(graph, settings, layout, x, terrain_count, h):
    """What vbd_step takes besides the state, as a plain tuple (a threaded kernel's array
    analysis cannot take a NamedTuple apart: _steps.py): the work arrays, and each graph
    entry's kd / h, which every block step reads (a division fewer a spring)."""
    return (graph, settings, layout, np.empty_like(x), np.empty_like(x), np.empty_like(x),
            np.zeros_like(x), np.zeros((x.shape[0] + 1, 3, 3)),
            np.empty((x.shape[0], terrain_count, 7)), graph.kd / h)


threaded_vbd_step = threaded(vbd_step)


@kernel
def advance(model, graph, settings, layout, state, h, steps, pairs):
    """Take ``steps`` steps of ``state`` (an ImplicitState, changed in place); returns (steps
    done, first diverged particle or -1, the post-step pass's pair list: _steps.drive)."""
    scratch = vbd_scratch(graph, settings, layout, state.x, model.terrain_epsilon.shape[0],
                          h)
    return drive(vbd_step, model, state, scratch, h, steps, pairs)


@parallel_kernel
def parallel_advance(model, graph, settings, layout, state, h, steps, pairs):
    """advance, each colour's particles on threads."""
    scratch = vbd_scratch(graph, settings, layout, state.x, model.terrain_epsilon.shape[0],
                          h)
    return threaded_drive(threaded_vbd_step, model, state, scratch, h, steps, pairs)


THREADED_FROM = 2048   # free particles from which a model runs the threaded kernel


@register
class VertexBlockDescent(KernelIntegrator):
    """Options (scene ``[vbd]``): ``iterations`` (sweeps a step, default 10),
    ``contact_stiffness_ratio`` (terrain contact stiffness over a particle's m/h^2, default
    1,000) and ``friction_velocity`` (m/s, default 0.001: slower sliding is held). Its kernels
    take the model's graph and settings besides the state (``kernel_call``), and it picks the
    threaded one by its free particles (THREADED_FROM); KernelIntegrator's ``advance`` calls
    them."""

    name = "vbd"
    order = 1
    summary = ("vertex block descent: backward Euler's step minimized particle by particle, "
               "a fixed cost a step")
    SECTION = "vbd"
    OPTIONS = ("iterations", "contact_stiffness_ratio", "friction_velocity")
    kernel = staticmethod(advance)
    parallel_kernel = staticmethod(parallel_advance)

    def __init__(self, iterations=10, contact_stiffness_ratio=1000.0, friction_velocity=1e-3,
                 **others):
        for key, value in others.items():
            raise SceneError(f"integrator option {key}", value,
                             f"'{self.name}' takes only " + ", ".join(self.OPTIONS))
        require(_is_whole(iterations) and 1 <= iterations <= 10000, "vbd.iterations", iterations,
                "must be a whole number from 1 to 10000")
        require(_is_number(contact_stiffness_ratio) and contact_stiffness_ratio > 0,
                "vbd.contact_stiffness_ratio", contact_stiffness_ratio,
                "must be a number > 0 (times m/h^2)")
        require(_is_number(friction_velocity) and friction_velocity > 0,
                "vbd.friction_velocity", friction_velocity, "must be a speed > 0 m/s")
        self.settings = Settings(int(iterations), float(contact_stiffness_ratio),
                                 float(friction_velocity))

    def tables(self, model) -> tuple:
        """The model's graph and term layout, built on first use and kept with the model."""
        kept = self.model_cache(model)
        if "graph" not in kept:
            kept["graph"] = vertex_graph(model.arrays)
            kept["layout"] = term_layout(model.arrays)
        return kept["graph"], kept["layout"]

    def kernel_call(self, model, state, dt, steps, threaded=None) -> KernelCall:
        graph, layout = self.tables(model)
        if threaded is None:
            threaded = graph.particles.shape[0] >= THREADED_FROM
        return KernelCall(self.parallel_kernel if threaded else self.serial_kernel(model), (
            model.arrays, graph, self.settings, layout,
            ImplicitState(state.positions, state.velocities, state.contacts), float(dt),
            int(steps), state.pairs))

    def parts(self, model, state, dt):
        from ..plain import plain_parts

        # no accelerations: its blocks are its own
        return plain_parts(drive_parts(model, state, dt), model)

