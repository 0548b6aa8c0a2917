"""Wind: air that moves, and the force it puts on every surface triangle and every ball.

A scene's ``[wind]`` table gives the air's ``velocity`` (m/s: a constant vector, or ``keyframes``
of ``{time, velocity}`` interpolated linearly and held outside them), its ``density`` rho
(kg/m^3), a ``drag`` coefficient C_d for the air's motion normal to a surface and a ``friction``
coefficient C_f along it, and optional ``gusts``: a seeded, deterministic turbulence field of a
given ``strength`` (a share of the mean wind speed) and ``length`` (m), a sum of GUST_MODES
travelling waves with random directions, wave numbers and phases drawn once from ``seed``. The
air is a function of place and time alone, so runs are deterministic and resume exactly.

On a triangle of area A and unit normal n, with w the air's velocity relative to the triangle
(the mean wind plus the mean of the gusts at its corners, minus the mean of its corners'
velocities):

    F = 1/2 rho C_d A |w_n| w_n n  +  1/2 rho C_f A |w_t| w_t,   w_n = w . n,  w_t = w - w_n n

shared equally among its three corners (a quad counts as both its triangulations at half
weight: ``quads_both_ways``), so that a flat sheet whose mass is spread by area falls flat and
reaches the flat-plate terminal speed sqrt(2 m g / (rho C_d A)). A ball feels
1/2 rho C_d pi r^2 |w| w.

Backward Euler takes the force at the step's end with its derivative in the corners' own
velocities, the diagonal blocks h (1/9) (rho C_d A |w_n| n n^T + rho C_f A |w_t| (I - n n^T))
per corner (a ball's h rho C_d pi r^2 |w| / 2 (I + w w^T/|w|^2)); the couplings between a
triangle's corners and the change of the normal with the positions are left out of the matrix
(they are in the force), which keeps it symmetric positive definite.
"""
import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .clock import WORLD_TIME
from ._jit import inline_kernel, kernel
from .errors import SceneError, is_finite, require

GUST_MODES = 8
# wind_settings: density, drag, friction, gust strength, gust length, and whether there is wind
DENSITY, DRAG, FRICTION, STRENGTH, LENGTH, ON = range(6)


@dataclass
class WindKey:
    """The air's velocity (m/s) at ``time`` (s)."""

    time: float
    velocity: tuple = (0.0, 0.0, 0.0)


@dataclass
class Gusts:
    """Turbulence: ``strength`` (a share of the mean wind speed, or m/s in still air), ``length``
    (m, the size of a gust) and the ``seed`` of its random field."""

    strength: float = 0.0
    length: float = 1.0
    seed: int = 0


@dataclass
class Wind:
    """Air that moves (module doc)."""

    velocity: tuple = (0.0, 0.0, 0.0)
    keyframes: list[WindKey] = field(default_factory=list)
    density: float = 1.2
    drag: float = 1.0
    friction: float = 0.0
    gusts: Gusts | None = None

    def validate(self, key: str) -> None:
        require(np.shape(self.velocity) == (3,) and is_finite(self.velocity), f"{key}.velocity",
                self.velocity, "must be three finite numbers (m/s)")
        require(is_finite(self.density) and self.density >= 0, f"{key}.density", self.density,
                "must be >= 0 kg/m^3")
        for name in ("drag", "friction"):
            value = getattr(self, name)
            require(is_finite(value) and value >= 0, f"{key}.{name}", value, "must be >= 0")
        if self.keyframes and any(self.velocity):
            raise SceneError(f"{key}.velocity", self.velocity,
                             "the wind is a constant velocity or keyframes, not both")
        previous = -math.inf
        for k, frame in enumerate(self.keyframes):
            here = f"{key}.keyframes.{k}"
            require(is_finite(frame.time) and frame.time > previous, f"{here}.time", frame.time,
                    f"keyframes must be in increasing time order, each later than the last "
                    f"({previous:g} s before it)")
            previous = frame.time
            require(np.shape(frame.velocity) == (3,) and is_finite(frame.velocity),
                    f"{here}.velocity", frame.velocity, "must be three finite numbers (m/s)")
        if self.gusts is not None:
            require(is_finite(self.gusts.strength) and self.gusts.strength >= 0,
                    f"{key}.gusts.strength", self.gusts.strength, "must be >= 0")
            require(is_finite(self.gusts.length) and self.gusts.length > 0,
                    f"{key}.gusts.length", self.gusts.length, "must be > 0 m")
            seed = self.gusts.seed   # NumPy's generators take a whole number >= 0 alone
            require(isinstance(seed, (int, np.integer)) and not isinstance(seed, bool)
                    and seed >= 0, f"{key}.gusts.seed", seed, "must be a whole number >= 0")


