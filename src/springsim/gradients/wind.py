"""The wind (wind.py) as differentiable NumPy: its force on the surface triangles, backward
Euler's diagonal blocks of its derivative, and their vector-Jacobian products.

Each triangle's terms are differentiated in its corners' positions and its relative air velocity
w by complex steps: f(z + i eps e_j) carries df/dz_j in its imaginary part to rounding, with no
difference taken, so the result is as exact as a derivative written out by hand, for the
terms as they stand (|w_n| is written w_n sign(Re w_n) to keep them analytic; where w_n or
w_t is zero the force has a kink, and the derivative is the one of the side the run is on). The
chains around them are written out: w = mean wind + mean of the corners' gusts - mean of the
corners' velocities; the gusts, sums of sines of the positions and the gust modes; the air
(mean wind, gust amplitude, 1/2 rho C_d, 1/2 rho C_f) as a function of the wind's keys and
settings, by complex steps again.

Balls feel the wind as spheres, 1/2 rho C_d pi r^2 |w| w with w the air's velocity relative to
the ball's; their derivatives are written out (``ball_winds``). The wind's time is the force
evaluation's (clock.py).
"""
from typing import NamedTuple

import numpy as np

from ..wind import DENSITY, DRAG, FRICTION, ON, STRENGTH
from .clock import FORCE_TIME
from ..terms.adjoint import AdjointTerm

STEP = 1e-30        # the complex step: far below rounding, so f(z + i STEP) has no error in f
TWO_NINTHS = 2.0 / 9.0


def blows(physical) -> bool:
    return bool(physical.wind_settings[ON])


# --- the air ------------------------------------------------------------------------------------

def air_vector(settings, keys, mode_count, t):
    """wind.air_at as an array (u0, u1, u2, gust amplitude, 1/2 rho C_d, 1/2 rho C_f), written
    for complex inputs (the branches taken on the real parts)."""
    times = keys[:, 0].real
    last = len(keys) - 1
    if t <= times[0] or last == 0:
        u = keys[0, 1:]
    elif t >= times[last]:
        u = keys[last, 1:]
    else:
        k = int(np.searchsorted(times, t, side="right")) - 1
        s = (t - keys[k, 0]) / (keys[k + 1, 0] - keys[k, 0])
        u = keys[k, 1:] + s * (keys[k + 1, 1:] - keys[k, 1:])
    gust = 0.0 * settings[STRENGTH]
    if mode_count > 0:
        speed = np.sqrt(np.sum(u * u))
        gust = settings[STRENGTH] * (speed if speed.real > 0.0 else 1.0)
        gust = gust / np.sqrt(mode_count / 2.0)
    rho = settings[DENSITY]
    return np.array([u[0], u[1], u[2], gust, 0.5 * rho * settings[DRAG],
                     0.5 * rho * settings[FRICTION]])


class Air(NamedTuple):
    value: np.ndarray      # (6,) air_vector
    settings: np.ndarray   # (6, 6) d value / d wind_settings
    keys: np.ndarray       # (6, K, 4) d value / d wind_keys


def air(physical, t) -> Air:
    """The air at time t with its derivatives in the wind's settings and keys."""
    settings, keys = physical.wind_settings, physical.wind_keys
    modes = len(physical.wind_modes)
    d_settings = np.empty((6, settings.size))
    for j in range(settings.size):
        z = settings.astype(complex)
        z[j] += 1j * STEP
        d_settings[:, j] = air_vector(z, keys, modes, t).imag / STEP
    d_keys = np.empty((6,) + keys.shape)
    for index in np.ndindex(keys.shape):
        z = keys.astype(complex)
        z[index] += 1j * STEP
        d_keys[(slice(None),) + index] = air_vector(settings, z, modes, t).imag / STEP
    return Air(air_vector(settings, keys, modes, t).real, d_settings, d_keys)


