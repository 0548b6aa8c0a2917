"""The adjoint's hot loops as Numba kernels: the springs' forces and the vector-Jacobian products
(VJPs) of physics.py, whose NumPy functions are their references (tests/test_gradients.py
compares them); the springs in no run of the RK4 step adjoint (run_kernels.py) take these loops.

Per spring (a, b): d = x_a - x_b, L = |d|, l = d / L, w = v_a - v_b, and for a cotangent g on the
particles g_s = g_a - g_b (physics.py's module doc has the formulas). Springs are visited in
order, one thread: the sums are the same bits whatever the thread count (issue 32's
determinism). A spring of zero length has no force and passes no gradient, as in the forward.
"""
import math
from typing import NamedTuple

import numpy as np

from .._jit import kernel


class Springs(NamedTuple):
    """Springs' ends and parameters, one entry per spring (physics.Physical's, or those of the
    springs in no run: run_kernels.py)."""

    a: np.ndarray      # (S,) int64: first particle
    b: np.ndarray      # (S,) int64: second particle
    ks: np.ndarray     # (S,) N/m
    kd: np.ndarray     # (S,) N s/m
    rest: np.ndarray   # (S,) m


class SpringBars(NamedTuple):
    """The cotangents of the springs' parameters, added to."""

    ks: np.ndarray
    kd: np.ndarray
    rest: np.ndarray


class Scales(NamedTuple):
    """What ``add_system_springs_vjp``'s terms are scaled by: (-h^2, h) for the system's
    springs, (1, 0) for the stiffness product."""

    stiffness: float
    damping: float


