"""Balls: rigid spheres, each one particle with a contact radius and the ball's mass.

A ball has no rotation (the reference has none), so the integrators advance it like any particle,
and terrain contact already accounts for its radius. Balls collide with each other and with every
other particle (cloth and cube particles are points); the body-body contact pass
(collision/pipeline.py) resolves those contacts once per step with the parameters held here.
Defaults are the reference's scene 2: four balls of radius 0.5 m and mass 125 kg (density
1000 r^3) at (+-0.75, 1, +-0.75), at rest; ball-ball restitution 0.8, ball-particle restitution
0.0 and friction 0.03, position correction 0.15 of the penetration, viscous drag 3.4e-4 N s/m.
"""
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields

import numpy as np

from ..errors import is_finite, require
from . import BuiltBody
from .cloth import REFERENCE_DRAG

# What the model needs of a body's balls to resolve their collisions, with the reference's values.
COLLISION_DEFAULTS = {"ball_restitution": 0.8, "particle_restitution": 0.0,
                      "particle_friction": 0.03, "position_correction": 0.15}


@dataclass
class Ball:
    """One ball: position and velocity of its centre (m, m/s), radius (m), mass (kg)."""

    position: tuple = (0.0, 1.0, 0.0)
    velocity: tuple = (0.0, 0.0, 0.0)
    radius: float = 0.5
    mass: float = 125.0


def reference_balls() -> list:
    return [Ball(position=(x, 1.0, z)) for x in (-0.75, 0.75) for z in (-0.75, 0.75)]


@dataclass
class Balls:
    """A set of balls and how they collide (restitutions in [0, 1], friction >= 0,
    position correction in [0, 1]: the share of a penetration removed per step)."""

    balls: list = field(default_factory=reference_balls)  # Ball, or tables with Ball's keys
    ball_restitution: float = COLLISION_DEFAULTS["ball_restitution"]
    particle_restitution: float = COLLISION_DEFAULTS["particle_restitution"]
    particle_friction: float = COLLISION_DEFAULTS["particle_friction"]
    position_correction: float = COLLISION_DEFAULTS["position_correction"]
    drag: float = REFERENCE_DRAG           # added to the scene's drag on every ball

    def validate(self, key: str) -> None:
        require(isinstance(self.balls, (list, tuple)) and len(self.balls) > 0, f"{key}.balls",
                self.balls, "must be a non-empty list of balls (position, velocity, radius, mass)")
        for b, ball in enumerate(self.balls):
            _validate_ball(as_ball(ball, f"{key}.balls.{b}"), f"{key}.balls.{b}")
        for name in ("ball_restitution", "particle_restitution", "position_correction"):
            value = getattr(self, name)
            require(is_finite(value) and 0 <= value <= 1, f"{key}.{name}", value,
                    "must lie in [0, 1]")
        for name, unit in (("particle_friction", ""), ("drag", " N s/m")):
            value = getattr(self, name)
            require(is_finite(value) and value >= 0, f"{key}.{name}", value, f"must be >= 0{unit}")

    def counts(self) -> tuple[int, int]:
        """Particles (one per ball) and springs (none)."""
        return len(self.balls), 0

    def build(self) -> BuiltBody:
        balls = [as_ball(ball, "balls") for ball in self.balls]
        count = len(balls)
        return BuiltBody(
            positions=np.array([ball.position for ball in balls], float).reshape(count, 3),
            velocities=np.array([ball.velocity for ball in balls], float).reshape(count, 3),
            masses=np.array([ball.mass for ball in balls], float),
            pinned=np.zeros(count, bool),
            springs=np.empty((0, 2), np.int32),
            spring_kind=np.empty(0, np.int8),
            spring_parameters={},
            radii=np.array([ball.radius for ball in balls], float),
        )


def as_ball(ball, key: str) -> Ball:
    """A Ball from a Ball or from a table (a TOML file's) with Ball's keys."""
    if isinstance(ball, Ball):
        return ball
    names = [f.name for f in fields(Ball)]
    require(isinstance(ball, Mapping), key, ball, "must be a ball: a table with keys "
            + ", ".join(names))
    for name in ball:
        require(name in names, f"{key}.{name}", ball[name],
                "is not a ball setting; a ball has " + ", ".join(names))
    return Ball(**{**asdict(Ball()), **ball})


def collision_parameters(spec) -> dict:
    """The collision settings of a body spec (a Balls body's own, the reference's otherwise)."""
    return {name: float(getattr(spec, name, default))
            for name, default in COLLISION_DEFAULTS.items()}


def _validate_ball(ball: Ball, key: str) -> None:
    for name in ("position", "velocity"):
        value = getattr(ball, name)
        require(np.shape(value) == (3,) and is_finite(value), f"{key}.{name}", value,
                "must be three finite numbers")
    require(is_finite(ball.radius) and ball.radius > 0, f"{key}.radius", ball.radius,
            "must be > 0 m")
    require(is_finite(ball.mass) and ball.mass > 0, f"{key}.mass", ball.mass, "must be > 0 kg")
