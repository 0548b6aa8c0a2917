"""Contact between particles and terrains.

How contact enters an integrator, and why (a terrain that moves, motion.py, is looked up where it
is at the time the stage asks for, world.py, and every velocity below is relative to its
surface's velocity at the contact point, rotation included: a body on a moving platform rides
along by static friction, and a ball leaves a moving wall at e times their approach speed):

1. Inside every force evaluation (every stage of a multi-stage method, on that stage's temporary
   state) a particle within the contact band (phi < epsilon) feels the terrain's reaction: the part
   of its acceleration that pushes into the surface is cancelled, and Coulomb friction acts against
   its sliding velocity with at most ``friction`` times that normal reaction. Friction is written as
   the tangential acceleration that would stop the sliding within the current step ``h``, clamped
   to the Coulomb cone: inside the cone the particle sticks (static friction, no creeping); outside
   it slides with kinetic friction along -v_T (see ``coulomb_friction`` for the slow end of
   sliding). Nothing divides by a zero |v_T|, so a particle at rest is no special case. Because the reaction is a force, every stage sees it and the method
   keeps its order away from impacts.
   A particle in the band that already moves away from the surface (v_N > 0) keeps the part of the
   push that stops it within the step: the reaction is -a_N - v_N / h, or none when that is
   negative (it leaves fast, or is pulled away). Cancelling the whole push instead would let it
   coast outwards at constant speed to the edge of the band, fall back in, bounce, and repeat: an
   endless chatter fed by a reaction doing positive work, with friction lost on every excursion
   (a cube resting on the plane kept vibrating that way, and one on a steep slope crept).
2. After the whole step, an impact pass: a particle within the band that still approaches the
   surface has its normal velocity reflected with restitution (v' = -e v_N + v_T, v_N relative
   to the surface's own velocity), and a particle
   that ended the step inside the surface is moved back onto it. A step of any size therefore ends
   with no penetration, whatever the integrator did in between; doing this once per step (not per
   stage) keeps stages smooth functions of the state, which is what their order relies on.
   An approach slower than sqrt(2 |g| epsilon) is resting contact, not an impact: its rebound
   would not even lift the particle out of the contact band, so it is below what the band
   resolves, and reflecting it would keep a resting body vibrating forever. Such approaches are
   stopped (restitution 0).
"""
import math

from numba import prange
import numpy as np

from ..._jit import inline_kernel, kernel
from ...terrains import still_terrain_distance, terrain_looks_ahead
from ...world import surface_velocity, terrain_at, terrain_view


BLOCK = 64   # particles whose terrain distances are looked up together (see apply_contact_forces)

# STILL_LOOKUP: the per-particle loops look a still terrain up with the still dispatcher
# (terrains/dispatch.py) directly on the model's arrays, as before terrains moved; the view
# (world.terrain_at) is for the moving ones. An inline kernel taking arrays held across the
# loop counts their references at every call: through the view, a still plane's contact was two
# to three times slower (benchmarks/terrain_lookup.py).