def quads_both_ways(triangles: np.ndarray):
    """(triangles, weights): each quad that a fan split into (a, b, c) and (a, c, d) split both
    ways, its four triangles at weight 1/2, so that each corner takes a quarter of its force (a
    fan alone gives the corners on its diagonal twice the others' share, and folds a falling
    sheet along it); other triangles at weight 1."""
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    second = {(int(t[0]), int(t[1])): k for k, t in enumerate(triangles)}   # (a, c) of (a, c, d)
    out, weights, used = [], [], np.zeros(len(triangles), bool)
    for k, (a, b, c) in enumerate(triangles):
        j = second.get((int(a), int(c)), -1)
        if used[k] or j < 0 or j == k or used[j]:
            continue
        d = triangles[j, 2]
        out += [(a, b, c), (a, c, d), (a, b, d), (b, c, d)]
        weights += [0.5] * 4
        used[k] = used[j] = True
    for k in np.flatnonzero(~used):
        out.append(tuple(triangles[k]))
        weights.append(1.0)
    return np.array(out, np.int64).reshape(-1, 3), np.array(weights, float)


def pack_wind(wind: Wind | None) -> dict:
    """The model's wind arrays: settings, velocity keys (time, velocity) and gust modes
    (direction, wave vector, angular frequency and phase)."""
    settings = np.zeros(6)
    keys = np.zeros((1, 4))
    modes = np.zeros((0, 8))
    if wind is not None:
        gusts = wind.gusts or Gusts()
        settings[:] = [wind.density, wind.drag, wind.friction, gusts.strength, gusts.length, 1.0]
        if wind.keyframes:
            keys = np.array([[k.time, *k.velocity] for k in wind.keyframes], float)
        else:
            keys = np.array([[0.0, *wind.velocity]], float)
        if gusts.strength > 0:
            random = np.random.default_rng(gusts.seed)
            direction = random.normal(size=(GUST_MODES, 3))
            direction /= np.linalg.norm(direction, axis=1, keepdims=True)
            along = random.normal(size=(GUST_MODES, 3))
            along /= np.linalg.norm(along, axis=1, keepdims=True)
            waves = along * (2 * np.pi / gusts.length) * random.uniform(0.5, 1.5, (GUST_MODES, 1))
            # each wave drifts past at about a gust length per second
            frequency = 2 * np.pi / gusts.length * random.uniform(0.5, 1.5, (GUST_MODES, 1))
            phase = random.uniform(0, 2 * np.pi, (GUST_MODES, 1))
            modes = np.hstack([direction, waves, frequency, phase])
    return {"wind_settings": settings, "wind_keys": keys, "wind_modes": modes}


class Air(NamedTuple):
    """The air at one time, taken once per kernel call for its loops over triangles: scalars
    only, since an array read from a tuple or the model inside such a loop has its reference
    counted at every triangle (six times the triangle's own force)."""

    u0: float       # the keyed mean wind's velocity (m/s)
    u1: float
    u2: float
    gust: float     # each gust mode's amplitude (m/s)
    normal: float   # 1/2 rho C_d
    along: float    # 1/2 rho C_f


