"""The model's physics as differentiable NumPy: forces, the implicit system's products, and their
vector-Jacobian products (VJPs).

Everything here is the same arithmetic as the kernels (forces.py, implicit/jacobian.py), in the
vectorized form of reference.py, with one parameter per spring (``Physical``): the gradient of
a group's ks is the sum over its springs, of a body's mass the sum over its particles, and so
on (parameters.py). For a spring (a, b) with d = x_a - x_b, L = |d|, l = d / L, w = v_a - v_b:

    force on a      f = -ks (L - r) l - kd (w . l) l                       (forces.py)
    stiffness       (dF_a/dx_a) u = -(along (l . u) l + across u),         (jacobian.py)
                    across = ks max(0, 1 - r / L), along = ks - across
    system block    C u = h kd (l . u) l + h^2 (along (l . u) l + across u)

Each VJP takes a cotangent g on the particles' outputs and, per spring, g_s = g_a - g_b, then
adds the cotangents of d (to x_a, minus to x_b), of w or u, and of ks, kd, r. A spring of zero
length has no force and no Jacobian (the kernels' rule), so it passes no gradient: never NaN.
"""
from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np

from . import kernels
from .body_contact import NO_BODIES, Bodies
from .contact import Planes, contact_accelerations, contact_accelerations_vjp
from .terms import external_forces, external_forces_vjp


# The contact keys that are parameters, each a Cotangents field, with the Bodies field it is
# (body_contact.py): the bodies' (B,), per contact body, and the balls' (N,), per ball
CONTACT_KEYS = {"body_friction": "friction", "body_restitution": "restitution",
                "ball_restitution": "ball_restitution",
                "particle_restitution": "particle_restitution",
                "particle_friction": "particle_friction"}


