"""The adjoint's hot loops as Numba kernels: the springs' forces and the vector-Jacobian products
(VJPs) of physics.py, whose NumPy functions are their references (tests/test_gradients.py
compares them), and the explicit methods' whole step adjoints without contact.

Per spring (a, b): d = x_a - x_b, L = |d|, l = d / L, w = v_a - v_b, and for a cotangent g on the
particles g_s = g_a - g_b (physics.py's module doc has the formulas). Springs are visited in
order, one thread: the sums are the same bits whatever the thread count (issue 32's
determinism). A spring of zero length has no force and passes no gradient, as in the forward.
"""
import math

import numpy as np

from .._jit import kernel


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
def add_spring_forces_vjp(a, b, ks, kd, rest, x, v, g, x_bar, v_bar, ks_bar, kd_bar, rest_bar):
    """Add g . d(spring forces)/d(x, v, ks, kd, rest) (physics.spring_forces_vjp)."""
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


@kernel
def accelerations(a, b, ks, kd, rest, inv_mass, drag, gravity, x, v, force, out):
    """out = dv/dt before contact (physics.accelerations); ``force`` gets the springs'."""
    force[:] = 0.0
    add_spring_forces(a, b, ks, kd, rest, x, v, force)
    for i in range(x.shape[0]):
        w = inv_mass[i]
        for c in range(3):
            out[i, c] = w * (force[i, c] - drag[i] * v[i, c]) + (gravity[c] if w > 0.0 else 0.0)


@kernel
def accelerations_vjp(a, b, ks, kd, rest, inv_mass, drag, x, v, force, g, x_bar, v_bar, bars,
                      scratch):
    """Add g . d(accelerations)/d(everything) (physics.accelerations_vjp); ``force`` is the
    springs' force at (x, v) (from ``accelerations``), ``bars`` (ks, kd, rest, mass, drag,
    gravity) the parameters' cotangents, ``scratch`` a (P, 3) work array."""
    ks_bar, kd_bar, rest_bar, mass_bar, drag_bar, gravity_bar = bars
    for i in range(x.shape[0]):
        w = inv_mass[i]
        if w > 0.0:
            net = 0.0
            for c in range(3):
                net += g[i, c] * (force[i, c] - drag[i] * v[i, c])
                gravity_bar[c] += g[i, c]
            mass_bar[i] -= w * w * net
        gv = 0.0
        for c in range(3):
            gv += g[i, c] * v[i, c]
            v_bar[i, c] -= w * drag[i] * g[i, c]
            scratch[i, c] = w * g[i, c]
        drag_bar[i] -= w * gv
    add_spring_forces_vjp(a, b, ks, kd, rest, x, v, scratch, x_bar, v_bar, ks_bar, kd_bar,
                          rest_bar)


@kernel
def rk4_step_vjp(springs, particles, h, x, v, x_bar, v_bar, bars, work):
    """The adjoint of one RK4 step without contact (adjoints.RK4Adjoint): (x_bar, v_bar) at
    the step's start, in place of those at its end. ``springs`` (a, b, ks, kd, rest),
    ``particles`` (inv_mass, drag, gravity); ``work`` 17 (P, 3) arrays."""
    a, b, ks, kd, rest = springs
    inv_mass, drag, gravity = particles
    count = x.shape[0]
    xs, vs, fs, acc = work[0:4], work[4:8], work[8:12], work[12:16]
    scratch = work[16]
    # the stages, as rk4.py takes them
    xs[0][:] = x
    vs[0][:] = v
    for k in range(4):
        if k > 0:
            step = h if k == 3 else h / 2
            for i in range(count):
                for c in range(3):
                    xs[k][i, c] = x[i, c] + step * vs[k - 1][i, c]
                    vs[k][i, c] = v[i, c] + step * acc[k - 1][i, c]
        accelerations(a, b, ks, kd, rest, inv_mass, drag, gravity, xs[k], vs[k], fs[k], acc[k])
    # backwards: stage k's slope (v_k, a_k) enters y' with weight; its state is
    # y + step (v_{k-1}, a_{k-1}), so what reaches (x_k, v_k) is carried to stage k-1
    out_x, out_v = x_bar.copy(), v_bar.copy()
    xk_bar, vk_bar = np.zeros((count, 3)), np.zeros((count, 3))
    g = np.empty((count, 3))
    v_carry, a_carry = np.zeros((count, 3)), np.zeros((count, 3))
    for k in range(3, -1, -1):
        weight = h / 6 if k == 0 or k == 3 else h / 3
        for i in range(count):
            for c in range(3):
                xk_bar[i, c] = 0.0
                vk_bar[i, c] = weight * x_bar[i, c] + v_carry[i, c]
                g[i, c] = weight * v_bar[i, c] + a_carry[i, c]
        accelerations_vjp(a, b, ks, kd, rest, inv_mass, drag, xs[k], vs[k], fs[k], g, xk_bar,
                          vk_bar, bars, scratch)
        step = h if k == 3 else h / 2
        for i in range(count):
            for c in range(3):
                out_x[i, c] += xk_bar[i, c]
                out_v[i, c] += vk_bar[i, c]
                v_carry[i, c] = step * xk_bar[i, c]
                a_carry[i, c] = step * vk_bar[i, c]
    # the loop added stage 1's own (x, v) cotangents; the carries out of it go nowhere
    x_bar[:] = out_x
    v_bar[:] = out_v


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
def add_system_springs_vjp(a, b, ks, kd, rest, x, u, g, h, stiffness_scale, damping_scale,
                           x_bar, u_bar, ks_bar, kd_bar, rest_bar):
    """Add g . d[the springs' terms applied to u]/d(x, u, ks, kd, rest), where a spring's term on
    particle a is  damping_scale kd (l . u_s) l + stiffness_scale (dF/dx) u_s:
    damping_scale = h, stiffness_scale = -h^2 gives the system's springs (A = M + ... - h^2
    dF/dx), damping_scale = 0, stiffness_scale = 1 the stiffness product. ``u_bar`` may be
    empty (u held fixed)."""
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
