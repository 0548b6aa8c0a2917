"""One particle's block of vertex block descent: the gradient and Hessian of the step's energy in
that particle's position alone, and the 3 x 3 Newton step they give.

Backward Euler's step is the minimum over the new positions x of the incremental potential

    E(x) = sum_i m_i / (2 h^2) |x_i - y_i|^2 + sum_springs (ks / 2) (|x_a - x_b| - r)^2
           + dampers and drag on the velocity (x - x0) / h + contact + the terms' forces,

with y = x0 + h v0 + h^2 g the inertial target. Held at all other particles, E is a function of
x_i, with force f_i = -dE/dx_i and Hessian H_i. Each piece below adds its share of both:

- inertia: f = -m/h^2 (x_i - y_i), H = m/h^2 I;
- a spring (i, j) with d = x_i - x_j, l = d / |d|: f = -ks (|d| - r) l - kd/h (((x_i - x0_i) -
  (x_j - x0_j)) . l) l, the damper exactly backward Euler's on the velocity (x - x0) / h;
  H = (ks - q + kd/h) l l^T + q I with q = ks max(0, 1 - r/|d|): the part across a squeezed
  spring, negative, is dropped, as backward Euler's matrix drops it (implicit/jacobian.py), so
  that H stays positive definite and every block step is a descent step;
- terrain contact: a penalty E = k/2 (delta - phi)^2 where phi < delta (contact.py);
- the terms (soft pins, attachments, wind, attractor...): their force and their diagonal block,
  linearized at the iteration's start (integrators/vbd.py).
"""
import math

from .._jit import kernel


@kernel
def spring_share(xi, mi, xj, oj, rest_length, ks, kd_over_h):
    """A spring (i, j)'s share of particle i's block (module doc), as the 9-tuple ``Block``
    holds: its force on i and the upper triangle of its Hessian. x_i, its motion this step
    m_i = x_i - x0_i, x_j and x0_j (``oj``) are given as tuples of their coordinates (scalars:
    the sweep reads particle i's once for all its springs); kd_over_h: kd / h, once a step. All
    zero for a spring of zero length (no direction, no force, as in forces.py)."""
    xi0, xi1, xi2 = xi
    mi0, mi1, mi2 = mi
    xj0, xj1, xj2 = xj
    oj0, oj1, oj2 = oj
    dx, dy, dz = xi0 - xj0, xi1 - xj1, xi2 - xj2
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    lx, ly, lz = dx / length, dy / length, dz / length
    # (x_i - x0_i) - (x_j - x0_j) along l, summed in the order m_i - x_j + x0_j
    stretch = (mi0 - xj0 + oj0) * lx + (mi1 - xj1 + oj1) * ly + (mi2 - xj2 + oj2) * lz
    size = ks * (length - rest_length) + kd_over_h * stretch
    across = ks * max(0.0, 1.0 - rest_length / length)
    along = ks - across + kd_over_h
    return (-size * lx, -size * ly, -size * lz, along * lx * lx + across, along * lx * ly,
            along * lx * lz, along * ly * ly + across, along * ly * lz, along * lz * lz + across)


@kernel
def added(block, share):
    """Two blocks' sums (force, then the Hessian's upper triangle), summed."""
    return (block[0] + share[0], block[1] + share[1], block[2] + share[2], block[3] + share[3],
            block[4] + share[4], block[5] + share[5], block[6] + share[6], block[7] + share[7],
            block[8] + share[8])


@kernel
def solve_block(block):
    """H^-1 f for a block's sums (``added``), H symmetric; zero where H is singular to rounding
    (no step rather than a wild one)."""
    fx, fy, fz, h00, h01, h02, h11, h12, h22 = block
    c00 = h11 * h22 - h12 * h12
    c01 = h02 * h12 - h01 * h22
    c02 = h01 * h12 - h02 * h11
    determinant = h00 * c00 + h01 * c01 + h02 * c02
    scale = abs(h00) + abs(h11) + abs(h22)
    if not abs(determinant) > 1e-12 * scale * scale * scale:
        return 0.0, 0.0, 0.0
    c11 = h00 * h22 - h02 * h02
    c12 = h01 * h02 - h00 * h12
    c22 = h00 * h11 - h01 * h01
    return ((c00 * fx + c01 * fy + c02 * fz) / determinant,
            (c01 * fx + c11 * fy + c12 * fz) / determinant,
            (c02 * fx + c12 * fy + c22 * fz) / determinant)
