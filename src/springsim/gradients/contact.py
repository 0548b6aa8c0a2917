"""Terrain contact of the explicit methods (collision/response/terrain.py) as differentiable
NumPy, and its vector-Jacobian products.

Two pieces, as the forward has them:

- ``contact_accelerations``: inside every force evaluation a particle in a terrain's band whose
  reaction -a_n - max(v_n, 0)/h is positive has its push into the surface cancelled and Coulomb
  friction added (sticking, kinetic, or the slow end of sliding: ``coulomb_friction``);
- ``impacts``: after the step, an approaching particle in the band has its normal velocity
  reflected with restitution (none below the resting speed), and one inside the surface is moved
  back onto it.

Both are the kernels' arithmetic in the kernels' order (terrain after terrain, each seeing what
the last one left), with the branch each particle takes found the same way, so the gradient is of
the run the simulation computed. Each branch is a smooth function of (x, v, friction,
restitution); the gradient is that branch's derivative. Where a particle changes branch (it
touches down, leaves, starts or stops sliding, bounces) the motion has a kink or a jump and the
gradient is the one-sided derivative of the branch the run took: finite, never NaN.

Planes, spheres, bowls and meshes, still or moving rigidly (terrain_shapes.py): a plane's normal
is the same everywhere, so the contact depends on positions only through which branch a particle
takes; a sphere's or a mesh's turns with the position, and its derivative (the curvature) carries
the normal's cotangent to the positions. On a moving terrain every velocity is relative to its
surface's, u = c' + w x (x - c), which depends on the position too: the relative velocity's
cotangent reaches the positions through du/dx = [w]x. A deforming mesh's surface moves with its
point cache: u is its closest point's, interpolated from its corners, and du/dx comes from how
that point's weights change with the position (terrain_shapes.Deforming).
Backward Euler's contact (implicit_contact.py) follows the still ones.
"""
import math
from typing import NamedTuple

import numpy as np

from ..terrains.deforming_mesh import REACH
from .clock import at_time
from ..terrains.plane import Flat
from .kernels import largest_component
from .terrain_shapes import Deforming, Moving, surface_velocity


class Planes(NamedTuple):
    """The model's terrains as contact needs them: one row per terrain (a terrain without a
    shape is not followed; checks.py refuses touching it)."""

    epsilon: np.ndarray     # (T,) m, the contact band
    offset: np.ndarray      # (P,) m, kept between a particle and a terrain
    resting_speed: np.ndarray   # (T,) m/s, approaches slower than this do not bounce
    shapes: tuple = ()      # (T,) terrain_shapes' shape of each terrain followed, or None

    @classmethod
    def of(cls, model, clock=None) -> "Planes":
        """``clock``: the adjoint's (clock.py), which the moving terrains' shapes read."""
        arrays = model.arrays
        shapes = []
        clock = np.zeros(2) if clock is None else clock
        for t, terrain in enumerate(model.terrains):
            row = arrays.terrain_parameters[t]
            motion, deforming = arrays.terrain_motion[t], arrays.terrain_deforming[t]
            shape = (terrain.adjoint_shape(row) if deforming < 0
                     else Deforming(terrain.deforming_surface(), clock,
                                    float(arrays.terrain_data[deforming + REACH])))
            if shape is not None and motion >= 0 and deforming < 0:
                shape = Moving(shape, int(motion), arrays.motion_info, arrays.motion_keys, clock)
            shapes.append(shape)
        g = arrays.gravity
        g_size = np.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
        epsilon = arrays.terrain_epsilon.astype(float)
        return cls(epsilon, arrays.terrain_offset.astype(float),
                   np.sqrt(2.0 * g_size * epsilon), tuple(shapes))


def along(u: np.ndarray, n: np.ndarray) -> np.ndarray:
    """u . n per row; n one normal (3,) or one per row (K, 3)."""
    return u[:, 0] * n[..., 0] + u[:, 1] * n[..., 1] + u[:, 2] * n[..., 2]


def followed(planes: Planes):
    """(t, shape) of every terrain the explicit methods' contact adjoint follows."""
    return [(t, shape) for t, shape in enumerate(planes.shapes) if shape is not None]


