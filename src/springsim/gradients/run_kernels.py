"""The RK4 step adjoint on springs in runs (spring_runs.py), the layout in which the forward's
force loop compiles to SIMD code: here the adjoint's own force evaluations and its
vector-Jacobian products (VJPs) use it too, with parameters per spring (a stiffness field gives
the springs of one run different constants) kept per entry of the runs.

Entry e of a run holds spring ``entry_spring[e]``, or -1 at a hole, whose stiffness and damping
are zero so that it adds nothing. The VJP of a run is one loop writing nine results per spring,
then the scatter to the springs' ends: it compiles to SIMD code only with the runtime alias
checks that _jit.allow_memory_checks permits (without them, scalar code; three loops of three
results each, which needed fewer checks, were a third slower: benchmarks/gradients.py kernels).
Springs in no run take kernels.py's loops. One thread, a fixed order: the same bits for any
thread count.

The columns (``cols``, ROWS x P) hold, by rows: positions, velocities, the cotangent g on the
forces, the springs' force, two blocks of scratch and the cotangents of x and v.
"""
import math
from typing import NamedTuple

import numpy as np

from .._jit import inline_kernel, kernel
from ..spring_runs import RunLayout
from .kernels import SpringBars, add_spring_forces, add_spring_forces_vjp

X, V, G, FORCE, PUSH, DAMP, X_BAR, V_BAR = range(0, 24, 3)   # first rows of each block
ROWS = 24
KS, KD, REST, KS_BAR, KD_BAR, REST_BAR = range(6)                    # rows of the entry table


class Particles(NamedTuple):
    """What the RK4 step adjoint takes of the particles."""

    inv_mass: np.ndarray   # (P,) 1/kg, 0 for a pinned particle
    drag: np.ndarray       # (P,) N s/m
    gravity: np.ndarray    # (3,) m/s^2


class StepBars(NamedTuple):
    """The parameters' cotangents the RK4 step adjoint adds to (physics.Cotangents')."""

    ks: np.ndarray
    kd: np.ndarray
    rest: np.ndarray
    mass: np.ndarray
    drag: np.ndarray
    gravity: np.ndarray


def entry_table(layout: RunLayout, ks, kd, rest) -> np.ndarray:
    """(6, E): each entry's ks, kd and rest length (a hole's 0, 0, -1) and three rows for their
    cotangents."""
    spring, hole = layout.entry_spring, layout.entry_spring < 0
    table = np.zeros((6, len(spring)))
    table[KS] = np.where(hole, 0.0, ks[spring])
    table[KD] = np.where(hole, 0.0, kd[spring])
    table[REST] = np.where(hole, -1.0, rest[spring])
    return table


@inline_kernel
def rows(cols, first, a, count):
    """Rows first, first + 1, first + 2 of the columns from a, count long."""
    return (cols[first, a:a + count], cols[first + 1, a:a + count],
            cols[first + 2, a:a + count])


@inline_kernel
def ends(cols, first, a, b, count):
    """Rows first.. of the columns at the springs' first ends and at their second ends."""
    x_a, y_a, z_a = rows(cols, first, a, count)
    x_b, y_b, z_b = rows(cols, first, b, count)
    return x_a, y_a, z_a, x_b, y_b, z_b


@inline_kernel
def difference(values, i):
    """Spring i's value at its first end minus that at its second (``values``: ends)."""
    return values[0][i] - values[3][i], values[1][i] - values[4][i], values[2][i] - values[5][i]


@inline_kernel
def direction(positions, i):
    """Spring i's d = x_a - x_b, 1/|d| (zero for a spring of no length: no force, no gradient)
    and unit vector."""
    dx, dy, dz = difference(positions, i)
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    inverse = 1.0 / length if length > 0.0 else 0.0
    return length, inverse, dx * inverse, dy * inverse, dz * inverse