class Physical(NamedTuple):
    """The differentiable numbers of a model, one per spring or particle."""

    ks: np.ndarray        # (S,) N/m
    kd: np.ndarray        # (S,) N s/m
    rest: np.ndarray      # (S,) m
    mass: np.ndarray      # (P,) kg (a pinned particle's is its body's, though nothing uses it)
    drag: np.ndarray      # (P,) N s/m
    gravity: np.ndarray   # (3,) m/s^2
    free: np.ndarray      # (P,) bool: not pinned
    a: np.ndarray         # (S,) the springs' first particles
    b: np.ndarray         # (S,) and second
    friction: np.ndarray      # (T,) the terrains' Coulomb friction
    restitution: np.ndarray   # (T,) and restitution
    planes: Planes            # the terrains as contact needs them (contact.py)
    wind_settings: np.ndarray   # (6,) wind.pack_wind's: density, C_d, C_f, gusts, on
    wind_keys: np.ndarray       # (K, 4) the mean wind's keys: time, velocity
    wind_modes: np.ndarray      # (M, 8) the gust modes: direction, wave vector, frequency, phase
    wind_triangles: np.ndarray  # (T, 3) the triangles the wind pushes
    wind_weights: np.ndarray    # (T,) their weights (wind.quads_both_ways)
    clock: np.ndarray           # (2,) s: the step's start and the force evaluation's (clock.py)
    pin_particles: np.ndarray   # (Q,) the particles of pins on paths and of soft pins (pins.py)
    pin_motion: np.ndarray      # (Q,) each one's path: a row of the motion tables
    pin_placed: np.ndarray      # (Q, 3) m, where its path starts it
    pin_stiffness: np.ndarray   # (Q,) N/m, 0 for a hard pin
    pin_damping: np.ndarray     # (Q,) N s/m
    motion_info: np.ndarray     # the motions (motion.pack_motions)
    motion_keys: np.ndarray
    attachment_nodes: np.ndarray      # (A, 4) each binding's particles (attachments.py)
    attachment_weights: np.ndarray    # (A, 4) and weights, summing to zero
    attachment_stiffness: np.ndarray  # (A,) N/m, 0 for a hard binding
    attachment_damping: np.ndarray    # (A,) N s/m
    bodies: Bodies = NO_BODIES        # the contact arrays of body-body contact (body_contact.py)
    term_tables: tuple = ()           # the terms' own tables (terms/base.py), as the model's

    @classmethod
    def of(cls, model) -> "Physical":
        arrays = model.arrays
        group = arrays.spring_group
        clock = np.zeros(2)   # the moving terrains' shapes read it (contact.Planes)
        return cls(
            ks=arrays.group_ks[group].astype(float), kd=arrays.group_kd[group].astype(float),
            rest=arrays.rest_length.astype(float), mass=model.mass.astype(float),
            drag=arrays.drag.astype(float), gravity=arrays.gravity.astype(float),
            free=arrays.inv_mass > 0.0, a=arrays.springs[:, 0].astype(np.int64),
            b=arrays.springs[:, 1].astype(np.int64),
            friction=arrays.terrain_friction.astype(float),
            restitution=arrays.terrain_restitution.astype(float),
            planes=Planes.of(model, clock),
            wind_settings=arrays.wind_settings.astype(float),
            wind_keys=arrays.wind_keys.astype(float), wind_modes=arrays.wind_modes.astype(float),
            wind_triangles=arrays.wind_triangles.astype(np.int64).reshape(-1, 3),
            wind_weights=arrays.wind_weights.astype(float), clock=clock,
            pin_particles=arrays.pin_particles.astype(np.int64),
            pin_motion=arrays.pin_motion.astype(np.int64),
            pin_placed=arrays.pin_placed.astype(float),
            pin_stiffness=arrays.pin_stiffness.astype(float),
            pin_damping=arrays.pin_damping.astype(float), motion_info=arrays.motion_info,
            motion_keys=arrays.motion_keys,
            attachment_nodes=arrays.attachment_nodes.astype(np.int64),
            attachment_weights=arrays.attachment_weights.astype(float),
            attachment_stiffness=arrays.attachment_stiffness.astype(float),
            attachment_damping=arrays.attachment_damping.astype(float),
            bodies=Bodies.of(arrays), term_tables=arrays.term_tables)

    def differentiable(self, name: str) -> np.ndarray:
        """The numbers Cotangents.``name`` is the cotangent of: a field, or one of the contact
        keys kept in ``bodies`` (CONTACT_KEYS)."""
        if name in CONTACT_KEYS:
            return getattr(self.bodies, CONTACT_KEYS[name])
        return getattr(self, name)

    @property
    def inv_mass(self) -> np.ndarray:
        return np.where(self.free, 1.0 / self.mass, 0.0)

    @property
    def solve_mass(self) -> np.ndarray:
        """The implicit system's masses: a pinned particle's placeholder is 1 kg
        (jacobian.particle_mass), and its rows are filtered out."""
        return np.where(self.free, self.mass, 1.0)


@dataclass
class Cotangents:
    """Gradients of the loss, accumulated as the adjoint runs backwards (Physical's shapes)."""

    ks: np.ndarray
    kd: np.ndarray
    rest: np.ndarray
    mass: np.ndarray
    drag: np.ndarray
    gravity: np.ndarray
    friction: np.ndarray
    restitution: np.ndarray
    wind_settings: np.ndarray
    wind_keys: np.ndarray
    wind_modes: np.ndarray
    pin_stiffness: np.ndarray
    pin_damping: np.ndarray
    attachment_stiffness: np.ndarray
    attachment_damping: np.ndarray
    body_friction: np.ndarray
    body_restitution: np.ndarray
    ball_restitution: np.ndarray
    particle_restitution: np.ndarray
    particle_friction: np.ndarray

    @classmethod
    def zeros(cls, physical: Physical) -> "Cotangents":
        return cls(*(np.zeros_like(physical.differentiable(f.name), dtype=float)
                     for f in fields(cls)))