def add_air_bar(physical, air_now: Air, air_bar, bar) -> None:
    bar.wind_settings += air_now.settings.T @ air_bar
    bar.wind_keys += np.einsum("a,akc->kc", air_bar, air_now.keys)


# --- gusts --------------------------------------------------------------------------------------

def gust_waves(physical, x, t):
    """(angles (P, M), sines): each gust mode's phase at every particle (wind.wave_angle)."""
    modes = physical.wind_modes
    angles = x @ modes[:, 3:6].T - modes[:, 6] * t + modes[:, 7]
    return angles, np.sin(angles)


def corner_gusts(physical, x, amplitude, t):
    """The gusts' velocity at every particle (wind.gust_velocity), (P, 3)."""
    if not len(physical.wind_modes):
        return np.zeros_like(x)
    _, sines = gust_waves(physical, x, t)
    return amplitude * sines @ physical.wind_modes[:, 0:3]


def gusts_vjp(physical, x, amplitude, t, gust_bar, x_bar, bar):
    """Add gust_bar . d(corner_gusts)/d(x, modes) to x_bar and bar; returns that of the
    amplitude."""
    modes = physical.wind_modes
    if not len(modes):
        return 0.0
    angles, sines = gust_waves(physical, x, t)
    along = gust_bar @ modes[:, 0:3].T                    # (P, M): d_g . gust_bar_i
    angle_bar = amplitude * np.cos(angles) * along
    x_bar += angle_bar @ modes[:, 3:6]
    modes_bar = bar.wind_modes
    modes_bar[:, 0:3] += amplitude * sines.T @ gust_bar
    modes_bar[:, 3:6] += angle_bar.T @ x
    modes_bar[:, 6] -= t * angle_bar.sum(axis=0)
    modes_bar[:, 7] += angle_bar.sum(axis=0)
    return float(np.sum(sines * along))


# --- triangles ----------------------------------------------------------------------------------

class Terms(NamedTuple):
    """A triangle's wind terms (wind.triangle_wind): unit normal, w . n, the tangential part
    of w, and A |w_n|, A |w_t| (the force's normal and tangential sizes over 1/2 rho C)."""

    normal: np.ndarray
    w_n: np.ndarray
    tangential: np.ndarray
    normal_size: np.ndarray
    along_size: np.ndarray


def cross(e, f):
    return np.stack([e[:, 1] * f[:, 2] - e[:, 2] * f[:, 1], e[:, 2] * f[:, 0] - e[:, 0] * f[:, 2],
                     e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0]], axis=1)


def terms(corners, w) -> Terms:
    """Terms of triangles with corners (T, 3, 3) and relative air w (T, 3), real or complex;
    a triangle of no area has no normal and no force (the kernel's rule)."""
    n = cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    twice_area = np.sqrt(np.sum(n * n, axis=1))
    real = twice_area.real > 0.0
    inverse = np.where(real, 1.0 / np.where(real, twice_area, 1.0), 0.0)
    n = n * inverse[:, None]
    area = 0.5 * twice_area
    w_n = np.sum(w * n, axis=1)
    t = w - w_n[:, None] * n
    w_t = np.sqrt(np.sum(t * t, axis=1))
    return Terms(n, w_n, t, area * w_n * np.sign(w_n.real), area * w_t)


def triangle_force(found: Terms, coefficients):
    """Each triangle's force (T, 3): 1/2 rho C_d A |w_n| w_n n + 1/2 rho C_f A |w_t| w_t."""
    normal, along = coefficients
    return ((normal * found.normal_size * found.w_n)[:, None] * found.normal
            + (along * found.along_size)[:, None] * found.tangential)


