"""Spring and damper Jacobians, assembled into the backward-Euler matrix.

For a spring (a, b) with d = x_a - x_b, L = |d|, l = d / L and rest length r, the force on a is
    f_a = -ks (L - r) l - kd ((v_a - v_b) . l) l,      f_b = -f_a,
and its Jacobians (the (a, a) and (b, b) blocks of dF/dx and dF/dv; (a, b) and (b, a) get minus):
    dF_a/dx_a = -ks [l l^T + (1 - r/L) (I - l l^T)]      stiffness along and across the spring
    dF_a/dv_a = -kd l l^T                                 damper
Drag -c v adds -c I to the diagonal of dF/dv.

Two terms are left out so that the matrix M - h dF/dv - h^2 dF/dx stays symmetric positive
definite, which conjugate gradients needs:
- the compressive part of the geometric stiffness: for a squeezed spring (L < r) the factor
  1 - r/L is negative, the spring is unstable across its axis, and a squeezed lattice would make
  the matrix indefinite. It is clamped to 0 (Choi and Ko, 2002, do the same);
- the damper's dependence on positions, -kd/L [l u^T + (u . l) I] (I - l l^T) with
  u = v_a - v_b: it is not symmetric, and it is zero for a spring that is not stretching.
Both only change the linearization, not the equations: a step stays first order, and further Newton
iterations still converge to the exact backward-Euler step (linearly rather than quadratically).
"""
import math

from .._jit import inline_kernel, kernel


@kernel
def stiffness_along_across(ks, rest_length, length):
    """dF_a/dx_a = -(along l l^T + across I): the two coefficients (N/m)."""
    across = ks * max(0.0, 1.0 - rest_length / length)  # compressed: dropped, see module doc
    return ks - across, across


@kernel
def particle_mass(inv_mass):
    """Mass (kg); a pinned particle (inverse mass 0) gets 1 kg, a placeholder that keeps the
    diagonal positive: its rows are filtered out of every solve."""
    return 1.0 / inv_mass if inv_mass > 0.0 else 1.0


@kernel
def spring_block(dx, dy, dz, ks, kd, rest_length, damping_scale, stiffness_scale):
    """The block C = -damping_scale dF_a/dv_a - stiffness_scale dF_a/dx_a = p l l^T + q I of a
    spring with d = x_a - x_b = (dx, dy, dz), as (p, q, l_x, l_y, l_z); all zero for a spring of
    zero length (no direction, no force as in forces.py, so no Jacobian). Scalars in and out, so
    that the compiler inlines it (a kernel called per spring with arrays as arguments costs a
    reference count up and down per array)."""
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    if length == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    along, across = stiffness_along_across(ks, rest_length, length)
    return (damping_scale * kd + stiffness_scale * along, stiffness_scale * across, dx / length,
            dy / length, dz / length)


@kernel
def assemble_mass(model, pattern, mass_scale, damping_scale, blocks):
    """blocks = mass_scale M - damping_scale (dF/dv of the drag): the diagonal, nothing else."""
    blocks[:] = 0.0
    for i in range(model.inv_mass.shape[0]):
        diagonal = mass_scale * particle_mass(model.inv_mass[i]) + damping_scale * model.drag[i]
        slot = pattern.diagonal_slot[i]
        for c in range(3):
            blocks[slot, c, c] = diagonal


@kernel
def assemble_system(model, pattern, x, mass_scale, damping_scale, stiffness_scale, blocks):
    """blocks = mass_scale M - damping_scale dF/dv - stiffness_scale dF/dx, at positions x.

    Backward Euler uses (1, h, h^2); (0, 1, 0) gives -dF/dv and (0, 0, 1) gives -dF/dx alone.
    Every spring adds its block C to (a, a) and (b, b) and subtracts it from (a, b) and (b, a).
    """
    assemble_mass(model, pattern, mass_scale, damping_scale, blocks)
    springs, rest_length, group = model.springs, model.rest_length, model.spring_group
    for s in range(springs.shape[0]):
        a, b, g = springs[s, 0], springs[s, 1], group[s]
        p, q, l0, l1, l2 = spring_block(x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2],
                                        model.group_ks[g], model.group_kd[g], rest_length[s],
                                        damping_scale, stiffness_scale)
        aa, bb, ab, ba = (pattern.spring_slots[s, 0], pattern.spring_slots[s, 1],
                          pattern.spring_slots[s, 2], pattern.spring_slots[s, 3])
        l = (l0, l1, l2)
        for r in range(3):
            for c in range(r, 3):   # each value computed once: the matrix is exactly symmetric
                value = p * l[r] * l[c] + (q if r == c else 0.0)
                blocks[aa, r, c] += value
                blocks[bb, r, c] += value
                blocks[ab, r, c] -= value
                blocks[ba, r, c] -= value
                if c != r:
                    blocks[aa, c, r] += value
                    blocks[bb, c, r] += value
                    blocks[ab, c, r] -= value
                    blocks[ba, c, r] -= value