class Springs(NamedTuple):
    """Per-spring geometry at some positions: d, L, l (zero where L = 0) and 1 / L (or 0)."""

    d: np.ndarray
    length: np.ndarray
    unit: np.ndarray
    inverse: np.ndarray


def geometry(physical: Physical, x: np.ndarray) -> Springs:
    d = x[physical.a] - x[physical.b]
    length = np.sqrt(np.einsum("ij,ij->i", d, d))
    inverse = np.divide(1.0, length, out=np.zeros_like(length), where=length > 0.0)
    return Springs(d, length, d * inverse[:, None], inverse)


def per_spring(physical: Physical, g: np.ndarray) -> np.ndarray:
    return g[physical.a] - g[physical.b]


def scatter(physical: Physical, values: np.ndarray, out: np.ndarray) -> None:
    """out_a += values, out_b -= values (per spring), deterministically (np.add.at is ordered)."""
    np.add.at(out, physical.a, values)
    np.add.at(out, physical.b, -values)


def dot(u: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", u, w)


def projection_vjp(springs: Springs, w: np.ndarray, g: np.ndarray) -> np.ndarray:
    """The cotangent of d for P(d) = (l . w) l, w fixed, and cotangent g:
    (I - l l^T) / L [(g . l) w + (l . w) g]."""
    l = springs.unit
    gl, wl = dot(g, l), dot(w, l)
    inside = gl[:, None] * w + wl[:, None] * g
    return (inside - dot(inside, l)[:, None] * l) * springs.inverse[:, None]


# --- spring and damper forces -------------------------------------------------------------------

def reference_spring_forces(physical: Physical, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    springs = geometry(physical, x)
    w = per_spring(physical, v)
    factor = -physical.ks * (springs.length - physical.rest) - physical.kd * dot(w, springs.unit)
    force = np.zeros_like(x)
    scatter(physical, factor[:, None] * springs.unit, force)
    return force


def reference_spring_forces_vjp(physical: Physical, x, v, g, x_bar, v_bar,
                                bar: Cotangents) -> None:
    """Add g . d(spring_forces)/d(x, v, ks, kd, r) into x_bar, v_bar and bar."""
    springs = geometry(physical, x)
    l, length = springs.unit, springs.length
    w, gs = per_spring(physical, v), per_spring(physical, g)
    gl, wl = dot(gs, l), dot(w, l)
    stretch = np.where(length > 0.0, length - physical.rest, 0.0)
    # d[(L - r) l] = l l^T dd + (L - r) / L (I - l l^T) dd
    across = (gs - gl[:, None] * l) * (stretch * springs.inverse)[:, None]
    d_bar = -physical.ks[:, None] * (gl[:, None] * l + across)
    d_bar -= physical.kd[:, None] * projection_vjp(springs, w, gs)
    scatter(physical, d_bar, x_bar)
    scatter(physical, -(physical.kd * gl)[:, None] * l, v_bar)
    bar.ks -= stretch * gl
    bar.kd -= wl * gl
    bar.rest += physical.ks * gl * (length > 0.0)


# --- accelerations (the explicit methods' derivative) -------------------------------------------

def accelerations(physical: Physical, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """dv/dt before contact: forces.free_accelerations (the wind at physical.clock's time)."""
    w = physical.inv_mass
    force = spring_forces(physical, x, v)
    return (w[:, None] * (force - physical.drag[:, None] * v)
            + np.where(physical.free[:, None], physical.gravity, 0.0)
            + w[:, None] * external_forces(physical, x, v))


def accelerations_vjp(physical: Physical, x, v, g, x_bar, v_bar, bar: Cotangents) -> None:
    """Add g . d(accelerations)/d(everything) into x_bar, v_bar and bar."""
    w = physical.inv_mass
    force = spring_forces(physical, x, v)
    net = force - physical.drag[:, None] * v + external_forces(physical, x, v)
    free = physical.free
    bar.gravity += g[free].sum(axis=0)
    bar.mass -= np.where(free, w * w * dot(g, net), 0.0)
    bar.drag -= w * dot(g, v)
    v_bar -= (w * physical.drag)[:, None] * g
    spring_forces_vjp(physical, x, v, w[:, None] * g, x_bar, v_bar, bar)
    external_forces_vjp(physical, x, v, w[:, None] * g, x_bar, v_bar, bar)


def step_accelerations(physical: Physical, x, v, h):
    """(dv/dt with terrain contact, what contact did): forces.accelerations at step h."""
    a = accelerations(physical, x, v)
    if not len(physical.friction):
        return a, []
    return contact_accelerations(physical, x, v, h, a)


def step_accelerations_vjp(physical: Physical, x, v, h, touches, g, x_bar, v_bar,
                           bar: Cotangents) -> None:
    """Add g . d(step_accelerations)/d(everything) into x_bar, v_bar and bar; ``touches`` is
    what step_accelerations returned second for the same (x, v)."""
    if touches:
        g = contact_accelerations_vjp(physical, h, touches, g, x_bar, v_bar, bar)
    accelerations_vjp(physical, x, v, g, x_bar, v_bar, bar)


# --- the implicit system (implicit/jacobian.py) -------------------------------------------------

def stiffness_coefficients(physical: Physical, springs: Springs):
    """(along, across, d across / dL, d across / dr) with the compressive part clamped to 0."""
    stretched = springs.length > physical.rest
    ratio = np.where(stretched, 1.0 - physical.rest * springs.inverse, 0.0)
    across = physical.ks * ratio
    return (physical.ks - across, across,
            np.where(stretched, physical.ks * physical.rest * springs.inverse ** 2, 0.0),
            np.where(stretched, -physical.ks * springs.inverse, 0.0), ratio)


def reference_stiffness_product(physical: Physical, x: np.ndarray,
                                u: np.ndarray) -> np.ndarray:
    """(dF/dx) u at x, clamped as the matrix is (jacobian.add_stiffness_product)."""
    springs = geometry(physical, x)
    along, across, _, _, _ = stiffness_coefficients(physical, springs)
    us = per_spring(physical, u)
    l = springs.unit
    values = -(along * dot(l, us))[:, None] * l - across[:, None] * us
    out = np.zeros_like(x)
    scatter(physical, values * (springs.length > 0.0)[:, None], out)
    return out


def reference_stiffness_product_vjp(physical: Physical, x, u, g, x_bar, u_bar,
                                    bar: Cotangents) -> None:
    """Add g . d[(dF/dx)(x) u]/d(x, u, ks, r) into x_bar, u_bar and bar."""
    springs = geometry(physical, x)
    along, across, across_dl, across_dr, ratio = stiffness_coefficients(physical, springs)
    l = springs.unit
    us, gs = per_spring(physical, u), per_spring(physical, g)
    lu, lg = dot(l, us), dot(l, gs)
    # out_a = -(ks P(u) + across (u - P(u))), P(u) = (l . u) l
    sideways = dot(gs, us) - lu * lg    # g . (u - P(u))
    d_bar = -(along[:, None] * projection_vjp(springs, us, gs)
              + (across_dl * sideways)[:, None] * l)
    scatter(physical, d_bar, x_bar)
    scatter(physical, -(physical.ks * lg)[:, None] * l - across[:, None] * (gs - lg[:, None] * l),
            u_bar)
    real = springs.length > 0.0
    bar.ks -= np.where(real, lu * lg + ratio * sideways, 0.0)
    bar.rest -= np.where(real, across_dr * sideways, 0.0)


def system_product(physical: Physical, x: np.ndarray, u: np.ndarray, h: float) -> np.ndarray:
    """A u, A = M + h (drag) - h dF/dv - h^2 dF/dx at x (implicit_euler's matrix)."""
    springs = geometry(physical, x)
    along, across, _, _, _ = stiffness_coefficients(physical, springs)
    l = springs.unit
    us = per_spring(physical, u)
    p = h * physical.kd + h * h * along
    values = (p * dot(l, us))[:, None] * l + (h * h * across)[:, None] * us
    out = (physical.solve_mass + h * physical.drag)[:, None] * u
    scatter(physical, values * (springs.length > 0.0)[:, None], out)
    return out


def reference_system_product_vjp(physical: Physical, x, u, g, h, x_bar,
                                 bar: Cotangents) -> None:
    """Add g . d(A(x) u)/d(x, ks, kd, r, mass, drag), u held fixed, into x_bar and bar."""
    bar.mass += np.where(physical.free, dot(g, u), 0.0)
    bar.drag += h * dot(g, u)
    springs = geometry(physical, x)
    l = springs.unit
    us, gs = per_spring(physical, u), per_spring(physical, g)
    real = springs.length > 0.0
    bar.kd += np.where(real, h * dot(l, us) * dot(l, gs), 0.0)
    # the stiffness part is -h^2 (dF/dx) u
    u_scratch = np.zeros_like(u)
    stiffness_product_vjp(physical, x, u, -h * h * g, x_bar, u_scratch, bar)
    d_bar = h * physical.kd[:, None] * projection_vjp(springs, us, gs)
    scatter(physical, d_bar, x_bar)


# --- the same through the kernels (kernels.py): what the adjoints call --------------------------

def spring_forces(physical: Physical, x, v) -> np.ndarray:
    """reference_spring_forces, in a kernel."""
    out = np.zeros_like(x)
    kernels.add_spring_forces(physical.a, physical.b, physical.ks, physical.kd, physical.rest,
                              np.ascontiguousarray(x), np.ascontiguousarray(v), out)
    return out


def springs_of(physical: Physical) -> "kernels.Springs":
    """The model's springs as the kernels take them."""
    return kernels.Springs(physical.a, physical.b, physical.ks, physical.kd, physical.rest)


def spring_bars(bar: "Cotangents") -> "kernels.SpringBars":
    """The springs' parameter cotangents of ``bar``, as the kernels add to them."""
    return kernels.SpringBars(bar.ks, bar.kd, bar.rest)


def spring_forces_vjp(physical: Physical, x, v, g, x_bar, v_bar, bar: Cotangents) -> None:
    """reference_spring_forces_vjp, in a kernel."""
    kernels.add_spring_forces_vjp(springs_of(physical), x, v, np.ascontiguousarray(g), x_bar,
                                  v_bar, spring_bars(bar))


def stiffness_product(physical: Physical, x, u) -> np.ndarray:
    """reference_stiffness_product, in a kernel."""
    out = np.zeros_like(x)
    kernels.add_stiffness_product(physical.a, physical.b, physical.ks, physical.rest, x,
                                  np.ascontiguousarray(u), 1.0, out)
    return out


def stiffness_product_vjp(physical: Physical, x, u, g, x_bar, u_bar, bar: Cotangents) -> None:
    """reference_stiffness_product_vjp, in a kernel."""
    kernels.add_system_springs_vjp(springs_of(physical), x, np.ascontiguousarray(u),
                                   np.ascontiguousarray(g), kernels.Scales(1.0, 0.0), x_bar,
                                   u_bar, spring_bars(bar))


def system_product_vjp(physical: Physical, x, u, g, h, x_bar, bar: Cotangents) -> None:
    """reference_system_product_vjp, the springs in a kernel."""
    bar.mass += np.where(physical.free, dot(g, u), 0.0)
    bar.drag += h * dot(g, u)
    kernels.add_system_springs_vjp(springs_of(physical), x, np.ascontiguousarray(u),
                                   np.ascontiguousarray(g), kernels.Scales(-h * h, h), x_bar,
                                   np.empty((0, 3)), spring_bars(bar))