class Reach(NamedTuple):
    """How near one state's free particles come to each followed terrain (m), at most how fast
    they go (m/s: sqrt(3) times the largest velocity component, cheaper than the norms), and
    the positions it is of. far_from_terrains looks at each state twice, as one
    step's start and the step before's end: among still terrains the second look reuses it."""

    positions: np.ndarray
    nearest: np.ndarray
    speed: float


def reach(physical, shapes, x, v) -> Reach:
    """The state (x, v)'s Reach to ``shapes`` [(t, shape)], each where physical's clock has it."""
    free, offset = physical.free, physical.planes.offset
    nearest = np.array([least_distance(shape, x, offset, free) for _, shape in shapes])
    return Reach(x, nearest, math.sqrt(3.0) * largest_component(v))


def least_distance(shape, x, offset, free) -> float:
    """The least distance of a free particle to ``shape``: its own, quicker, where it has one."""
    if hasattr(shape, "least_distance"):
        return shape.least_distance(x, offset, free)
    # np.where, not indexing by the mask: 3 times faster
    return float(np.min(np.where(free, shape.distance(x, offset), np.inf), initial=np.inf))


def far_from_terrains(physical, h, start, end, known: Reach | None = None):
    """(far, the start's Reach): far when no stage of a step can have touched a followed
    terrain: every free particle starts and ends it farther from each (a moving one where it is
    then) than the band and twice the distance its fastest particle and the terrain's surface
    there cover in a step (an explicit step's stages stay within h |v| of its start, near
    enough). The adjoint then skips contact (run_kernels.rk4_step_vjp). ``known``: the Reach
    of the step after's start, which is this step's end, where every followed terrain is
    still."""
    planes = physical.planes
    shapes = followed(planes)
    if not shapes:
        return True, None
    (x, v), (x_end, v_end) = start[:2], end[:2]
    still = not any(hasattr(shape, "velocity") for _, shape in shapes)
    at_time(physical, 0.0)   # a moving terrain where it is at the step's start and end
    first = reach(physical, shapes, x, v)
    sweeps = [surface_velocity(shape, x) for _, shape in shapes]
    at_time(physical, h)
    last = (known if still and known is not None and known.positions is x_end
            else reach(physical, shapes, x_end, v_end))
    speed = max(first.speed, last.speed)
    for j, (t, shape) in enumerate(shapes):
        sweep = sweeps[j]   # the terrain's surface moves as far again
        sweep = 0.0 if sweep is None else float(np.sqrt(np.max(np.einsum(
            "ij,ij->i", sweep, sweep)[physical.free], initial=0.0)))
        reach_t = planes.epsilon[t] + 2.0 * h * (speed + sweep)
        if min(first.nearest[j], last.nearest[j]) < reach_t:
            return False, first
    return True, first


FAR_CHUNK = 64   # states far_steps takes at a time


def far_steps(physical, h, starts):
    """far_from_terrains for every step of a run of states at once, ``starts`` (S, 2, P, 3)
    (tape.KeepingRun): (S - 1,) bool, or None where some followed terrain is not a still plane
    (each step then takes far_from_terrains). NumPy over all the states is a few microseconds a
    step against some fifty for a call a step."""
    planes = physical.planes
    shapes = followed(planes)
    if not all(isinstance(shape, Flat) for _, shape in shapes):
        return None
    x, v = starts[:, 0], starts[:, 1]
    # no temporary of the states' size: the tape holding them already fills its memory limit
    speed = math.sqrt(3.0) * np.maximum(v.max(axis=(1, 2), initial=0.0),
                                        -v.min(axis=(1, 2), initial=0.0))
    travel = 2.0 * h * np.maximum(speed[:-1], speed[1:])
    far = np.ones(len(starts) - 1, bool)
    for t, shape in shapes:
        nearest = np.concatenate([
            np.where(physical.free, x[k:k + FAR_CHUNK] @ shape.normal - planes.offset,
                     np.inf).min(axis=1, initial=np.inf) for k in range(0, len(x), FAR_CHUNK)])
        nearest -= float(shape.point @ shape.normal)
        far &= np.minimum(nearest[:-1], nearest[1:]) >= planes.epsilon[t] + travel
    return far


