"""Attachments: particles of one body bound to the surface of another (a cape sewn to a jelly,
two cloth panels stitched along an edge, a ball hung on a cloth).

A scene's ``[[attachments]]`` each choose particles of ``body`` as a pin does (bodies/pins.py:
``particles = [...]`` or ``region = {min, max}``) and bind every one to the nearest triangle of
body ``to``'s contact surface (collision/shapes/surfaces.py), found once where the bodies start:
the closest point's barycentric weights (w_a, w_b, w_c) are kept for the whole run. Every chosen
particle must start within ``distance`` (m) of that surface.

Each binding is a stencil, as a contact is (docs/architecture.md): four particles (p, a, b, c)
and weights c = (1, -w_a, -w_b, -w_c) that sum to zero, so that d = sum_i c_i x_i runs from the
triangle's point to the particle. A force along it acts on particle i with weight c_i, and the
two bodies exchange momentum without gaining any:

- soft (``stiffness`` k, N/m, and ``damping`` kd, N s/m): a spring of zero rest length,
  f_i = -c_i (k d + kd d'), in every stage's forces (``add_attachment_forces``) and, with its
  derivative (k c_i c_j I off the diagonal too), inside backward Euler's solve
  (``add_attachment_jacobian``; implicit/pattern.py stores the blocks it couples);
- hard (no ``stiffness``): after every step, under every integrator (integrators/_steps.collide),
  and on the starting state (model.build_model), ``hold_attachments`` moves the particle and the
  triangle's corners together, each by its inverse mass, until d = 0, and their velocities until
  d' = 0: the one-constraint projection of position-based dynamics,
      x_i -= c_i m_i^-1 d / sum_j c_j^2 m_j^-1,
  which keeps the pair's linear momentum (sum_i m_i dx_i = -sum_i c_i d / ... = 0) and angular
  momentum (every correction is along d, through the triangle's point). A particle held by
  several bindings (a stitched seam shares the triangles' corners) is projected sweep after
  sweep, in a fixed order, until no binding is off by more than HOLD_TOLERANCE.

A pinned particle (no inverse mass) takes no share: a particle bound to a pinned cloth hangs
from it.
"""
import math
from dataclasses import dataclass, field

import numpy as np

from ._jit import kernel
from .bodies.pins import Region, check_choice, chosen_particles, describe, start_hint
from .geometry.closest_points import closest_on_triangle
from .collision.shapes.surfaces import collision_triangles
from .errors import SceneError, is_finite, require

HOLD_TOLERANCE = 1e-13   # m (positions) and m/s (velocities): a hard binding this close is held
HOLD_SWEEPS = 200        # the most projection sweeps a step takes (bindings that share particles)


@dataclass
class Attachment:
    """Particles of ``body`` bound to the surface of body ``to`` (both numbers of the scene's
    bodies, from 0); the particles are chosen in exactly one of ``particles``, ``region``."""

    body: int                                       # the body whose particles are bound
    to: int                                         # the body whose surface receives them
    particles: list = field(default_factory=list)   # particle numbers of ``body``
    region: Region | None = None                    # a box at the start (m)
    distance: float = 0.05                          # m: the farthest a particle may start
    stiffness: float | None = None                  # N/m: a soft binding; unset: hard
    damping: float = 0.0                            # N s/m, a soft binding's damper

    def validate(self, key: str, body_count: int) -> None:
        """The keys on their own and against the scene's number of bodies (the particles and
        the surface are checked when the model is built: ``pack_attachments``)."""
        for name in ("body", "to"):
            value = getattr(self, name)
            whole = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
            require(whole and 0 <= value < body_count, f"{key}.{name}", value,
                    f"must be a body number in [0, {body_count - 1}] (the scene has "
                    f"{body_count} bodies)")
        require(self.to != self.body, f"{key}.to", self.to,
                f"must be another body than body = {self.body}")
        require(is_finite(self.distance) and self.distance > 0, f"{key}.distance",
                self.distance, "must be > 0 m")
        if self.stiffness is not None:
            require(is_finite(self.stiffness) and self.stiffness > 0, f"{key}.stiffness",
                    self.stiffness, "must be > 0 N/m (leave it out for a hard attachment)")
        require(is_finite(self.damping) and self.damping >= 0, f"{key}.damping", self.damping,
                "must be >= 0 N s/m")
        check_choice(self, key, "an attachment", ("particles", "region"))

    @property
    def group(self) -> str:
        """No named groups (chosen_particles asks): an attachment's body may be of any kind."""
        return ""