@kernel
def assemble_diagonal_and_terms(model, layout, x, mass_scale, damping_scale, stiffness_scale,
                                blocks, terms):
    """The matrix of assemble_system, as its diagonal blocks (``layout.diagonal`` a
    ``diagonal_pattern``) and the springs' coefficients in ``terms`` (spring_terms.py) laid out
    as ``layout`` has them (pattern.SolveLayout), holes of the runs zero."""
    pattern = layout.diagonal
    assemble_mass(model, pattern, mass_scale, damping_scale, blocks)
    runs, run_coefficients, loose_pairs, loose_coefficients, columns = terms
    run_coefficients[:] = 0.0
    for r in range(runs.shape[0]):
        first, offset, count, start = runs[r, 0], runs[r, 1], runs[r, 2], runs[r, 3]
        for i in range(count):
            s = layout.entry_spring[start + i]
            if s < 0:
                continue   # a hole
            set_spring_coefficients(model, s, x, first + i, first + i + offset, damping_scale,
                                    stiffness_scale, run_coefficients, start + i)
    for k in range(loose_pairs.shape[0]):
        set_spring_coefficients(model, layout.loose_springs[k], x, loose_pairs[k, 0],
                                loose_pairs[k, 1], damping_scale, stiffness_scale,
                                loose_coefficients, k)
    add_terms_to_diagonal(pattern, terms, blocks)


@inline_kernel
def set_spring_coefficients(model, s, x, a, b, damping_scale, stiffness_scale, coefficients,
                            column):
    """Column ``column`` of ``coefficients`` = spring s's p, q, l (spring_block) at x; a and b
    its particles."""
    g = model.spring_group[s]
    p, q, l0, l1, l2 = spring_block(x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2],
                                    model.group_ks[g], model.group_kd[g], model.rest_length[s],
                                    damping_scale, stiffness_scale)
    coefficients[0, column], coefficients[1, column] = p, q
    coefficients[2, column], coefficients[3, column], coefficients[4, column] = l0, l1, l2


@kernel
def add_terms_to_diagonal(pattern, terms, blocks):
    """Every spring's block C to the diagonal blocks of both its particles."""
    runs, run_coefficients, loose_pairs, loose_coefficients, columns = terms
    for r in range(runs.shape[0]):
        first, offset, count, start = runs[r, 0], runs[r, 1], runs[r, 2], runs[r, 3]
        for i in range(count):
            for end in (first + i, first + i + offset):
                slot = pattern.diagonal_slot[end]
                k = start + i
                p, q = run_coefficients[0, k], run_coefficients[1, k]
                l = (run_coefficients[2, k], run_coefficients[3, k], run_coefficients[4, k])
                add_block(blocks, slot, p, q, l)
    for k in range(loose_pairs.shape[0]):
        for end in (loose_pairs[k, 0], loose_pairs[k, 1]):
            p, q = loose_coefficients[0, k], loose_coefficients[1, k]
            l = (loose_coefficients[2, k], loose_coefficients[3, k], loose_coefficients[4, k])
            add_block(blocks, pattern.diagonal_slot[end], p, q, l)


@inline_kernel
def add_block(blocks, slot, p, q, l):
    """blocks[slot] += p l l^T + q I, each value computed once: exactly symmetric."""
    for row in range(3):
        for c in range(row, 3):
            value = p * l[row] * l[c] + (q if row == c else 0.0)
            blocks[slot, row, c] += value
            if c != row:
                blocks[slot, c, row] += value


@kernel
def add_stiffness_product(model, x, w, scale, out):
    """out += scale (dF/dx) w, with the same (clamped) stiffness as the assembled matrix."""
    springs, rest_length, group = model.springs, model.rest_length, model.spring_group
    for s in range(springs.shape[0]):
        a, b = springs[s, 0], springs[s, 1]
        dx, dy, dz = x[a, 0] - x[b, 0], x[a, 1] - x[b, 1], x[a, 2] - x[b, 2]
        length = math.sqrt(dx * dx + dy * dy + dz * dz)
        if length == 0.0:
            continue
        l0, l1, l2 = dx / length, dy / length, dz / length
        g = group[s]
        along, across = stiffness_along_across(model.group_ks[g], rest_length[s], length)
        u0, u1, u2 = w[a, 0] - w[b, 0], w[a, 1] - w[b, 1], w[a, 2] - w[b, 2]
        # (dF_a/dx_a) u = -(along (l . u) l + across u)
        lu = along * (l0 * u0 + l1 * u1 + l2 * u2)
        f0 = -scale * (lu * l0 + across * u0)
        f1 = -scale * (lu * l1 + across * u1)
        f2 = -scale * (lu * l2 + across * u2)
        out[a, 0] += f0
        out[a, 1] += f1
        out[a, 2] += f2
        out[b, 0] -= f0
        out[b, 1] -= f1
        out[b, 2] -= f2


@kernel
def block_multiply(pattern, blocks, u, out):
    """out = A u for the block sparse matrix A (``blocks`` in ``pattern``)."""
    row_start, column = pattern.row_start, pattern.column
    for i in range(u.shape[0]):
        s0 = s1 = s2 = 0.0
        for slot in range(row_start[i], row_start[i + 1]):
            j = column[slot]
            u0, u1, u2 = u[j, 0], u[j, 1], u[j, 2]
            s0 += blocks[slot, 0, 0] * u0 + blocks[slot, 0, 1] * u1 + blocks[slot, 0, 2] * u2
            s1 += blocks[slot, 1, 0] * u0 + blocks[slot, 1, 1] * u1 + blocks[slot, 1, 2] * u2
            s2 += blocks[slot, 2, 0] * u0 + blocks[slot, 2, 1] * u1 + blocks[slot, 2, 2] * u2
        out[i, 0] = s0
        out[i, 1] = s1
        out[i, 2] = s2