@inline_kernel
def apply_contact_forces(model, x, v, h, a):
    """Cancel accelerations into touched terrains and add Coulomb friction (see module doc).

    With a terrain kind whose lookup is long (a mesh's grid: an index, eight loads, the
    interpolation and a square root, one after the other) the particles go a block at a time
    (apply_contact_forces_in_blocks); otherwise one by one, which is faster for short lookups
    (benchmarks/mesh_terrain.py compares both). One by one, the particles
    are independent, so a threaded kernel (integrators.KernelIntegrator) shares them among its
    threads, with the same results (this is inlined for that: a kernel's loops run on threads
    only in the kernel compiled with them); blocks run serially. The contact arithmetic is
    written out in both loops: moved into an inline kernel taking a and v, it made the plane's
    contact several times slower (references counted per call), and into a kernel
    on scalars 1.5 times."""
    epsilon, friction = model.terrain_epsilon, model.terrain_friction
    terrains = terrain_view(model)
    blocks = False
    for t in range(epsilon.shape[0]):
        blocks = blocks or terrain_looks_ahead(model.terrain_kind[t])
    if blocks:
        apply_contact_forces_in_blocks(model, x, v, h, a)
        return
    # the model's arrays the particle loop reads, as locals: a threaded kernel's loop takes
    # what it reads as arguments, and the model's nested tables (term_tables) cannot be one
    inv_mass, terrain_offset = model.inv_mass, model.terrain_offset
    terrain_kind, terrain_parameters = model.terrain_kind, model.terrain_parameters
    terrain_data, terrain_motion = model.terrain_data, model.terrain_motion
    terrain_deforming = model.terrain_deforming
    for i in prange(x.shape[0]):
        if inv_mass[i] == 0.0:
            continue
        for t in range(epsilon.shape[0]):
            # a still terrain looked up with the model's own arrays (STILL_LOOKUP)
            still = terrain_motion[t] < 0 and terrain_deforming[t] < 0
            if still:
                phi, nx, ny, nz = still_terrain_distance(
                    terrain_kind[t], terrain_parameters[t], terrain_data,
                    x[i, 0], x[i, 1], x[i, 2], terrain_offset[i])
            else:
                phi, nx, ny, nz = terrain_at(terrains, t, x[i, 0], x[i, 1], x[i, 2],
                                             terrain_offset[i])
            if phi >= epsilon[t]:
                continue
            a_n = a[i, 0] * nx + a[i, 1] * ny + a[i, 2] * nz
            # the velocity relative to the terrain's surface there (zero for a still terrain)
            u0 = u1 = u2 = 0.0
            if not still:
                u0, u1, u2 = surface_velocity(terrains, t, x[i, 0], x[i, 1], x[i, 2])
            r0, r1, r2 = v[i, 0] - u0, v[i, 1] - u1, v[i, 2] - u2
            v_n = r0 * nx + r1 * ny + r2 * nz
            # The reaction cancels the push into the surface; a particle already moving away
            # keeps the part of the push that stops it within this step (see module doc).
            reaction = -a_n - max(v_n, 0.0) / h
            if reaction <= 0.0:
                continue  # pulled away from the surface, or leaving fast: no reaction, no friction
            # tangential acceleration and tangential (sliding) velocity
            ax, ay, az = a[i, 0] - a_n * nx, a[i, 1] - a_n * ny, a[i, 2] - a_n * nz
            tx, ty, tz = r0 - v_n * nx, r1 - v_n * ny, r2 - v_n * nz
            fx, fy, fz = coulomb_friction(ax, ay, az, tx, ty, tz, friction[t] * reaction, h)
            a_normal = a_n + reaction  # -max(v_n, 0) / h: zero for a particle at rest
            a[i, 0] = ax + fx + a_normal * nx
            a[i, 1] = ay + fy + a_normal * ny
            a[i, 2] = az + fz + a_normal * nz


@kernel
def apply_contact_forces_in_blocks(model, x, v, h, a):
    """apply_contact_forces, a block of particles at a time: the terrains whose lookup is long
    are looked up for the whole block before its contact, so that the processor overlaps the
    lookups of many particles instead of stalling the contact arithmetic behind each one (a
    mesh floor's contact: benchmarks/mesh_terrain.py). A particle
    meets the terrains in the same order as one by one, so the results are the same."""
    epsilon, friction = model.terrain_epsilon, model.terrain_friction
    terrains = terrain_view(model)
    found = np.empty((BLOCK, 4))
    for start in range(0, x.shape[0], BLOCK):
        stop = min(start + BLOCK, x.shape[0])
        for t in range(epsilon.shape[0]):
            ahead = terrain_looks_ahead(model.terrain_kind[t])
            if ahead:
                for i in range(start, stop):
                    found[i - start, 0], found[i - start, 1], found[i - start, 2], \
                        found[i - start, 3] = terrain_at(
                            terrains, t, x[i, 0], x[i, 1], x[i, 2], model.terrain_offset[i])
            for i in range(start, stop):
                if model.inv_mass[i] == 0.0:
                    continue
                if ahead:
                    phi, nx, ny, nz = found[i - start, 0], found[i - start, 1], \
                        found[i - start, 2], found[i - start, 3]
                else:
                    phi, nx, ny, nz = terrain_at(terrains, t, x[i, 0], x[i, 1], x[i, 2],
                                                 model.terrain_offset[i])
                if phi >= epsilon[t]:
                    continue
                a_n = a[i, 0] * nx + a[i, 1] * ny + a[i, 2] * nz
                u0, u1, u2 = surface_velocity(terrains, t, x[i, 0], x[i, 1], x[i, 2])
                r0, r1, r2 = v[i, 0] - u0, v[i, 1] - u1, v[i, 2] - u2
                v_n = r0 * nx + r1 * ny + r2 * nz   # relative to the surface
                # The reaction cancels the push into the surface; a particle already moving away
                # keeps the part of the push that stops it within this step (see module doc).
                reaction = -a_n - max(v_n, 0.0) / h
                if reaction <= 0.0:
                    continue  # pulled away, or leaving fast: no reaction, no friction
                # tangential acceleration and tangential (sliding) velocity
                ax, ay, az = a[i, 0] - a_n * nx, a[i, 1] - a_n * ny, a[i, 2] - a_n * nz
                tx, ty, tz = r0 - v_n * nx, r1 - v_n * ny, r2 - v_n * nz
                fx, fy, fz = coulomb_friction(ax, ay, az, tx, ty, tz, friction[t] * reaction, h)
                a_normal = a_n + reaction  # -max(v_n, 0) / h: zero for a particle at rest
                a[i, 0] = ax + fx + a_normal * nx
                a[i, 1] = ay + fy + a_normal * ny
                a[i, 2] = az + fz + a_normal * nz