@kernel
def add_spring_forces(a, b, ks, kd, rest, x, v, out):
    """out += every spring's and damper's force (N)."""
    for s in range(a.shape[0]):
        i, j = a[s], b[s]
        dx, dy, dz = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1], x[i, 2] - x[j, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            continue
        lx, ly, lz = dx / length, dy / length, dz / length
        wl = (v[i, 0] - v[j, 0]) * lx + (v[i, 1] - v[j, 1]) * ly + (v[i, 2] - v[j, 2]) * lz
        f = -ks[s] * (length - rest[s]) - kd[s] * wl
        out[i, 0] += f * lx
        out[i, 1] += f * ly
        out[i, 2] += f * lz
        out[j, 0] -= f * lx
        out[j, 1] -= f * ly
        out[j, 2] -= f * lz


@kernel
def add_spring_forces_vjp(springs, x, v, g, x_bar, v_bar, bars):
    """Add g . d(spring forces)/d(x, v, ks, kd, rest) (physics.spring_forces_vjp); ``springs``
    a Springs, ``bars`` a SpringBars."""
    a, b, ks, kd, rest = springs.a, springs.b, springs.ks, springs.kd, springs.rest
    ks_bar, kd_bar, rest_bar = bars.ks, bars.kd, bars.rest
    for s in range(a.shape[0]):
        i, j = a[s], b[s]
        dx, dy, dz = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1], x[i, 2] - x[j, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            continue
        inverse = 1.0 / length
        lx, ly, lz = dx * inverse, dy * inverse, dz * inverse
        wx, wy, wz = v[i, 0] - v[j, 0], v[i, 1] - v[j, 1], v[i, 2] - v[j, 2]
        gx, gy, gz = g[i, 0] - g[j, 0], g[i, 1] - g[j, 1], g[i, 2] - g[j, 2]
        gl = gx * lx + gy * ly + gz * lz
        wl = wx * lx + wy * ly + wz * lz
        stretch = length - rest[s]
        k, c = ks[s], kd[s]
        # -ks [gl l + (L - r)/L (g - gl l)] - kd (I - l l^T)/L [gl w + wl g]
        ratio = stretch * inverse
        px, py, pz = gl * wx + wl * gx, gl * wy + wl * gy, gl * wz + wl * gz
        pl = px * lx + py * ly + pz * lz
        ex = -k * (gl * lx + (gx - gl * lx) * ratio) - c * (px - pl * lx) * inverse
        ey = -k * (gl * ly + (gy - gl * ly) * ratio) - c * (py - pl * ly) * inverse
        ez = -k * (gl * lz + (gz - gl * lz) * ratio) - c * (pz - pl * lz) * inverse
        x_bar[i, 0] += ex
        x_bar[i, 1] += ey
        x_bar[i, 2] += ez
        x_bar[j, 0] -= ex
        x_bar[j, 1] -= ey
        x_bar[j, 2] -= ez
        cg = c * gl
        v_bar[i, 0] -= cg * lx
        v_bar[i, 1] -= cg * ly
        v_bar[i, 2] -= cg * lz
        v_bar[j, 0] += cg * lx
        v_bar[j, 1] += cg * ly
        v_bar[j, 2] += cg * lz
        ks_bar[s] -= stretch * gl
        kd_bar[s] -= wl * gl
        rest_bar[s] += k * gl


# --- the implicit system (physics.stiffness_product_vjp, system_product_vjp) --------------------

@kernel
def add_stiffness_product(a, b, ks, rest, x, u, scale, out):
    """out += scale (dF/dx)(x) u, the compressive part clamped (physics.stiffness_product)."""
    for s in range(a.shape[0]):
        i, j = a[s], b[s]
        dx, dy, dz = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1], x[i, 2] - x[j, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            continue
        inverse = 1.0 / length
        lx, ly, lz = dx * inverse, dy * inverse, dz * inverse
        across = ks[s] * (1.0 - rest[s] * inverse) if length > rest[s] else 0.0
        along = ks[s] - across
        ux, uy, uz = u[i, 0] - u[j, 0], u[i, 1] - u[j, 1], u[i, 2] - u[j, 2]
        lu = lx * ux + ly * uy + lz * uz
        ex = -scale * (along * lu * lx + across * ux)
        ey = -scale * (along * lu * ly + across * uy)
        ez = -scale * (along * lu * lz + across * uz)
        out[i, 0] += ex
        out[i, 1] += ey
        out[i, 2] += ez
        out[j, 0] -= ex
        out[j, 1] -= ey
        out[j, 2] -= ez


@kernel
def add_system_springs_vjp(springs, x, u, g, scales, x_bar, u_bar, bars):
    """Add g . d[the springs' terms applied to u]/d(x, u, ks, kd, rest), where a spring's term on
    particle a is  damping_scale kd (l . u_s) l + stiffness_scale (dF/dx) u_s (``scales``):
    damping_scale = h, stiffness_scale = -h^2 gives the system's springs (A = M + ... - h^2
    dF/dx), damping_scale = 0, stiffness_scale = 1 the stiffness product. ``u_bar`` may be
    empty (u held fixed); ``springs`` a Springs, ``bars`` a SpringBars."""
    a, b, ks, kd, rest = springs.a, springs.b, springs.ks, springs.kd, springs.rest
    ks_bar, kd_bar, rest_bar = bars.ks, bars.kd, bars.rest
    stiffness_scale, damping_scale = scales.stiffness, scales.damping
    with_u = u_bar.shape[0] > 0
    for s in range(a.shape[0]):
        i, j = a[s], b[s]
        dx, dy, dz = x[i, 0] - x[j, 0], x[i, 1] - x[j, 1], x[i, 2] - x[j, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            continue
        inverse = 1.0 / length
        lx, ly, lz = dx * inverse, dy * inverse, dz * inverse
        k, r = ks[s], rest[s]
        stretched = length > r
        ratio = 1.0 - r * inverse if stretched else 0.0
        across = k * ratio
        along = k - across
        across_dl = k * r * inverse * inverse if stretched else 0.0
        across_dr = -k * inverse if stretched else 0.0
        ux, uy, uz = u[i, 0] - u[j, 0], u[i, 1] - u[j, 1], u[i, 2] - u[j, 2]
        gx, gy, gz = g[i, 0] - g[j, 0], g[i, 1] - g[j, 1], g[i, 2] - g[j, 2]
        lu = lx * ux + ly * uy + lz * uz
        lg = lx * gx + ly * gy + lz * gz
        sideways = gx * ux + gy * uy + gz * uz - lu * lg
        # stiffness part: out_a = -(along P(u) + across (u - P(u))) times stiffness_scale, with
        # P(u) = (l . u) l; the damping part damping_scale kd P(u)
        p = damping_scale * kd[s] - stiffness_scale * along
        # cotangent of d through P(u): (I - l l^T)/L [(g . l) u + (l . u) g]
        qx, qy, qz = lg * ux + lu * gx, lg * uy + lu * gy, lg * uz + lu * gz
        ql = qx * lx + qy * ly + qz * lz
        dl = -stiffness_scale * across_dl * sideways
        ex = p * (qx - ql * lx) * inverse + dl * lx
        ey = p * (qy - ql * ly) * inverse + dl * ly
        ez = p * (qz - ql * lz) * inverse + dl * lz
        x_bar[i, 0] += ex
        x_bar[i, 1] += ey
        x_bar[i, 2] += ez
        x_bar[j, 0] -= ex
        x_bar[j, 1] -= ey
        x_bar[j, 2] -= ez
        if with_u:
            pu, q = damping_scale * kd[s] - stiffness_scale * k, -stiffness_scale * across
            fx = pu * lg * lx + q * (gx - lg * lx)
            fy = pu * lg * ly + q * (gy - lg * ly)
            fz = pu * lg * lz + q * (gz - lg * lz)
            u_bar[i, 0] += fx
            u_bar[i, 1] += fy
            u_bar[i, 2] += fz
            u_bar[j, 0] -= fx
            u_bar[j, 1] -= fy
            u_bar[j, 2] -= fz
        kd_bar[s] += damping_scale * lu * lg
        ks_bar[s] -= stiffness_scale * (lu * lg + ratio * sideways)
        rest_bar[s] -= stiffness_scale * across_dr * sideways


@kernel
def largest_component(v):
    """The largest |v_ic| (sqrt(3) times it bounds the fastest speed)."""
    largest = 0.0
    for i in range(v.shape[0]):
        for c in range(3):
            largest = max(largest, abs(v[i, c]))
    return largest