# --- the reaction and friction inside each force evaluation --------------------------------------

STICK, KINETIC, SLOWING = 0, 1, 2
STEP = 1e-30   # normal_vjp's complex step


class Touch(NamedTuple):
    """What one terrain did to the particles it touched in one force evaluation."""

    index: np.ndarray    # (K,) the particles
    a: np.ndarray        # (K, 3) their accelerations before it
    v: np.ndarray        # (K, 3) their velocities
    case: np.ndarray     # (K,) STICK, KINETIC or SLOWING (coulomb_friction's branches)
    n: np.ndarray        # (K, 3) the terrain's normal at each
    curvature: np.ndarray | None   # (K, 3, 3) (dn/dx)^T there, None for a plane
    moving: object       # the terrain's shape if its surface moves (v is relative to it), or None
    x: np.ndarray        # (K, 3) their positions


def contact_accelerations(physical, x, v, h, a):
    """(a after contact, [Touch or None per terrain]): apply_contact_forces."""
    planes = physical.planes
    touches = [None] * len(planes.epsilon)
    for t, shape in followed(planes):
        n = shape.normals(x)
        phi = shape.distance(x, planes.offset)
        u = surface_velocity(shape, x)
        relative = v if u is None else v - u
        a_n, v_n = along(a, n), along(relative, n)
        reaction = -a_n - np.maximum(v_n, 0.0) / h
        index = np.nonzero(physical.free & (phi < planes.epsilon[t]) & (reaction > 0.0))[0]
        if not len(index):
            continue
        ai, vi, ni = a[index], relative[index], n[index]
        new, case = touched(ai, vi, ni, physical.friction[t], h)
        a = a.copy()
        a[index] = new
        touches[t] = Touch(index, ai, vi, case, ni, shape.curvature(x[index]),
                           shape if u is not None else None, x[index])
    return a, touches


def touched(a, v, n, friction, h):
    """(the accelerations after contact, coulomb_friction's branch) of particles in contact,
    n one normal per particle."""
    a_n, v_n = along(a, n), along(v, n)
    reaction = -a_n - np.maximum(v_n, 0.0) / h
    at = a - a_n[:, None] * n
    vt = v - v_n[:, None] * n
    limit = friction * reaction
    s = -(at + vt / h)
    stick = np.sqrt(s[:, 0] * s[:, 0] + s[:, 1] * s[:, 1] + s[:, 2] * s[:, 2])
    speed = np.sqrt(vt[:, 0] * vt[:, 0] + vt[:, 1] * vt[:, 1] + vt[:, 2] * vt[:, 2])
    case = np.where(stick <= limit, STICK, np.where(speed > limit * h, KINETIC, SLOWING))
    return response(a, v, n, friction, h, case, v_n > 0.0), case


def response(a, v, n, friction, h, case, leaving):
    """``touched``'s accelerations on the branches ``case`` and ``leaving`` (v . n > 0), for
    real or complex inputs (contact_normal_vjp steps the normal into the complex plane)."""
    a_n, v_n = along(a, n), along(v, n)
    reaction = -a_n - np.where(leaving, v_n, 0.0) / h
    at = a - a_n[:, None] * n
    vt = v - v_n[:, None] * n
    limit = friction * reaction
    s = -(at + vt / h)
    stick = np.sqrt(np.sum(s * s, axis=1))
    speed = np.sqrt(np.sum(vt * vt, axis=1))
    kinetic, slowing = case == KINETIC, case == SLOWING
    f = np.where(kinetic[:, None], -limit[:, None] * vt / np.where(kinetic, speed, 1.0)[:, None],
                 np.where(slowing[:, None],
                          limit[:, None] * s / np.where(slowing, stick, 1.0)[:, None], s))
    return at + f + (a_n + reaction)[:, None] * n


def normal_vjp(touch, friction, h, g):
    """The cotangent of each touched particle's normal (K, 3), by complex steps of
    ``response`` on the branches the run took (exact to rounding, as a written-out
    derivative)."""
    leaving = along(touch.v, touch.n) > 0.0
    n_bar = np.empty_like(touch.n)
    for c in range(3):
        n = touch.n.astype(complex)
        n[:, c] += 1j * STEP
        moved = response(touch.a, touch.v, n, friction, h, touch.case, leaving)
        n_bar[:, c] = np.sum(g * moved.imag, axis=1) / STEP
    return n_bar


