"""An attractor: every particle of the chosen bodies pulled toward a point by a spring and a
damper, F_i = k (p - x_i) - d v_i, as a scene asks for it in ``[[forces]]``::

    [[forces]]
    type = "attractor"
    point = [0.0, 1.0, 0.0]   # m
    stiffness = 5.0           # N/m on each particle
    damping = 0.1             # N s/m on each particle
    bodies = [0]              # body numbers; empty: every body

This file is the whole force: its scene table, its packed parameters, its kernels for every
integrator and its adjoint. Backward Euler's share of A = M - h dF/dv - h^2 dF/dx is
(h d + h^2 k) I on the particle's diagonal block, with -h^2 k v in the first iteration's
right-hand side. Its own parameters are not differentiable (the gradients follow it in the
positions and velocities, so every other parameter's gradient is exact through it).
"""
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .._jit import kernel
from ..errors import is_finite, require
from .adjoint import AdjointTerm
from .base import Term, register, scene_forces


@dataclass
class Attractor:
    """The scene's ``[[forces]]`` table of ``type = "attractor"``."""

    point: tuple = (0.0, 0.0, 0.0)   # m
    stiffness: float = 1.0           # N/m on each particle
    damping: float = 0.0             # N s/m on each particle
    bodies: list = field(default_factory=list)   # body numbers; empty: every body

    def validate(self, key: str, body_count: int) -> None:
        require(np.shape(self.point) == (3,) and is_finite(self.point), f"{key}.point",
                self.point, "must be three finite numbers (m)")
        require(is_finite(self.stiffness) and self.stiffness >= 0, f"{key}.stiffness",
                self.stiffness, "must be >= 0 N/m")
        require(is_finite(self.damping) and self.damping >= 0, f"{key}.damping",
                self.damping, "must be >= 0 N s/m")
        for body in self.bodies:
            require(isinstance(body, int) and 0 <= body < body_count, f"{key}.bodies", body,
                    f"must be body numbers from 0 to {body_count - 1}")


class AttractorTable(NamedTuple):
    """One row per attracted particle (a particle two attractors pull has two rows)."""

    particles: np.ndarray   # (N,) int64
    point: np.ndarray       # (N, 3) m
    stiffness: np.ndarray   # (N,) N/m
    damping: np.ndarray     # (N,) N s/m


@kernel
def add_attractor_forces(model, table, x, v, scale, out):
    """out[i] += scale_i (k (p - x_i) - d v_i) for every row (scale as terms/base.py says)."""
    for r in range(table.particles.shape[0]):
        i = table.particles[r]
        k, d = table.stiffness[r], table.damping[r]
        w = scale[i] if scale.shape[0] > 1 else scale[0]
        for c in range(3):
            out[i, c] += w * (k * (table.point[r, c] - x[i, c]) - d * v[i, c])


@kernel
def add_attractor_jacobian(model, table, layout, h, first, x_k, v_k, v, blocks, rhs):
    """(h d + h^2 k) I on each attracted particle's diagonal block; -h^2 k v in the first
    iteration's right-hand side."""
    slots = layout.diagonal.diagonal_slot
    for r in range(table.particles.shape[0]):
        i = table.particles[r]
        k, d = table.stiffness[r], table.damping[r]
        for c in range(3):
            blocks[slots[i], c, c] += h * d + h * h * k
            if first:
                rhs[i, c] -= h * h * k * v[i, c]


@register
class AttractorTerm(Term):
    name = "attractor"
    add_forces = add_attractor_forces
    add_step_end_forces = add_attractor_forces
    add_jacobian = add_attractor_jacobian
    adjoint = "springsim.terms.attractor:AttractorAdjoint"
    order = 40
    scene_type = "attractor"
    settings = Attractor

    @classmethod
    def pack(cls, scene, built, offsets) -> AttractorTable:
        rows = []
        for _, force in scene_forces(scene, Attractor):
            for body in force.bodies or range(len(built)):
                particles = np.arange(offsets[body], offsets[body + 1])
                rows.append((particles, force))
        count = sum(len(particles) for particles, _ in rows)
        table = AttractorTable(np.zeros(count, np.int64), np.zeros((count, 3)), np.zeros(count),
                               np.zeros(count))
        start = 0
        for particles, force in rows:
            stop = start + len(particles)
            table.particles[start:stop] = particles
            table.point[start:stop] = force.point
            table.stiffness[start:stop] = force.stiffness
            table.damping[start:stop] = force.damping
            start = stop
        return table


class AttractorAdjoint(AdjointTerm):
    """The attractor in NumPy: its force is linear in x and v, its blocks constant."""

    @classmethod
    def table(cls, physical) -> AttractorTable:
        return physical.term_tables[AttractorTerm.slot]

    @classmethod
    def acts(cls, physical) -> bool:
        return len(cls.table(physical).particles) > 0

    @classmethod
    def forces(cls, physical, x, v):
        table, out = cls.table(physical), np.zeros_like(x)
        rows = table.particles
        np.add.at(out, rows, table.stiffness[:, None] * (table.point - x[rows])
                  - table.damping[:, None] * v[rows])
        return out

    @classmethod
    def forces_vjp(cls, physical, x, v, g, x_bar, v_bar, bar) -> None:
        table = cls.table(physical)
        rows = table.particles
        np.add.at(x_bar, rows, -table.stiffness[:, None] * g[rows])
        np.add.at(v_bar, rows, -table.damping[:, None] * g[rows])

    @classmethod
    def first_iteration_rhs(cls, physical, v, h):
        table, out = cls.table(physical), np.zeros_like(v)
        np.add.at(out, table.particles, -h * h * table.stiffness[:, None] * v[table.particles])
        return out

    @classmethod
    def first_iteration_rhs_vjp(cls, physical, v, h, g, v_bar, bar) -> None:
        table = cls.table(physical)
        np.add.at(v_bar, table.particles,
                  -h * h * table.stiffness[:, None] * g[table.particles])

    @classmethod
    def diagonal_blocks(cls, physical, x, v, h):
        table, out = cls.table(physical), np.zeros((len(x), 3, 3))
        size = h * table.damping + h * h * table.stiffness
        np.add.at(out, table.particles, size[:, None, None] * np.eye(3))
        return out