def block_contraction(found: Terms, coefficients, q):
    """D : Q per triangle, D = 2/9 (1/2 rho C_d A |w_n| n n^T + 1/2 rho C_f A |w_t| (I - n n^T))
    (wind.add_triangle_winds' block before its factor h w_k), Q (T, 3, 3)."""
    normal, along = coefficients
    n = found.normal
    nqn = np.einsum("ki,kij,kj->k", n, q, n)
    trace = np.einsum("kii->k", q)
    return TWO_NINTHS * (normal * found.normal_size * nqn
                         + along * found.along_size * (trace - nqn))


def complex_gradient(function, corners, w):
    """The gradients of sum_k function(corners, w)_k in corners (T, 3, 3) and w (T, 3), each
    triangle's own (function's value per triangle depends on that triangle's inputs only)."""
    corners_bar, w_bar = np.empty(corners.shape), np.empty(w.shape)
    z_corners, z_w = corners.astype(complex), w.astype(complex)
    for j in range(3):
        for c in range(3):
            z_corners[:, j, c] += 1j * STEP
            corners_bar[:, j, c] = function(z_corners, z_w).imag / STEP
            z_corners[:, j, c] = corners[:, j, c]
    for c in range(3):
        z_w[:, c] += 1j * STEP
        w_bar[:, c] = function(corners, z_w).imag / STEP
        z_w[:, c] = w[:, c]
    return corners_bar, w_bar


class Triangles(NamedTuple):
    """The wind triangles at some (x, v, t): their corners, relative air and terms."""

    corners: np.ndarray
    w: np.ndarray
    found: Terms
    air: Air
    gusts: np.ndarray


def triangles_at(physical, x, v, t) -> Triangles:
    triangles = physical.wind_triangles
    air_now = air(physical, t)
    gusts = corner_gusts(physical, x, air_now.value[3], t)
    third = 1.0 / 3.0
    w = (air_now.value[:3] + (gusts[triangles[:, 0]] + gusts[triangles[:, 1]]
                              + gusts[triangles[:, 2]]) * third
         - (v[triangles[:, 0]] + v[triangles[:, 1]] + v[triangles[:, 2]]) * third)
    corners = x[triangles]
    return Triangles(corners, w, terms(corners, w), air_now, gusts)


def chain_back(physical, x, t, at: Triangles, corners_bar, w_bar, coefficients_bar, x_bar,
               v_bar, bar) -> None:
    """From the cotangents of the triangles' corners, relative air and the two coefficients
    to x_bar, v_bar and the wind's parameters."""
    triangles = physical.wind_triangles
    gust_bar = np.zeros_like(x)
    for j in range(3):
        np.add.at(x_bar, triangles[:, j], corners_bar[:, j])
        np.add.at(v_bar, triangles[:, j], -w_bar / 3.0)
        np.add.at(gust_bar, triangles[:, j], w_bar / 3.0)
    amplitude_bar = gusts_vjp(physical, x, at.air.value[3], t, gust_bar, x_bar, bar)
    air_bar = np.concatenate([w_bar.sum(axis=0), [amplitude_bar], coefficients_bar])
    add_air_bar(physical, at.air, air_bar, bar)


# --- balls --------------------------------------------------------------------------------------

class BallWinds(NamedTuple):
    """The balls' relative air velocities (wind.ball_wind) and what their forces are made of."""

    balls: np.ndarray   # (N,) the balls' particles
    w: np.ndarray       # (N, 3) m/s: the air's velocity relative to each ball
    speed: np.ndarray   # (N,) |w|
    area: np.ndarray    # (N,) pi r^2
    air: Air


def ball_winds(physical, v, air_there: Triangles) -> BallWinds:
    """The balls' winds from the air and the gusts at every particle that ``triangles_at``
    found for the same evaluation."""
    balls = physical.bodies.balls
    w = air_there.air.value[:3] + air_there.gusts[balls] - v[balls]
    return BallWinds(balls, w, np.sqrt(np.sum(w * w, axis=1)),
                     np.pi * physical.bodies.radius[balls] ** 2, air_there.air)