@inline_kernel
def add_run_forces(cols, a, b, count, ks, kd, rest):
    """The force rows += the force of springs (a + i, b + i), i < count."""
    positions, velocities = ends(cols, X, a, b, count), ends(cols, V, a, b, count)
    fx, fy, fz = rows(cols, PUSH, a, count)
    for i in range(count):
        length, _, lx, ly, lz = direction(positions, i)
        wx, wy, wz = difference(velocities, i)
        factor = -ks[i] * (length - rest[i]) - kd[i] * (wx * lx + wy * ly + wz * lz)
        fx[i], fy[i], fz[i] = factor * lx, factor * ly, factor * lz
    add_to_ends(cols, FORCE, PUSH, a, b, count, 1.0)


@inline_kernel
def add_to_ends(cols, target, source, a, b, count, sign):
    """Rows target.. at a + i += sign source[i], and at b + i -= it (their own loops: b + i may be
    a + j of another i)."""
    for c in range(3):
        from_a, to_a, to_b = (cols[source + c, a:a + count], cols[target + c, a:a + count],
                              cols[target + c, b:b + count])
        for i in range(count):
            to_a[i] += sign * from_a[i]
        for i in range(count):
            to_b[i] -= sign * from_a[i]


@inline_kernel
def add_run_vjp(cols, table, a, b, count, start):
    """Add g . d(force)/d(x, v) of springs (a + i, b + i) to the cotangent rows, and
    g . d(force)/d(ks, kd, rest) to the table's cotangent rows at entries start + i. With
    d = x_a - x_b, L = |d|, l = d / L, w = v_a - v_b, g = g_a - g_b (kernels.add_spring_forces_vjp
    has the derivation): PUSH = g . d(force on a)/d x_a, DAMP = kd (g . l) l, minus
    g . d(force on a)/d v_a."""
    positions, velocities = ends(cols, X, a, b, count), ends(cols, V, a, b, count)
    cotangents = ends(cols, G, a, b, count)
    ks, kd, rest = table_rows(table, start, count)
    ks_bar, kd_bar = table[KS_BAR, start:start + count], table[KD_BAR, start:start + count]
    rest_bar = table[REST_BAR, start:start + count]
    ex, ey, ez = rows(cols, PUSH, a, count)
    qx, qy, qz = rows(cols, DAMP, a, count)
    for i in range(count):
        length, inverse, lx, ly, lz = direction(positions, i)
        wx, wy, wz = difference(velocities, i)
        gx, gy, gz = difference(cotangents, i)
        gl = gx * lx + gy * ly + gz * lz
        wl = wx * lx + wy * ly + wz * lz
        stretch = length - rest[i]
        ratio = stretch * inverse
        px, py, pz = gl * wx + wl * gx, gl * wy + wl * gy, gl * wz + wl * gz
        pl = px * lx + py * ly + pz * lz
        k, c = ks[i], kd[i]
        ex[i] = -k * (gl * lx + (gx - gl * lx) * ratio) - c * (px - pl * lx) * inverse
        ey[i] = -k * (gl * ly + (gy - gl * ly) * ratio) - c * (py - pl * ly) * inverse
        ez[i] = -k * (gl * lz + (gz - gl * lz) * ratio) - c * (pz - pl * lz) * inverse
        damped = c * gl
        qx[i], qy[i], qz[i] = damped * lx, damped * ly, damped * lz
        ks_bar[i] -= stretch * gl
        kd_bar[i] -= wl * gl
        rest_bar[i] += k * gl
    add_to_ends(cols, X_BAR, PUSH, a, b, count, 1.0)
    add_to_ends(cols, V_BAR, DAMP, a, b, count, -1.0)


@inline_kernel
def to_rows(cols, first, values):
    """Rows first.. of the columns = values (P, 3)."""
    for i in range(values.shape[0]):
        for c in range(3):
            cols[first + c, i] = values[i, c]


