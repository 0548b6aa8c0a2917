"""The vector-Jacobian products of the explicit methods' body-body contact (body_contact.py):
back through the overlap correction, the impulse passes, the stencils' mobilities and
geometry, to the positions, velocities, masses and the contact parameters."""
from typing import NamedTuple

import numpy as np

from .body_contact import slid
from .stencil_geometry import BALL, EDGE, POINT, STEP, dot, geometry_of

class Bars(NamedTuple):
    """The cotangents of the contacts' stencils and of the inverse masses, gathered on the way
    back before they go to the positions."""

    weights: np.ndarray   # (K, 4)
    normal: np.ndarray    # (K, 3)
    depth: np.ndarray     # (K,)
    mobility: np.ndarray  # (K,)
    inv_mass: np.ndarray  # (P,)
    kinetic: np.ndarray   # (K,) each contact's kinetic friction
    restitution: np.ndarray   # (K,) and restitution


def scatter_vjp(weights, nodes, inv_mass, values, out_bar, bars):
    """Of out[n_i] += c_i m_i^-1 values_k: the values' cotangent (K, 3), the weights' and the
    inverse masses' added to ``bars``."""
    after = out_bar[nodes]                                # (K, 4, 3)
    moved = np.einsum("kjc,kc->kj", after, values)
    bars.weights[...] += inv_mass[nodes] * moved
    np.add.at(bars.inv_mass, nodes.ravel(), (weights * moved).ravel())
    return np.einsum("kj,kjc->kc", weights * inv_mass[nodes], after)


def gather_vjp(weights, nodes, u, g, u_bar, bars):
    """Of sum_i c_i u[n_i]: g (K, 3) to u_bar and the weights."""
    np.add.at(u_bar, nodes.ravel(), (weights[:, :, None] * g[:, None, :]).reshape(-1, 3))
    bars.weights[...] += np.einsum("kjc,kc->kj", u[nodes], g)


def respond_vjp(physical, response, x_bar, v_bar, bar):
    """The cotangents of (x, v) before ``respond`` and of the step's start positions, from
    those after it (the masses' share added to ``bar``)."""
    contacts = response.contacts
    count = len(contacts.nodes)
    bars = Bars(np.zeros((count, 4)), np.zeros((count, 3)), np.zeros(count), np.zeros(count),
                np.zeros(len(x_bar)), np.zeros(count), np.zeros(count))
    x_bar, v_bar = x_bar.copy(), v_bar.copy()
    start_bar = np.zeros_like(x_bar)
    overlap_vjp(physical, response, x_bar, start_bar, bars)
    impulse_passes_vjp(physical, contacts, response.mobility, response.passes, v_bar, bars)
    mobility_vjp(physical, contacts, response.count, bars)
    geometry_vjp(contacts, response.x, bars, x_bar)
    inv = physical.inv_mass
    bar.mass += np.where(physical.free, -bars.inv_mass * inv * inv, 0.0)
    keys_vjp(physical, contacts, bars, bar)
    return x_bar, v_bar, start_bar


def keys_vjp(physical, contacts, bars, bar):
    """The contacts' restitution and kinetic friction cotangents to the keys they came from
    (surface_params, ball_contacts): a surface contact's are the means of its two bodies', a
    ball-ball contact's restitution the mean of the two balls', a ball-particle contact's the
    ball's own."""
    surface = contacts.geometry.pair[:, 0] >= 0
    for side in (0, 1):
        bodies = contacts.geometry.pair[surface, side]
        np.add.at(bar.body_friction, bodies, 0.5 * bars.kinetic[surface])
        np.add.at(bar.body_restitution, bodies, 0.5 * bars.restitution[surface])
    slot = physical.bodies.ball_slot
    ball, partner = slot[contacts.nodes[~surface, 0]], slot[contacts.nodes[~surface, 1]]
    both = partner >= 0
    restitution, kinetic = bars.restitution[~surface], bars.kinetic[~surface]
    np.add.at(bar.ball_restitution, ball[both], 0.5 * restitution[both])
    np.add.at(bar.ball_restitution, partner[both], 0.5 * restitution[both])
    np.add.at(bar.particle_restitution, ball[~both], restitution[~both])
    # static and kinetic friction are one key: only the kinetic is differentiable
    np.add.at(bar.particle_friction, ball[~both], kinetic[~both])


def overlap_vjp(physical, response, x_bar, start_bar, bars):
    """Back through x' = x + sum c m^-1 shift, shift = S / W (overlap_shifts)."""
    contacts, mobility = response.contacts, response.mobility
    nodes, c, n, params = contacts.nodes, contacts.weights, contacts.normal, contacts.params
    shift_bar = scatter_vjp(c, nodes, physical.inv_mass, response.shift, x_bar, bars)
    moving = mobility > 0.0
    safe = np.where(moving, mobility, 1.0)
    s_bar = np.where(moving[:, None], shift_bar / safe[:, None], 0.0)
    bars.mobility[...] -= np.where(moving, dot(shift_bar, response.shift) / safe, 0.0)
    pushed = params[:, 3] * np.maximum(contacts.depth, 0.0)
    bars.depth[...] += np.where(contacts.depth > 0.0, params[:, 3] * dot(n, s_bar), 0.0)
    bars.normal[...] += pushed[:, None] * s_bar
    back = np.where(response.stuck & (params[:, 4] > 0.0), params[:, 4], 0.0)
    sliding = slid(contacts, response.x, response.start)
    along, s_n = dot(sliding, n), dot(n, s_bar)
    sliding_bar = -back[:, None] * (s_bar - s_n[:, None] * n)
    bars.normal[...] += back[:, None] * (along[:, None] * s_bar + s_n[:, None] * sliding)
    gather_vjp(c, nodes, response.x - response.start, sliding_bar, x_bar, bars)
    np.add.at(start_bar, nodes.ravel(), -(c[:, :, None] * sliding_bar[:, None, :])
              .reshape(-1, 3))