@inline_kernel
def air_at(model, t):
    """The air at time t: the keyed mean wind, interpolated linearly and held outside the keys,
    and the gusts' amplitude, a share of its speed."""
    keys = model.wind_keys
    last = keys.shape[0] - 1
    if t <= keys[0, 0] or last == 0:
        a0, a1, a2 = keys[0, 1], keys[0, 2], keys[0, 3]
    elif t >= keys[last, 0]:
        a0, a1, a2 = keys[last, 1], keys[last, 2], keys[last, 3]
    else:
        k = 0
        while keys[k + 1, 0] <= t:
            k += 1
        s = (t - keys[k, 0]) / (keys[k + 1, 0] - keys[k, 0])
        a0 = keys[k, 1] + s * (keys[k + 1, 1] - keys[k, 1])
        a1 = keys[k, 2] + s * (keys[k + 1, 2] - keys[k, 2])
        a2 = keys[k, 3] + s * (keys[k + 1, 3] - keys[k, 3])
    settings = model.wind_settings
    gust = 0.0
    if model.wind_modes.shape[0] > 0:
        speed = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        gust = settings[STRENGTH] * (speed if speed > 0.0 else 1.0)
        gust /= math.sqrt(model.wind_modes.shape[0] / 2.0)   # the modes' sum has about this spread
    rho = settings[DENSITY]
    return Air(a0, a1, a2, gust, 0.5 * rho * settings[DRAG], 0.5 * rho * settings[FRICTION])


# sine(): Cody-Waite reduction by pi/2 in three parts, and fdlibm's minimax polynomials for
# sin and cos on [-pi/4, pi/4]
TWO_OVER_PI = 0.636619772367581343076
PI_OVER_2 = (1.57079632673412561417e+00, 6.07710050630396597660e-11, 2.02226624871116645580e-21)
SINE = (-1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04,
        2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10)
COSINE = (4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05,
          -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11)


@inline_kernel
def sine(angle):
    """sin(angle) within an ulp or two, with no call to the C library, so that a loop of it
    compiles to SIMD code (math.sin is a call per element, several times slower, and the gusts'
    sines were much of the wind's cost). The reduction is exact for |angle| < 2^20 pi/2, 1.6e6 rad:
    a gust wave of 1 m reaches that after about two days of simulated time."""
    k = math.floor(angle * TWO_OVER_PI + 0.5)
    r = ((angle - k * PI_OVER_2[0]) - k * PI_OVER_2[1]) - k * PI_OVER_2[2]
    z = r * r
    s = r + r * z * (SINE[0] + z * (SINE[1] + z * (SINE[2] + z * (SINE[3] + z * (
        SINE[4] + z * SINE[5])))))
    c = 1.0 - 0.5 * z + z * z * (COSINE[0] + z * (COSINE[1] + z * (COSINE[2] + z * (
        COSINE[3] + z * (COSINE[4] + z * COSINE[5])))))
    quadrant = np.int64(k) & 3
    value = c if quadrant & 1 else s
    return -value if quadrant & 2 else value


@inline_kernel
def wave_angle(modes, g, x0, x1, x2, t):
    """The phase of gust mode g at a point and time."""
    return modes[g, 3] * x0 + modes[g, 4] * x1 + modes[g, 5] * x2 - modes[g, 6] * t + modes[g, 7]


@inline_kernel
def gust_velocity(air, modes, x0, x1, x2, t):
    """The gusts' velocity (m/s) at a point: the sum of the travelling waves ``modes``
    (model.wind_modes, read once by the caller)."""
    a0 = a1 = a2 = 0.0
    for g in range(modes.shape[0]):
        wave = sine(wave_angle(modes, g, x0, x1, x2, t))
        a0 += air.gust * wave * modes[g, 0]
        a1 += air.gust * wave * modes[g, 1]
        a2 += air.gust * wave * modes[g, 2]
    return a0, a1, a2


@inline_kernel
def corner_gusts(air, modes, x, triangles, t):
    """The gusts at every corner of the wind triangles, each particle's once (a cloth has a
    quarter as many particles as wind triangles), mode by mode so that the sines run as one
    SIMD loop; no rows without gusts. The same sums, in the same order, as gust_velocity."""
    gusts = np.zeros((x.shape[0] if modes.shape[0] > 0 else 0, 3))
    if modes.shape[0] == 0:
        return gusts
    seen = np.zeros(x.shape[0], np.bool_)
    corners = np.empty(x.shape[0], np.int64)
    count = 0
    for k in range(triangles.shape[0]):
        for j in range(3):
            i = triangles[k, j]
            if not seen[i]:
                seen[i] = True
                corners[count] = i
                count += 1
    # the corners' positions and gusts in contiguous arrays, so that each mode's loop is SIMD
    px, py, pz = np.empty(count), np.empty(count), np.empty(count)
    for j in range(count):
        px[j], py[j], pz[j] = x[corners[j], 0], x[corners[j], 1], x[corners[j], 2]
    gx, gy, gz = np.zeros(count), np.zeros(count), np.zeros(count)
    for g in range(modes.shape[0]):
        k0, k1, k2, frequency, phase = (modes[g, 3], modes[g, 4], modes[g, 5], modes[g, 6],
                                        modes[g, 7])
        d0, d1, d2, size = modes[g, 0], modes[g, 1], modes[g, 2], air.gust
        for j in range(count):   # wave_angle and gust_velocity's sums, written out
            wave = sine(k0 * px[j] + k1 * py[j] + k2 * pz[j] - frequency * t + phase)
            gx[j] += size * wave * d0
            gy[j] += size * wave * d1
            gz[j] += size * wave * d2
    for j in range(count):
        gusts[corners[j], 0], gusts[corners[j], 1], gusts[corners[j], 2] = gx[j], gy[j], gz[j]
    return gusts


