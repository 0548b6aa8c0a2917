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


@inline_kernel
def gust_velocity(air, modes, x0, x1, x2, t):
    """The gusts' velocity (m/s) at a point: the sum of the travelling waves ``modes``
    (model.wind_modes, read once by the caller)."""
    a0 = a1 = a2 = 0.0
    for g in range(modes.shape[0]):
        wave = math.sin(modes[g, 3] * x0 + modes[g, 4] * x1 + modes[g, 5] * x2
                        - modes[g, 6] * t + modes[g, 7])
        a0 += air.gust * wave * modes[g, 0]
        a1 += air.gust * wave * modes[g, 1]
        a2 += air.gust * wave * modes[g, 2]
    return a0, a1, a2


@inline_kernel
def corner_gusts(air, modes, x, triangles, t):
    """The gusts at every corner of the wind triangles, each particle's once (a sum of sines is
    the air's costly part, and a cloth has a quarter as many particles as wind triangles); no
    rows without gusts."""
    gusts = np.zeros((x.shape[0] if modes.shape[0] > 0 else 0, 3))
    if modes.shape[0] == 0:
        return gusts
    seen = np.zeros(x.shape[0], np.bool_)
    for k in range(triangles.shape[0]):
        for j in range(3):
            i = triangles[k, j]
            if not seen[i]:
                seen[i] = True
                gusts[i, 0], gusts[i, 1], gusts[i, 2] = gust_velocity(air, modes, x[i, 0],
                                                                      x[i, 1], x[i, 2], t)
    return gusts


@inline_kernel
def triangle_wind(air, gusts, x, v, a, b, c):
    """The wind force (N) on triangle (a, b, c), and the coefficients of its corners'
    diagonal derivative, rho C_d A |w_n| / 9 (along n) and rho C_f A |w_t| / 9 (across), with n.
    ``gusts``: corner_gusts."""
    e0, e1, e2 = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
    f0, f1, f2 = x[c, 0] - x[a, 0], x[c, 1] - x[a, 1], x[c, 2] - x[a, 2]
    n0, n1, n2 = e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0
    twice_area = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if twice_area == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    n0, n1, n2 = n0 / twice_area, n1 / twice_area, n2 / twice_area
    area = 0.5 * twice_area
    third = 1.0 / 3.0
    air0, air1, air2 = air.u0, air.u1, air.u2
    if gusts.shape[0] > 0:
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
    return (normal * w_n * n0 + along * t0, normal * w_n * n1 + along * t1,
            normal * w_n * n2 + along * t2, 2.0 * normal / 9.0, 2.0 * along / 9.0, n0, n1, n2)


@inline_kernel
def ball_wind(air, modes, r, x, v, i, t):
    """Ball i's (radius r) relative air velocity w and 1/2 rho C_d pi r^2 |w| (its force is that
    times w)."""
    g0, g1, g2 = gust_velocity(air, modes, x[i, 0], x[i, 1], x[i, 2], t)
    w0, w1, w2 = air.u0 + g0 - v[i, 0], air.u1 + g1 - v[i, 1], air.u2 + g2 - v[i, 2]
    size = air.normal * math.pi * r * r * math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    return w0, w1, w2, size


@kernel
def add_wind_forces(model, x, v, scale, out):
    """out[i] += scale_i F_i: every wind triangle's force shared among its corners, and every
    ball's; ``scale`` per particle (inverse masses: accelerations) or one entry for all (h:
    backward Euler's impulses). The time is the world's (world.move_world)."""
    if model.wind_settings[ON] == 0.0:
        return
    t = model.clock[2]
    air, modes = air_at(model, t), model.wind_modes
    triangles = model.wind_triangles
    gusts = corner_gusts(air, modes, x, triangles, t)
    for k in range(triangles.shape[0]):
        a, b, c = triangles[k, 0], triangles[k, 1], triangles[k, 2]
        f0, f1, f2, _, _, _, _, _ = triangle_wind(air, gusts, x, v, a, b, c)
        share = model.wind_weights[k] / 3.0
        for i in (a, b, c):
            w = (scale[i] if scale.shape[0] > 1 else scale[0]) * share
            out[i, 0] += w * f0
            out[i, 1] += w * f1
            out[i, 2] += w * f2
    for i in model.balls:
        w0, w1, w2, size = ball_wind(air, modes, model.radius[i], x, v, i, t)
        s = scale[i] if scale.shape[0] > 1 else scale[0]
        out[i, 0] += s * size * w0
        out[i, 1] += s * size * w1
        out[i, 2] += s * size * w2


@kernel
def add_wind_jacobian(model, diagonal_slot, x, v, h, blocks):
    """Backward Euler: each corner's -h dF_i/dv_i (module doc) added to its diagonal block."""
    if model.wind_settings[ON] == 0.0:
        return
    t = model.clock[2]
    air, modes = air_at(model, t), model.wind_modes
    triangles = model.wind_triangles
    gusts = corner_gusts(air, modes, x, triangles, t)
    for k in range(triangles.shape[0]):
        a, b, c = triangles[k, 0], triangles[k, 1], triangles[k, 2]
        _, _, _, normal, along, n0, n1, n2 = triangle_wind(air, gusts, x, v, a, b, c)
        normal, along = normal * model.wind_weights[k], along * model.wind_weights[k]
        n = (n0, n1, n2)
        for i in (a, b, c):
            slot = diagonal_slot[i]
            for r in range(3):
                for s in range(3):
                    identity = 1.0 if r == s else 0.0
                    blocks[slot, r, s] += h * (normal * n[r] * n[s]
                                               + along * (identity - n[r] * n[s]))
    for i in model.balls:
        w0, w1, w2, size = ball_wind(air, modes, model.radius[i], x, v, i, t)
        w = (w0, w1, w2)
        speed = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if speed == 0.0:
            continue
        slot = diagonal_slot[i]
        for p in range(3):
            for q in range(3):
                identity = 1.0 if p == q else 0.0
                blocks[slot, p, q] += h * size * (identity + w[p] * w[q] / (speed * speed))