@kernel
def coulomb_friction(ax, ay, az, tx, ty, tz, limit, h):
    """Friction acceleration on a particle with tangential acceleration a_T and sliding velocity
    v_T, at most ``limit`` (friction times the normal reaction, per unit mass).

    Sticking: the acceleration that would stop the sliding within this step, -(a_T + v_T / h),
    when the cone allows it. Sliding: ``limit`` along -v_T (Coulomb's kinetic friction) when even
    that cannot stop the sliding within the step (|v_T| > limit h); below that speed the direction
    of the end-of-step velocity -(a_T + v_T / h) is used instead, which does not flip from step to
    step as the sliding stops. Never divides by a zero |v_T|.
    """
    sx, sy, sz = -(ax + tx / h), -(ay + ty / h), -(az + tz / h)
    stick = math.sqrt(sx * sx + sy * sy + sz * sz)
    if stick <= limit:
        return sx, sy, sz
    speed = math.sqrt(tx * tx + ty * ty + tz * tz)
    if speed > limit * h:
        return -limit * tx / speed, -limit * ty / speed, -limit * tz / speed
    return limit * sx / stick, limit * sy / stick, limit * sz / stick


@inline_kernel
def resolve_terrain_impacts(model, x, v):
    """After a step: reflect approaching velocities with restitution, lift particles out.
    Particle by particle, independently: on threads in a threaded kernel (apply_contact_forces)."""
    epsilon, restitution = model.terrain_epsilon, model.terrain_restitution
    terrains = terrain_view(model)
    g = model.gravity
    g_size = math.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
    # the model's arrays the particle loop reads, as locals: a threaded kernel's loop takes
    # what it reads as arguments, and the model's nested tables (term_tables) cannot be one
    inv_mass, terrain_offset = model.inv_mass, model.terrain_offset
    terrain_kind, terrain_parameters = model.terrain_kind, model.terrain_parameters
    terrain_data, terrain_motion = model.terrain_data, model.terrain_motion
    terrain_deforming = model.terrain_deforming
    for i in prange(x.shape[0]):
        if inv_mass[i] == 0.0:
            continue
        for t in range(epsilon.shape[0]):
            still = terrain_motion[t] < 0 and terrain_deforming[t] < 0
            if still:   # STILL_LOOKUP
                phi, nx, ny, nz = still_terrain_distance(
                    terrain_kind[t], terrain_parameters[t], terrain_data,
                    x[i, 0], x[i, 1], x[i, 2], terrain_offset[i])
            else:
                phi, nx, ny, nz = terrain_at(terrains, t, x[i, 0], x[i, 1], x[i, 2],
                                             terrain_offset[i])
            if phi >= epsilon[t]:
                continue
            u0 = u1 = u2 = 0.0
            if not still:
                u0, u1, u2 = surface_velocity(terrains, t, x[i, 0], x[i, 1], x[i, 2])
            v_n = (v[i, 0] - u0) * nx + (v[i, 1] - u1) * ny + (v[i, 2] - u2) * nz   # relative
            if v_n < 0.0:
                # slower than this, the rebound would stay in the band: resting contact (module doc)
                resting_speed = math.sqrt(2.0 * g_size * epsilon[t])
                e = restitution[t] if -v_n > resting_speed else 0.0
                bounce = (1.0 + e) * v_n
                v[i, 0] -= bounce * nx
                v[i, 1] -= bounce * ny
                v[i, 2] -= bounce * nz
            if phi < 0.0:
                x[i, 0] -= phi * nx
                x[i, 1] -= phi * ny
                x[i, 2] -= phi * nz