def validate_attachments(attachments, body_count: int) -> None:
    for a, attachment in enumerate(attachments):
        attachment.validate(f"attachments.{a}", body_count)


def pack_attachments(attachments, built, offsets) -> dict:
    """The model's arrays of the attachments (model.ModelArrays documents them): one row per
    bound particle, its stencil's particles and weights, its stiffness and damping (0: hard).
    A choice that chooses no particle, a ``to`` body without surface triangles, or a particle
    farther than ``distance`` from them is a SceneError naming the key."""
    nodes, weights, stiffness, damping = [], [], [], []
    for a, attachment in enumerate(attachments):
        key = f"attachments.{a}"
        own, other = built[attachment.body], built[attachment.to]
        chosen = chosen_particles(attachment, own.positions, {}, key)
        require(chosen.size > 0, key, describe(attachment),
                "chooses no particle; " + start_hint(own.positions))
        triangles = collision_triangles(other)
        require(len(triangles) > 0, f"{key}.to", attachment.to,
                "names a body without surface triangles (a body of balls has none); bind "
                "its particles the other way round")
        corners = np.ascontiguousarray(other.positions[triangles], float)
        row, bary, gap = nearest_triangles(np.ascontiguousarray(own.positions[chosen], float),
                                           corners)
        farthest = int(np.argmax(gap))
        if gap[farthest] > attachment.distance:
            raise SceneError(f"{key}.distance", attachment.distance,
                             f"particle {int(chosen[farthest])} of bodies.{attachment.body} "
                             f"starts {gap[farthest]:.4g} m from the surface of "
                             f"bodies.{attachment.to}; every chosen particle must start within "
                             "distance (m) of it")
        start, start_to = int(offsets[attachment.body]), int(offsets[attachment.to])
        nodes.append(np.column_stack([chosen + start, triangles[row] + start_to]))
        weights.append(np.column_stack([np.ones(len(chosen)), -bary]))
        soft = attachment.stiffness is not None
        stiffness.append(np.full(len(chosen), float(attachment.stiffness) if soft else 0.0))
        damping.append(np.full(len(chosen), float(attachment.damping) if soft else 0.0))
    return {"attachment_nodes": np.concatenate([np.empty((0, 4), np.int64)] + nodes)
            .astype(np.int64),
            "attachment_weights": np.concatenate([np.empty((0, 4))] + weights),
            "attachment_stiffness": np.concatenate([np.empty(0)] + stiffness),
            "attachment_damping": np.concatenate([np.empty(0)] + damping)}


def nearest_triangles(points, corners):
    """For each point (n, 3): the row of its nearest triangle of ``corners`` (T, 3, 3), the
    closest point's barycentric weights (n, 3) and its distance (m). libigl's AABB tree finds
    the triangle, since a search of every pair grows as points times triangles
    (benchmarks/attachments.py); the weights come from the contact code's closest_on_triangle,
    so that the binding holds the point contact would find."""
    import igl

    vertices = corners.reshape(-1, 3)
    faces = np.arange(len(vertices), dtype=np.int64).reshape(-1, 3)
    _, row, _ = igl.point_mesh_squared_distance(points, vertices, faces)
    row = np.asarray(row, np.int64)
    weights, gap = closest_points_on(points, corners, row)
    return row, weights, gap


@kernel
def closest_points_on(points, corners, row):
    """The barycentric weights (n, 3) of each point's closest point on triangle row[i] of
    ``corners``, and its distance (m)."""
    count = points.shape[0]
    weights, gap = np.zeros((count, 3)), np.zeros(count)
    for i in range(count):
        p, triangle = points[i], corners[row[i]]
        weights[i, 0], weights[i, 1], weights[i, 2] = closest_on_triangle(p, triangle)
        d = 0.0
        for c in range(3):
            q = (weights[i, 0] * triangle[0, c] + weights[i, 1] * triangle[1, c]
                 + weights[i, 2] * triangle[2, c])
            d += (p[c] - q) ** 2
        gap[i] = math.sqrt(d)
    return weights, gap