def ball_chain_back(physical, x, t, at: BallWinds, w_bar, drag_bar, x_bar, v_bar, bar) -> None:
    """From the cotangents of the balls' relative air and of 1/2 rho C_d to x_bar, v_bar and the
    wind's parameters (the gusts at the balls' positions)."""
    v_bar[at.balls] -= w_bar
    balls_bar = np.zeros((len(at.balls), 3))
    amplitude_bar = gusts_vjp(physical, x[at.balls], at.air.value[3], t, w_bar, balls_bar, bar)
    x_bar[at.balls] += balls_bar
    add_air_bar(physical, at.air, np.concatenate([w_bar.sum(axis=0), [amplitude_bar],
                                                  [drag_bar, 0.0]]), bar)


def unit(at: BallWinds):
    """w / |w| per ball, zero in still air (where the force and its derivatives vanish)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(at.speed[:, None] > 0.0, at.w / at.speed[:, None], 0.0)


def ball_forces_vjp(physical, x, v, air_there, g, x_bar, v_bar, bar) -> None:
    """g . d(F_balls)/d(everything): dF/dw = c A (|w| I + w w^T / |w|)."""
    t = physical.clock[FORCE_TIME]
    at = ball_winds(physical, v, air_there)
    c, g_b, u = at.air.value[4], g[at.balls], unit(at)
    along = np.sum(g_b * at.w, axis=1)
    w_bar = (c * at.area)[:, None] * (at.speed[:, None] * g_b + along[:, None] * u)
    drag_bar = float(np.sum(at.area * at.speed * along))
    ball_chain_back(physical, x, t, at, w_bar, drag_bar, x_bar, v_bar, bar)


def ball_blocks_vjp(physical, x, v, air_there, h, weights, x_bar, v_bar, bar) -> None:
    """d(sum_i W_i : B_i)/d(everything), B_i = h c A (|w| I + w w^T / |w|) (wind.py's
    add_ball_derivative)."""
    t = physical.clock[FORCE_TIME]
    at = ball_winds(physical, v, air_there)
    c, u, q = at.air.value[4], unit(at), weights[at.balls]
    trace = np.einsum("kii->k", q)
    uqu = np.einsum("ki,kij,kj->k", u, q, u)
    symmetric = np.einsum("kij,kj->ki", q + np.transpose(q, (0, 2, 1)), u)
    w_bar = (h * c * at.area)[:, None] * (trace[:, None] * u + symmetric - uqu[:, None] * u)
    drag_bar = float(np.sum(h * at.area * at.speed * (trace + uqu)))
    ball_chain_back(physical, x, t, at, w_bar, drag_bar, x_bar, v_bar, bar)


# --- what the adjoints call ---------------------------------------------------------------------

def wind_forces(physical, x, v):
    """Every particle's wind force (N), (P, 3): each triangle's shared among its corners by
    weight / 3 (wind.add_triangle_winds), and each ball's, at the wind's time."""
    out = np.zeros_like(x)
    if not blows(physical):
        return out
    at = triangles_at(physical, x, v, physical.clock[FORCE_TIME])
    force = triangle_force(at.found, at.air.value[4:6])
    share = (physical.wind_weights / 3.0)[:, None] * force
    for j in range(3):
        np.add.at(out, physical.wind_triangles[:, j], share)
    if len(physical.bodies.balls):
        balls = ball_winds(physical, v, at)
        out[balls.balls] += (balls.air.value[4] * balls.area * balls.speed)[:, None] * balls.w
    return out


def wind_forces_vjp(physical, x, v, g, x_bar, v_bar, bar) -> None:
    """Add g . d(wind_forces)/d(x, v, the wind's parameters) (g (P, 3))."""
    if not blows(physical):
        return
    t = physical.clock[FORCE_TIME]
    at = triangles_at(physical, x, v, t)
    triangles = physical.wind_triangles
    g_k = (physical.wind_weights / 3.0)[:, None] * (g[triangles[:, 0]] + g[triangles[:, 1]]
                                                     + g[triangles[:, 2]])
    coefficients = at.air.value[4:6]

    def contracted(corners, w):
        return np.sum(g_k * triangle_force(terms(corners, w), coefficients), axis=1)

    corners_bar, w_bar = complex_gradient(contracted, at.corners, at.w)
    found = at.found
    coefficients_bar = np.array([
        np.sum(g_k * (found.normal_size * found.w_n)[:, None] * found.normal),
        np.sum(g_k * found.along_size[:, None] * found.tangential)])
    chain_back(physical, x, t, at, corners_bar, w_bar, coefficients_bar, x_bar, v_bar, bar)
    if len(physical.bodies.balls):
        ball_forces_vjp(physical, x, v, at, g, x_bar, v_bar, bar)


def wind_blocks(physical, x, v, h):
    """Each particle's share of backward Euler's matrix from the wind (P, 3, 3), h w_k D_k
    summed over its triangles (wind.add_triangle_winds)."""
    out = np.zeros((len(x), 3, 3))
    if not blows(physical):
        return out
    at = triangles_at(physical, x, v, physical.clock[FORCE_TIME])
    found = at.found
    normal, along = at.air.value[4:6]
    n = found.normal
    outer = n[:, :, None] * n[:, None, :]
    blocks = TWO_NINTHS * ((normal * found.normal_size)[:, None, None] * outer
                           + (along * found.along_size)[:, None, None] * (np.eye(3) - outer))
    blocks *= (h * physical.wind_weights)[:, None, None]
    for j in range(3):
        np.add.at(out, physical.wind_triangles[:, j], blocks)
    if len(physical.bodies.balls):
        balls = ball_winds(physical, v, at)
        u = unit(balls)
        size = h * balls.air.value[4] * balls.area * balls.speed
        out[balls.balls] += size[:, None, None] * (np.eye(3) + u[:, :, None] * u[:, None, :])
    return out


def wind_blocks_vjp(physical, x, v, h, weights, x_bar, v_bar, bar) -> None:
    """Add d(sum_i weights_i : wind_blocks_i)/d(x, v, the wind's parameters) (weights
    (P, 3, 3), the cotangent of each particle's block)."""
    if not blows(physical) or not weights.any():
        return
    t = physical.clock[FORCE_TIME]
    at = triangles_at(physical, x, v, t)
    triangles = physical.wind_triangles
    q = (h * physical.wind_weights)[:, None, None] * (
        weights[triangles[:, 0]] + weights[triangles[:, 1]] + weights[triangles[:, 2]])
    coefficients = at.air.value[4:6]

    def contracted(corners, w):
        return block_contraction(terms(corners, w), coefficients, q)

    corners_bar, w_bar = complex_gradient(contracted, at.corners, at.w)
    found = at.found
    n = found.normal
    nqn = np.einsum("ki,kij,kj->k", n, q, n)
    trace = np.einsum("kii->k", q)
    coefficients_bar = TWO_NINTHS * np.array([np.sum(found.normal_size * nqn),
                                              np.sum(found.along_size * (trace - nqn))])
    chain_back(physical, x, t, at, corners_bar, w_bar, coefficients_bar, x_bar, v_bar, bar)
    if len(physical.bodies.balls):
        ball_blocks_vjp(physical, x, v, at, h, weights, x_bar, v_bar, bar)


class WindAdjoint(AdjointTerm):
    """The wind's derivative (terms/air.py): its blocks sit on the diagonal, and depend on v."""

    @classmethod
    def acts(cls, physical) -> bool:
        return blows(physical)

    # the functions above, whose arguments are the protocol's (terms/adjoint.py)
    forces, forces_vjp = staticmethod(wind_forces), staticmethod(wind_forces_vjp)
    diagonal_blocks = staticmethod(wind_blocks)
    diagonal_blocks_vjp = staticmethod(wind_blocks_vjp)