@inline_kernel
def stage_accelerations(runs, table, loose, particles, x, v, cols, force, out):
    """out = dv/dt at (x, v) before contact (physics.accelerations), ``force`` the springs'."""
    inv_mass, drag, gravity = particles.inv_mass, particles.drag, particles.gravity
    to_rows(cols, X, x)
    to_rows(cols, V, v)
    cols[FORCE:FORCE + 3] = 0.0
    for r in range(runs.shape[0]):
        first, offset, count, start = runs[r, 0], runs[r, 1], runs[r, 2], runs[r, 3]
        ks, kd, rest = table_rows(table, start, count)
        add_run_forces(cols, first, first + offset, count, ks, kd, rest)
    for i in range(x.shape[0]):
        for c in range(3):
            force[i, c] = cols[FORCE + c, i]
    add_spring_forces(loose.a, loose.b, loose.ks, loose.kd, loose.rest, x, v, force)
    for i in range(x.shape[0]):
        w = inv_mass[i]
        for c in range(3):
            out[i, c] = w * (force[i, c] - drag[i] * v[i, c]) + (gravity[c] if w > 0.0 else 0.0)


@inline_kernel
def table_rows(table, start, count):
    """ks, kd and rest length of one run's entries."""
    return (table[KS, start:start + count], table[KD, start:start + count],
            table[REST, start:start + count])


@kernel
def rk4_step_vjp(layout, table, loose, particles, h, start, start_bar, bars, work, cols, kept):
    """The adjoint of one RK4 step without contact (adjoints.RK4Adjoint) from ``start`` (x, v):
    ``start_bar`` (x_bar, v_bar) at the step's start, in place of those at its end. ``layout``
    (a RunLayout), ``table`` (entry_table), ``loose`` (kernels.Springs) the springs in no run,
    ``particles`` (Particles), ``bars`` (StepBars) the parameters' cotangents, added to;
    ``work`` 17 (P, 3) arrays; ``cols`` (ROWS, P); ``kept`` the stages' accelerations as the
    forward computed them (4, P, 3: tape.py), or no rows, and then they are evaluated again
    here."""
    runs, entry_spring, loose_springs = layout.runs, layout.entry_spring, layout.loose
    count = loose_springs.shape[0]
    loose_bars = SpringBars(np.zeros(count), np.zeros(count), np.zeros(count))
    table[KS_BAR:REST_BAR + 1] = 0.0
    if kept.shape[0] == 4:
        stages_vjp(runs, table, loose, loose_bars, particles, h, start, kept, start_bar, bars,
                   work, cols)
    else:
        acc = work[12:16]
        evaluate_stages(runs, table, loose, particles, h, start, work, cols, acc)
        stages_vjp(runs, table, loose, loose_bars, particles, h, start, acc, start_bar, bars,
                   work, cols)
    ks_bar, kd_bar, rest_bar = bars.ks, bars.kd, bars.rest
    for e in range(entry_spring.shape[0]):
        s = entry_spring[e]
        if s >= 0:
            ks_bar[s] += table[KS_BAR, e]
            kd_bar[s] += table[KD_BAR, e]
            rest_bar[s] += table[REST_BAR, e]
    for j in range(loose_springs.shape[0]):
        s = loose_springs[j]
        ks_bar[s] += loose_bars.ks[j]
        kd_bar[s] += loose_bars.kd[j]
        rest_bar[s] += loose_bars.rest[j]


@inline_kernel
def evaluate_stages(runs, table, loose, particles, h, start, work, cols, acc):
    """The stages' accelerations acc (4, P, 3) from ``start`` (x, v), as rk4.py takes them."""
    x, v = start
    xs, vs, fs = work[0:4], work[4:8], work[8:12]
    xs[0][:] = x
    vs[0][:] = v
    for k in range(4):
        if k > 0:
            step = h if k == 3 else h / 2
            for i in range(x.shape[0]):
                for c in range(3):
                    xs[k][i, c] = x[i, c] + step * vs[k - 1][i, c]
                    vs[k][i, c] = v[i, c] + step * acc[k - 1][i, c]
        stage_accelerations(runs, table, loose, particles, xs[k], vs[k], cols, fs[k], acc[k])