def add_curvature(rows, curvature, n_bar, x_bar):
    """x_bar[rows] += (dn/dx)^T n_bar (``curvature`` is the transpose); nothing for a plane."""
    if curvature is not None:
        np.add.at(x_bar, rows, np.einsum("kij,kj->ki", curvature, n_bar))


def contact_accelerations_vjp(physical, h, touches, g, x_bar, v_bar, bar):
    """The cotangent of the accelerations before contact, given g on those after; adds the
    positions' share (a curved terrain's normal) into x_bar, the velocities' into v_bar and
    friction's into bar.friction. Terrains in reverse."""
    g = g.copy()
    for t in reversed(range(len(touches))):
        touch = touches[t]
        if touch is None:
            continue
        gi = g[touch.index]
        a_bar, vi_bar, friction_bar = touched_vjp(touch, touch.n, physical.friction[t], h, gi)
        if touch.curvature is not None:
            add_curvature(touch.index, touch.curvature,
                          normal_vjp(touch, physical.friction[t], h, gi), x_bar)
        g[touch.index] = a_bar
        np.add.at(v_bar, touch.index, vi_bar)
        if touch.moving is not None:   # v - u(x)
            np.add.at(x_bar, touch.index, touch.moving.velocity_vjp(touch.x, -vi_bar))
        bar.friction[t] += friction_bar
    return g


def touched_vjp(touch, n, friction, h, g):
    """(a_bar, v_bar, friction_bar) of ``touched`` for the cotangent g of its output.
    a' = a_T + f(a_T, v_T, limit) - max(v_n, 0)/h n,  limit = friction (-a_n - max(v_n, 0)/h)."""
    a, v, case = touch.a, touch.v, touch.case
    a_n, v_n = along(a, n), along(v, n)
    leaving = v_n > 0.0
    reaction = -a_n - np.maximum(v_n, 0.0) / h
    at, vt = a - a_n[:, None] * n, v - v_n[:, None] * n
    limit = friction * reaction
    s = -(at + vt / h)
    at_bar, vt_bar = g.copy(), np.zeros_like(g)
    v_n_bar = -np.where(leaving, along(g, n), 0.0) / h       # a_normal = -max(v_n, 0) / h
    limit_bar = np.zeros(len(g))
    stick = case == STICK
    # sticking: f = s = -(a_T + v_T / h)
    s_bar = np.where(stick[:, None], g, 0.0)
    # kinetic: f = -limit v_T / |v_T|
    k = case == KINETIC
    if k.any():
        speed = np.linalg.norm(vt[k], axis=1)
        u, gk = vt[k] / speed[:, None], g[k]
        gu = np.einsum("ij,ij->i", gk, u)
        limit_bar[k] = -gu
        vt_bar[k] -= limit[k, None] * (gk - gu[:, None] * u) / speed[:, None]
    # the slow end of sliding: f = limit s / |s|
    w = case == SLOWING
    if w.any():
        size = np.linalg.norm(s[w], axis=1)
        u, gw = s[w] / size[:, None], g[w]
        gu = np.einsum("ij,ij->i", gw, u)
        limit_bar[w] = gu
        s_bar[w] += limit[w, None] * (gw - gu[:, None] * u) / size[:, None]
    at_bar -= s_bar
    vt_bar -= s_bar / h
    friction_bar = float(np.sum(limit_bar * reaction))
    reaction_bar = limit_bar * friction
    a_n_bar = -reaction_bar
    v_n_bar -= np.where(leaving, reaction_bar, 0.0) / h
    # a_T = (I - n n^T) a, v_T likewise
    a_bar = at_bar - along(at_bar, n)[:, None] * n + a_n_bar[:, None] * n
    v_bar = vt_bar - along(vt_bar, n)[:, None] * n + v_n_bar[:, None] * n
    return a_bar, v_bar, friction_bar


# --- the impact pass after each step ------------------------------------------------------------