@inline_kernel
def triangle_wind(air, gusts, gusted, x, v, a, b, c):
    """The wind force (N) on triangle (a, b, c), and the coefficients of its corners'
    diagonal derivative, rho C_d A |w_n| / 9 (along n) and rho C_f A |w_t| / 9 (across), with n.
    ``gusts``: corner_gusts, read if ``gusted``. A triangle of no area has no normal and no
    force."""
    e0, e1, e2 = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
    f0, f1, f2 = x[c, 0] - x[a, 0], x[c, 1] - x[a, 1], x[c, 2] - x[a, 2]
    n0, n1, n2 = e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0
    twice_area = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    inverse = 1.0 / twice_area if twice_area > 0.0 else 0.0
    n0, n1, n2 = n0 * inverse, n1 * inverse, n2 * inverse
    area = 0.5 * twice_area
    third = 1.0 / 3.0
    air0, air1, air2 = air.u0, air.u1, air.u2
    if gusted:
        air0 += (gusts[a, 0] + gusts[b, 0] + gusts[c, 0]) * third
        air1 += (gusts[a, 1] + gusts[b, 1] + gusts[c, 1]) * third
        air2 += (gusts[a, 2] + gusts[b, 2] + gusts[c, 2]) * third
    w0 = air0 - (v[a, 0] + v[b, 0] + v[c, 0]) * third
    w1 = air1 - (v[a, 1] + v[b, 1] + v[c, 1]) * third
    w2 = air2 - (v[a, 2] + v[b, 2] + v[c, 2]) * third
    w_n = w0 * n0 + w1 * n1 + w2 * n2
    t0, t1, t2 = w0 - w_n * n0, w1 - w_n * n1, w2 - w_n * n2
    w_t = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
    normal = air.normal * area * abs(w_n)
    along = air.along * area * w_t
    two_ninths = 2.0 / 9.0
    return (normal * w_n * n0 + along * t0, normal * w_n * n1 + along * t1,
            normal * w_n * n2 + along * t2, two_ninths * normal, two_ninths * along, n0, n1, n2)


@inline_kernel
def ball_wind(air, modes, r, x, v, i, t):
    """Ball i's (radius r) relative air velocity w and 1/2 rho C_d pi r^2 |w| (its force is that
    times w)."""
    g0, g1, g2 = gust_velocity(air, modes, x[i, 0], x[i, 1], x[i, 2], t)
    w0, w1, w2 = air.u0 + g0 - v[i, 0], air.u1 + g1 - v[i, 1], air.u2 + g2 - v[i, 2]
    size = air.normal * math.pi * r * r * math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    return w0, w1, w2, size