@inline_kernel
def stages_vjp(runs, table, loose, loose_bars, particles, h, start, acc, start_bar, bars, work,
               cols):
    """The stages backwards (physics.accelerations_vjp at each): stage k's slope (v_k, a_k)
    enters y' with ``weight``, and its state is y + step (v_{k-1}, a_{k-1}), so what reaches
    (x_k, v_k) is carried to stage k-1. Each stage's state is written straight into the
    columns' rows, from the stages' accelerations, in the pass that also takes the particles'
    terms (their mass, drag and gravity), and one pass after the springs adds what they gave
    and carries it on. ``acc``: the stages' accelerations w (force - drag v) + gravity, whose
    derivative with respect to the mass is -w (acc - gravity)."""
    (x, v), (x_bar, v_bar) = start, start_bar
    inv_mass, drag, gravity = particles.inv_mass, particles.drag, particles.gravity
    mass_bar, drag_bar, gravity_bar = bars.mass, bars.drag, bars.gravity
    has_loose = loose.a.shape[0] > 0
    xk, vk, gk, xk_bar, vk_bar = work[0], work[1], work[2], work[3], work[4]
    v_carry, a_carry, out_x, out_v = work[5], work[6], work[7], work[8]
    out_x[:] = x_bar
    out_v[:] = v_bar
    v_carry[:] = 0.0
    a_carry[:] = 0.0
    for k in range(3, -1, -1):
        weight = h / 6 if k == 0 or k == 3 else h / 3
        step = h if k == 3 else h / 2
        for i in range(x.shape[0]):
            w = inv_mass[i]
            net = 0.0
            gv = 0.0
            for c in range(3):
                if k == 0:
                    position, velocity = x[i, c], v[i, c]
                else:
                    before = v[i, c] if k == 1 else v[i, c] + h / 2 * acc[k - 2][i, c]
                    position = x[i, c] + step * before
                    velocity = v[i, c] + step * acc[k - 1][i, c]
                g = weight * v_bar[i, c] + a_carry[i, c]   # on the stage's acceleration
                cols[X + c, i], cols[V + c, i], cols[G + c, i] = position, velocity, w * g
                xk_bar[i, c] = 0.0
                vk_bar[i, c] = weight * x_bar[i, c] + v_carry[i, c] - w * drag[i] * g
                if has_loose:
                    xk[i, c], vk[i, c], gk[i, c] = position, velocity, w * g
                if w > 0.0:
                    net += g * (acc[k][i, c] - gravity[c])
                    gravity_bar[c] += g
                gv += g * velocity
            if w > 0.0:
                mass_bar[i] -= w * net
            drag_bar[i] -= w * gv
        cols[X_BAR:V_BAR + 3] = 0.0
        for r in range(runs.shape[0]):
            first, offset, count, start = runs[r, 0], runs[r, 1], runs[r, 2], runs[r, 3]
            add_run_vjp(cols, table, first, first + offset, count, start)
        if has_loose:
            add_spring_forces_vjp(loose, xk, vk, gk, xk_bar, vk_bar, loose_bars)
        for i in range(x.shape[0]):
            for c in range(3):
                x_share = xk_bar[i, c] + cols[X_BAR + c, i]
                v_share = vk_bar[i, c] + cols[V_BAR + c, i]
                out_x[i, c] += x_share
                out_v[i, c] += v_share
                v_carry[i, c] = step * x_share
                a_carry[i, c] = step * v_share
    # the loop added stage 1's own (x, v) cotangents; the carries out of it go nowhere
    x_bar[:] = out_x
    v_bar[:] = out_v