class Impact(NamedTuple):
    """What one terrain's impact pass did: particles whose normal velocity it took away
    (``bounced``, with the restitution used, e or 0) and those it moved out (``lifted``), with
    the normal, the distance's gradient, the curvature (None for a plane) and what they
    were."""

    bounced: np.ndarray
    fast: np.ndarray      # (len(bounced),) bool: reflected with the terrain's restitution
    v_n: np.ndarray       # their approach speeds
    lifted: np.ndarray
    v: np.ndarray         # (len(bounced), 3) the bounced particles' velocities before
                          # (relative to a moving terrain's surface)
    n: np.ndarray         # (P, 3) the terrain's normal at every particle, before lifting
    phi: np.ndarray       # (P,) and the distance
    curvature: object     # shape.curvature, called for the rows that need it
    gradient: object      # shape.gradient (grad phi), likewise
    moving: object        # the terrain's shape if its surface moves, or None
    x: np.ndarray         # (P, 3) the positions before lifting


def impacts(physical, x, v):
    """(x, v, [Impact or None per terrain]) after resolve_terrain_impacts."""
    planes = physical.planes
    found = [None] * len(planes.epsilon)
    for t, shape in followed(planes):
        n = shape.normals(x)
        phi = shape.distance(x, planes.offset)
        u = surface_velocity(shape, x)
        relative = v if u is None else v - u
        v_n = along(relative, n)
        band = physical.free & (phi < planes.epsilon[t])
        bounced = np.nonzero(band & (v_n < 0.0))[0]
        lifted = np.nonzero(band & (phi < 0.0))[0]
        if not len(bounced) and not len(lifted):
            continue
        vb = v_n[bounced]
        fast = -vb > planes.resting_speed[t]
        e = np.where(fast, physical.restitution[t], 0.0)
        bounce = (1.0 + e) * vb
        before = relative[bounced]
        v = v.copy()
        v[bounced] -= bounce[:, None] * n[bounced]
        if len(lifted):
            x_before, x = x, x.copy()
            x[lifted] -= phi[lifted, None] * n[lifted]
        else:
            x_before = x
        found[t] = Impact(bounced, fast, vb, lifted, before, n, phi,
                          lambda rows, s=shape, at=x_before: s.curvature(at[rows]),
                          lambda rows, s=shape, at=x_before: s.gradient(at[rows]),
                          shape if u is not None else None, x_before)
    return x, v, found


def impacts_vjp(physical, found, x_bar, v_bar, bar):
    """The cotangents of (x, v) before the impact pass, given those after (in place). Lifted:
    x - phi n, whose derivative is I - n (grad phi)^T - phi dn/dx. Bounced:
    v - (1 + e) v_n n, whose normal's cotangent -(1 + e) ((g . n) v + v_n g) goes to x through
    dn/dx."""
    for t in reversed(range(len(found))):
        impact = found[t]
        if impact is None:
            continue
        n_bar = np.zeros((len(impact.bounced), 3))
        rows = impact.bounced
        if len(rows):
            n = impact.n[rows]
            gn = along(v_bar[rows], n)
            e = np.where(impact.fast, physical.restitution[t], 0.0)
            bar.restitution[t] -= float(np.sum(np.where(impact.fast, impact.v_n * gn, 0.0)))
            n_bar = -(1.0 + e)[:, None] * (gn[:, None] * impact.v + impact.v_n[:, None]
                                           * v_bar[rows])
            v_bar[rows] -= ((1.0 + e) * gn)[:, None] * n
            u_bar = ((1.0 + e) * gn)[:, None] * n   # v_n = (v - u(x)) . n on a moving one
        lifted = impact.lifted
        if len(lifted):
            n = impact.n[lifted]
            g = x_bar[lifted]
            inward = g - along(g, n)[:, None] * impact.gradient(lifted)
            curvature = impact.curvature(lifted)
            if curvature is not None:
                inward -= impact.phi[lifted, None] * np.einsum("kij,kj->ki", curvature, g)
            x_bar[lifted] = inward
        if len(rows):
            add_curvature(rows, impact.curvature(rows), n_bar, x_bar)
            if impact.moving is not None:
                np.add.at(x_bar, rows, impact.moving.velocity_vjp(impact.x[rows], u_bar))
    return x_bar, v_bar
