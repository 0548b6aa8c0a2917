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

Planes only: a plane's normal is the same everywhere, so the contact depends on positions only
through which branch a particle takes. A curved terrain's normal turns with the position (its
curvature would enter the gradient); such a terrain touched during a run is refused
(gradients/checks.py).
"""
from typing import NamedTuple

import numpy as np


class Planes(NamedTuple):
    """The model's terrains as contact needs them: one row per terrain (non-planes have NaN
    points; checks.py refuses touching them)."""

    point: np.ndarray       # (T, 3) m
    normal: np.ndarray      # (T, 3) unit
    epsilon: np.ndarray     # (T,) m, the contact band
    offset: np.ndarray      # (P,) m, kept between a particle and a terrain
    is_plane: np.ndarray    # (T,) bool
    resting_speed: np.ndarray   # (T,) m/s, approaches slower than this do not bounce

    @classmethod
    def of(cls, model) -> "Planes":
        from ..terrains import Plane

        arrays = model.arrays
        count = len(model.terrains)
        point, normal = np.full((count, 3), np.nan), np.full((count, 3), np.nan)
        is_plane = np.zeros(count, bool)
        for t, terrain in enumerate(model.terrains):
            if isinstance(terrain, Plane):
                row = arrays.terrain_parameters[t]
                point[t], normal[t], is_plane[t] = row[0:3], row[3:6], True
        g = arrays.gravity
        g_size = np.sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2])
        epsilon = arrays.terrain_epsilon.astype(float)
        return cls(point, normal, epsilon, arrays.terrain_offset.astype(float), is_plane,
                   np.sqrt(2.0 * g_size * epsilon))


def plane_distance(planes: Planes, t: int, x: np.ndarray) -> np.ndarray:
    """phi of every particle to plane t, as plane_distance and the dispatcher compute it."""
    p, n = planes.point[t], planes.normal[t]
    return ((x[:, 0] - p[0]) * n[0] + (x[:, 1] - p[1]) * n[1] + (x[:, 2] - p[2]) * n[2]
            - planes.offset)


def along(u: np.ndarray, n: np.ndarray) -> np.ndarray:
    return u[:, 0] * n[0] + u[:, 1] * n[1] + u[:, 2] * n[2]


def far_from_planes(physical, h, start, end) -> bool:
    """Whether no stage of a step can have touched a plane: every free particle starts and ends
    it farther from each plane than the band and twice the distance its fastest particle
    covers in a step (an explicit step's stages stay within h |v| of its start, near enough).
    The adjoint then skips contact (run_kernels.rk4_step_vjp)."""
    planes = physical.planes
    if not planes.is_plane.any():
        return True
    (x, v), (x_end, v_end) = start[:2], end[:2]
    speed = max(np.sqrt(np.max(np.einsum("ij,ij->i", v, v))),
                np.sqrt(np.max(np.einsum("ij,ij->i", v_end, v_end))))
    for t in np.nonzero(planes.is_plane)[0]:
        near = np.minimum(plane_distance(planes, t, x), plane_distance(planes, t, x_end))
        if np.any(physical.free & (near < planes.epsilon[t] + 2.0 * h * speed)):
            return False
    return True


# --- the reaction and friction inside each force evaluation --------------------------------------

STICK, KINETIC, SLOWING = 0, 1, 2


class Touch(NamedTuple):
    """What one terrain did to the particles it touched in one force evaluation."""

    index: np.ndarray    # (K,) the particles
    a: np.ndarray        # (K, 3) their accelerations before it
    v: np.ndarray        # (K, 3) their velocities
    case: np.ndarray     # (K,) STICK, KINETIC or SLOWING (coulomb_friction's branches)


def contact_accelerations(physical, x, v, h, a):
    """(a after contact, [Touch or None per terrain]): apply_contact_forces."""
    planes = physical.planes
    touches = []
    for t in range(len(planes.epsilon)):
        if not planes.is_plane[t]:
            touches.append(None)
            continue
        n = planes.normal[t]
        phi = plane_distance(planes, t, x)
        a_n, v_n = along(a, n), along(v, n)
        reaction = -a_n - np.maximum(v_n, 0.0) / h
        index = np.nonzero(physical.free & (phi < planes.epsilon[t]) & (reaction > 0.0))[0]
        if not len(index):
            touches.append(None)
            continue
        ai, vi = a[index], v[index]
        new, case = touched(ai, vi, n, physical.friction[t], h)
        a = a.copy()
        a[index] = new
        touches.append(Touch(index, ai, vi, case))
    return a, touches


def touched(a, v, n, friction, h):
    """(the accelerations after contact, coulomb_friction's branch) of particles in contact."""
    a_n, v_n = along(a, n), along(v, n)
    reaction = -a_n - np.maximum(v_n, 0.0) / h
    at = np.stack([a[:, c] - a_n * n[c] for c in range(3)], axis=1)
    vt = np.stack([v[:, c] - v_n * n[c] for c in range(3)], axis=1)
    limit = friction * reaction
    s = -(at + vt / h)
    stick = np.sqrt(s[:, 0] * s[:, 0] + s[:, 1] * s[:, 1] + s[:, 2] * s[:, 2])
    speed = np.sqrt(vt[:, 0] * vt[:, 0] + vt[:, 1] * vt[:, 1] + vt[:, 2] * vt[:, 2])
    case = np.where(stick <= limit, STICK, np.where(speed > limit * h, KINETIC, SLOWING))
    f = s.copy()
    kinetic, slowing = case == KINETIC, case == SLOWING
    f[kinetic] = -limit[kinetic, None] * vt[kinetic] / speed[kinetic, None]
    f[slowing] = limit[slowing, None] * s[slowing] / stick[slowing, None]
    a_normal = a_n + reaction
    return np.stack([at[:, c] + f[:, c] + a_normal * n[c] for c in range(3)], axis=1), case


def contact_accelerations_vjp(physical, h, touches, g, v_bar, bar):
    """The cotangent of the accelerations before contact, given g on those after; adds the
    velocities' share into v_bar and friction's into bar.friction. Terrains in reverse."""
    planes = physical.planes
    g = g.copy()
    for t in reversed(range(len(touches))):
        touch = touches[t]
        if touch is None:
            continue
        a_bar, vi_bar, friction_bar = touched_vjp(touch, planes.normal[t],
                                                  physical.friction[t], h, g[touch.index])
        g[touch.index] = a_bar
        np.add.at(v_bar, touch.index, vi_bar)
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
    (``bounced``, with the restitution used, e or 0) and those it moved out (``lifted``)."""

    bounced: np.ndarray
    fast: np.ndarray      # (len(bounced),) bool: reflected with the terrain's restitution
    v_n: np.ndarray       # their approach speeds
    lifted: np.ndarray


def impacts(physical, x, v):
    """(x, v, [Impact or None per terrain]) after resolve_terrain_impacts."""
    planes = physical.planes
    found = []
    for t in range(len(planes.epsilon)):
        if not planes.is_plane[t]:
            found.append(None)
            continue
        n = planes.normal[t]
        phi = plane_distance(planes, t, x)
        v_n = along(v, n)
        band = physical.free & (phi < planes.epsilon[t])
        bounced = np.nonzero(band & (v_n < 0.0))[0]
        lifted = np.nonzero(band & (phi < 0.0))[0]
        if not len(bounced) and not len(lifted):
            found.append(None)
            continue
        vb = v_n[bounced]
        fast = -vb > planes.resting_speed[t]
        e = np.where(fast, physical.restitution[t], 0.0)
        bounce = (1.0 + e) * vb
        v = v.copy()
        for c in range(3):
            v[bounced, c] -= bounce * n[c]
        if len(lifted):
            x = x.copy()
            depth = phi[lifted]
            for c in range(3):
                x[lifted, c] -= depth * n[c]
        found.append(Impact(bounced, fast, vb, lifted))
    return x, v, found


def impacts_vjp(physical, found, x_bar, v_bar, bar):
    """The cotangents of (x, v) before the impact pass, given those after (in place)."""
    planes = physical.planes
    for t in reversed(range(len(found))):
        impact = found[t]
        if impact is None:
            continue
        n = planes.normal[t]
        if len(impact.lifted):   # x - phi n = (I - n n^T) x + const: phi = n . (x - p) - offset
            rows = impact.lifted
            x_bar[rows] -= along(x_bar[rows], n)[:, None] * n
        rows = impact.bounced
        if len(rows):   # v - (1 + e) v_n n
            gn = along(v_bar[rows], n)
            e = np.where(impact.fast, physical.restitution[t], 0.0)
            bar.restitution[t] -= float(np.sum(np.where(impact.fast, impact.v_n * gn, 0.0)))
            v_bar[rows] -= ((1.0 + e) * gn)[:, None] * n
    return x_bar, v_bar