def impulse_passes_vjp(physical, contacts, mobility, passes, v_bar, bars):
    """Back through ``impulse_passes``, last pass first: v_bar in place, the contacts' and the
    masses' cotangents into ``bars``; returns the cotangent of the starting ``pushed``."""
    nodes, c, n, params = contacts.nodes, contacts.weights, contacts.normal, contacts.params
    restitution, kinetic = params[:, 0], params[:, 1]
    inv = physical.inv_mass
    count = len(c)
    total_bar, rubbed_bar, target_bar = np.zeros(count), np.zeros((count, 3)), np.zeros(count)
    safe = np.where(mobility > 0.0, mobility, 1.0)
    for sweep in reversed(range(len(passes))):
        this_pass = passes[sweep]
        active = this_pass.active
        impulse_bar = np.where(active[:, None], scatter_vjp(c, nodes, inv, this_pass.impulse,
                                                            v_bar, bars), 0.0)
        wanted_bar = impulse_bar + rubbed_bar
        previous_bar = np.where(active[:, None], -impulse_bar, rubbed_bar)
        j_bar = dot(impulse_bar, n)
        bars.normal[...] += this_pass.j[:, None] * impulse_bar
        w, total = this_pass.w, this_pass.total
        with np.errstate(divide="ignore", invalid="ignore"):
            size = np.sqrt(dot(w, w))
            along_w = dot(w, wanted_bar)
            slide = active & ~this_pass.stuck
            q = np.where(slide, kinetic * total / size, 1.0)
            w_bar = q[:, None] * wanted_bar - np.where(
                slide, kinetic * total * along_w / size ** 3, 0.0)[:, None] * w
            total_bar = total_bar + np.where(slide, kinetic * along_w / size, 0.0)
            bars.kinetic[...] += np.where(slide, total * along_w / size, 0.0)
        w_bar = np.where(active[:, None], w_bar, 0.0)
        previous_bar = previous_bar + w_bar
        tangential = this_pass.relative - this_pass.approach[:, None] * n
        tangential_bar = -w_bar / safe[:, None]
        bars.mobility[...] += np.where(active, dot(tangential, w_bar) / (safe * safe), 0.0)
        relative_bar = tangential_bar.copy()
        approach_bar = -dot(tangential_bar, n)
        bars.normal[...] -= this_pass.approach[:, None] * tangential_bar
        j_bar = np.where(active, j_bar + total_bar, 0.0)
        push = active & this_pass.pushed
        target_bar = target_bar + np.where(push, j_bar / safe, 0.0)
        approach_bar -= np.where(push, j_bar / safe, 0.0)
        bars.mobility[...] -= np.where(push, j_bar * this_pass.j / safe, 0.0)
        if sweep == 0:
            approach_bar += np.where(this_pass.approach < 0.0, -restitution * target_bar, 0.0)
            bars.restitution[...] -= np.minimum(this_pass.approach, 0.0) * target_bar
        relative_bar += approach_bar[:, None] * n
        bars.normal[...] += approach_bar[:, None] * this_pass.relative
        relative_bar = np.where(active[:, None], relative_bar, 0.0)
        gather_vjp(c, nodes, this_pass.v, relative_bar, v_bar, bars)
        rubbed_bar = previous_bar
    return total_bar


def mobility_vjp(physical, contacts, count, bars):
    """W = sum_i c_i^2 m_i^-1 n_i (the particles' contact counts n_i fixed)."""
    nodes, c = contacts.nodes, contacts.weights
    inv, count = physical.inv_mass[nodes], count[nodes]
    bars.weights[...] += 2.0 * c * inv * count * bars.mobility[:, None]
    np.add.at(bars.inv_mass, nodes.ravel(), (c * c * count * bars.mobility[:, None]).ravel())


def geometry_vjp(contacts, x, bars, x_bar):
    """The stencils' weights, normals and depths depend on their particles' positions:
    their cotangents go there through the complex step (module doc), kind by kind."""
    geometry = contacts.geometry
    for kind in (POINT, EDGE, BALL):
        rows = np.flatnonzero(geometry.kind == kind)
        if not len(rows):
            continue
        x4 = x[contacts.nodes[rows]].astype(complex)
        x4_bar = np.zeros((len(rows), 4, 3))
        for corner in range(4):
            for axis in range(3):
                x4[:, corner, axis] += 1j * STEP
                weights, normal, gap = geometry_of(geometry, rows, x4)
                x4[:, corner, axis] -= 1j * STEP
                x4_bar[:, corner, axis] = (
                    dot4(bars.weights[rows], weights.imag) + dot(bars.normal[rows], normal.imag)
                    - bars.depth[rows] * gap.imag) / STEP
        np.add.at(x_bar, contacts.nodes[rows].ravel(), x4_bar.reshape(-1, 3))


def dot4(u, w):
    return u[:, 0] * w[:, 0] + u[:, 1] * w[:, 1] + u[:, 2] * w[:, 2] + u[:, 3] * w[:, 3]