@kernel
def stencil_gap(nodes, weights, a, x, c):
    """Component c of d = sum_i c_i x_i for binding a (x positions or velocities)."""
    return (weights[a, 0] * x[nodes[a, 0], c] + weights[a, 1] * x[nodes[a, 1], c]
            + weights[a, 2] * x[nodes[a, 2], c] + weights[a, 3] * x[nodes[a, 3], c])


@kernel
def add_attachment_forces(model, x, v, scale, out):
    """out[i] += scale_i c_i f, f = -(k d + kd d') for every soft binding (module doc):
    ``scale`` per particle (the inverse masses, for accelerations) or, with one entry, for all
    (the step h, for backward Euler's impulses)."""
    nodes, weights = model.attachment_nodes, model.attachment_weights
    for a in range(nodes.shape[0]):
        k, kd = model.attachment_stiffness[a], model.attachment_damping[a]
        if k == 0.0:
            continue   # hard: held by hold_attachments
        for c in range(3):
            f = -(k * stencil_gap(nodes, weights, a, x, c)
                  + kd * stencil_gap(nodes, weights, a, v, c))
            for j in range(4):
                i = nodes[a, j]
                w = scale[i] if scale.shape[0] > 1 else scale[0]
                out[i, c] += w * weights[a, j] * f


@kernel
def add_attachment_jacobian(model, slots, h, first, v, blocks, rhs):
    """Backward Euler's soft bindings: A gains (h kd + h^2 k) c_i c_j I in block (i, j) of every
    two of a binding's particles (-h dF/dv - h^2 dF/dx; ``slots`` (A, 4, 4) are those blocks'
    places: implicit/pattern.py), and the first iteration's right-hand side its
    h^2 dF/dx v = -h^2 k c_i d'."""
    nodes, weights = model.attachment_nodes, model.attachment_weights
    for a in range(nodes.shape[0]):
        k, kd = model.attachment_stiffness[a], model.attachment_damping[a]
        if k == 0.0:
            continue
        coefficient = h * kd + h * h * k
        for i in range(4):
            for j in range(4):
                value = coefficient * weights[a, i] * weights[a, j]
                for c in range(3):
                    blocks[slots[a, i, j], c, c] += value
        if first:
            for c in range(3):
                along = h * h * k * stencil_gap(nodes, weights, a, v, c)
                for j in range(4):
                    rhs[nodes[a, j], c] -= weights[a, j] * along


@kernel
def hold_attachments(model, x, v):
    """Every hard binding exactly on its triangle's point, moving with it (module doc): x, then
    v, projected sweep by sweep. Returns the sweeps taken on x."""
    if model.attachment_nodes.shape[0] == 0:
        return 0
    sweeps = project_bindings(model, x)
    project_bindings(model, v)
    return sweeps


@kernel
def project_bindings(model, x):
    """Project every hard binding's d = sum_i c_i x_i to zero, weighting by inverse mass, until
    a sweep finds none off by more than HOLD_TOLERANCE (HOLD_SWEEPS at most)."""
    nodes, weights, inv_mass = model.attachment_nodes, model.attachment_weights, model.inv_mass
    for sweep in range(HOLD_SWEEPS):
        worst = 0.0
        for a in range(nodes.shape[0]):
            if model.attachment_stiffness[a] > 0.0:
                continue   # soft: a spring (add_attachment_forces)
            share = 0.0
            for j in range(4):
                share += weights[a, j] * weights[a, j] * inv_mass[nodes[a, j]]
            if share == 0.0:
                continue   # all of it pinned: nothing can move
            d0 = stencil_gap(nodes, weights, a, x, 0)
            d1 = stencil_gap(nodes, weights, a, x, 1)
            d2 = stencil_gap(nodes, weights, a, x, 2)
            worst = max(worst, abs(d0), abs(d1), abs(d2))
            for j in range(4):
                i = nodes[a, j]
                move = weights[a, j] * inv_mass[i] / share
                x[i, 0] -= move * d0
                x[i, 1] -= move * d1
                x[i, 2] -= move * d2
        if worst <= HOLD_TOLERANCE:
            return sweep + 1
    return HOLD_SWEEPS