@inline_kernel
def wind_pass(model, x, v, scale, out, jacobian, diagonal_slot, h, blocks):
    """out[i] += scale_i F_i: every wind triangle's force shared among its corners, and every
    ball's; ``scale`` per particle (inverse masses: accelerations) or one entry for all (h:
    backward Euler's impulses). With ``jacobian`` (a constant of the caller), each corner's
    -h dF_i/dv_i (module doc) is added to its diagonal block in the same pass, since the gusts'
    sines and each triangle's normal are most of the cost. The time is the world's
    (world.move_world)."""
    if model.wind_settings[ON] == 0.0:
        return
    t = model.clock[WORLD_TIME]
    air, modes = air_at(model, t), model.wind_modes
    gusts = corner_gusts(air, modes, x, model.wind_triangles, t)
    # whether there are gusts is asked once, not at every triangle: asked there, it kept the
    # loop from being compiled as well, and the loop ran much more slowly
    if gusts.shape[0] > 0:
        add_triangle_winds(model, air, gusts, True, x, v, scale, out, jacobian, diagonal_slot, h,
                           blocks)
    else:
        add_triangle_winds(model, air, gusts, False, x, v, scale, out, jacobian, diagonal_slot,
                           h, blocks)
    radius = model.radius
    for i in model.balls:
        w0, w1, w2, size = ball_wind(air, modes, radius[i], x, v, i, t)
        s = scale[i] if scale.shape[0] > 1 else scale[0]
        out[i, 0] += s * size * w0
        out[i, 1] += s * size * w1
        out[i, 2] += s * size * w2
        if jacobian:
            add_ball_derivative(blocks, diagonal_slot[i], h, size, w0, w1, w2)


@inline_kernel
def add_triangle_winds(model, air, gusts, gusted, x, v, scale, out, jacobian, diagonal_slot, h,
                       blocks):
    """wind_pass's loop over the wind triangles."""
    triangles, weights = model.wind_triangles, model.wind_weights
    for k in range(triangles.shape[0]):
        a, b, c = triangles[k, 0], triangles[k, 1], triangles[k, 2]
        f0, f1, f2, normal, along, n0, n1, n2 = triangle_wind(air, gusts, gusted, x, v, a, b, c)
        share = weights[k] / 3.0
        for i in (a, b, c):
            w = (scale[i] if scale.shape[0] > 1 else scale[0]) * share
            out[i, 0] += w * f0
            out[i, 1] += w * f1
            out[i, 2] += w * f2
        if jacobian:
            normal, along = h * normal * weights[k], h * along * weights[k]
            d00, d11, d22 = (normal * n0 * n0 + along * (1.0 - n0 * n0),
                             normal * n1 * n1 + along * (1.0 - n1 * n1),
                             normal * n2 * n2 + along * (1.0 - n2 * n2))
            d01, d02, d12 = ((normal - along) * n0 * n1, (normal - along) * n0 * n2,
                             (normal - along) * n1 * n2)
            for i in (a, b, c):
                add_symmetric(blocks, diagonal_slot[i], d00, d01, d02, d11, d12, d22)


@inline_kernel
def add_symmetric(blocks, slot, d00, d01, d02, d11, d12, d22):
    """blocks[slot] += the symmetric 3x3 matrix of these entries."""
    blocks[slot, 0, 0] += d00
    blocks[slot, 0, 1] += d01
    blocks[slot, 0, 2] += d02
    blocks[slot, 1, 0] += d01
    blocks[slot, 1, 1] += d11
    blocks[slot, 1, 2] += d12
    blocks[slot, 2, 0] += d02
    blocks[slot, 2, 1] += d12
    blocks[slot, 2, 2] += d22


@inline_kernel
def add_ball_derivative(blocks, slot, h, size, w0, w1, w2):
    """A ball's h size (I + w w^T / |w|^2) added to its block (none in still air)."""
    speed_squared = w0 * w0 + w1 * w1 + w2 * w2
    if speed_squared == 0.0:
        return
    scale, inverse = h * size, 1.0 / speed_squared
    add_symmetric(blocks, slot, scale * (1.0 + w0 * w0 * inverse), scale * w0 * w1 * inverse,
                  scale * w0 * w2 * inverse, scale * (1.0 + w1 * w1 * inverse),
                  scale * w1 * w2 * inverse, scale * (1.0 + w2 * w2 * inverse))


@kernel
def add_wind_forces(model, x, v, scale, out):
    """out[i] += scale_i F_i, the wind's force alone (wind_pass)."""
    wind_pass(model, x, v, scale, out, False, np.empty(0, np.int64), 0.0, np.empty((0, 3, 3)))


@kernel
def add_wind_with_jacobian(model, diagonal_slot, x, v, h, out, blocks):
    """Backward Euler: out += h F(x, v) and each corner's -h dF_i/dv_i into its diagonal block,
    in one pass (wind_pass)."""
    wind_pass(model, x, v, np.full(1, h), out, True, diagonal_slot, h, blocks)
