"""A scene: the plain description a model is built from (bodies, terrains, gravity, integrator).

Scenes are plain dataclasses so that presets, TOML files and ``--set`` overrides all say the same
things. ``Scene.validate`` rejects what cannot be simulated before anything is built.
"""
from dataclasses import dataclass, field

import numpy as np

from .attachments import Attachment, validate_attachments
from .collision.shapes.settings import SurfaceContact
from .bodies.pins import check_follows
from .errors import is_finite, require
from .rivets import check_rivets
from .sampling import check_duration
from .scene_values import check_values
from .sizes import check_scene_size
from .wind import Wind


@dataclass
class ImplicitSettings:
    """Settings of the implicit integrators (implicit_euler); the explicit ones ignore them."""

    newton_iterations: int = 1        # linearized solves per step (1: Baraff-Witkin)
    cg_tolerance: float = 1e-5        # relative residual of each conjugate-gradient solve
    cg_max_iterations: int = 500
    preconditioner: str = "two_level"  # or "block_jacobi" (implicit/coarse.py)


@dataclass
class VbdSettings:
    """Settings of vertex block descent (integrators/vbd.py); the other integrators ignore them."""

    iterations: int = 10                    # sweeps over the particles a step
    contact_stiffness_ratio: float = 1000.0  # terrain contact stiffness over a particle's m/h^2
    friction_velocity: float = 0.001        # m/s: sliding slower than this is held (static)


@dataclass
class Scene:
    name: str = "custom"
    # tables each with a ``type`` (scene_values.TYPED_LISTS)
    bodies: list = field(default_factory=list, metadata={"typed_list": True})
    terrains: list = field(default_factory=list, metadata={"typed_list": True})
    integrator: str = "rk4"
    dt: float = 0.001                     # s
    duration: float = 8.0                 # s, how long `springsim run` simulates
    gravity: tuple = (0.0, -9.8, 0.0)     # m/s^2
    drag: float = 0.0                     # viscous drag coefficient, N s/m (f = -drag v)
    implicit: ImplicitSettings = field(default_factory=ImplicitSettings)
    vbd: VbdSettings = field(default_factory=VbdSettings)
    wind: Wind | None = None              # moving air (wind.py); unset: still air, no force
    # particles of one body bound to another's surface (attachments.py)
    attachments: list[Attachment] = field(default_factory=list)
    # forces of the kinds in terms/ that a scene adds by name (``[[forces]]``, a ``type`` each)
    forces: list = field(default_factory=list, metadata={"typed_list": True})

    def validate(self) -> None:
        from .integrators import integrator_names

        check_values(self)   # kinds and finite numbers, as a scene file's values are checked
        require(self.integrator in integrator_names(), "integrator", self.integrator,
                "must be one of " + ", ".join(integrator_names()))
        require(is_finite(self.dt) and self.dt > 0, "dt", self.dt, "must be a time step > 0 s")
        check_duration(self.duration)
        require(np.shape(self.gravity) == (3,) and is_finite(self.gravity), "gravity",
                self.gravity, "must be three finite numbers (m/s^2)")
        require(is_finite(self.drag) and self.drag >= 0, "drag", self.drag, "must be >= 0 N s/m")
        require(len(self.bodies) > 0, "bodies", self.bodies, "a scene needs at least one body")
        for i, body in enumerate(self.bodies):
            body.validate(f"bodies.{i}")
        for t, terrain in enumerate(self.terrains):
            terrain.validate(f"terrains.{t}")
        for i, body in enumerate(self.bodies):
            check_follows(getattr(body, "pins", ()), self.terrains, f"bodies.{i}.pins")
            check_rivets(getattr(body, "pins", ()), self.terrains, f"bodies.{i}.pins")
        validate_attachments(self.attachments, len(self.bodies))
        for f, force in enumerate(self.forces):
            force.validate(f"forces.{f}", len(self.bodies))
        self.validate_implicit_settings()
        if self.wind is not None:
            self.wind.validate("wind")
        check_scene_size(self)   # before anything is allocated
        for i, body in enumerate(self.bodies):
            if isinstance(body, SurfaceContact):
                body.validate_thickness(f"bodies.{i}")

    def validate_implicit_settings(self) -> None:
        """``[implicit]`` and ``[vbd]`` are checked whatever the integrator (a scene may switch
        to one that uses them): each integrator checks its section (its ``SECTION``) as it would
        use it."""
        from .integrators import REGISTRY

        for integrator in REGISTRY.values():
            if getattr(integrator, "OPTIONS", ()):
                integrator(**section_settings(self, integrator))


def section_settings(scene, integrator) -> dict:
    """The scene's settings for ``integrator`` (a registered class): those of its OPTIONS that
    its ``SECTION`` of the scene has."""
    section = getattr(scene, getattr(integrator, "SECTION", "implicit"))
    return {name: getattr(section, name) for name in getattr(integrator, "OPTIONS", ())
            if hasattr(section, name)}


def check_bodies_outside_terrains(model) -> None:
    """Reject a model whose bodies start inside a terrain (it would be shot out at once)."""
    for body_index, body in enumerate(model.bodies):
        x = model.initial_positions[body.start:body.stop]
        radii = model.arrays.terrain_offset[body.start:body.stop]
        for t, terrain in enumerate(model.terrains):
            # where the terrain is at time 0: the points looked up in its placed frame
            rotation, center, pivot = terrain.pose_at(0.0)
            placed = (x - center) @ rotation + pivot if terrain.motion is not None else x
            distance = terrain.signed_distance(placed, radii)
            deepest = int(np.argmin(distance))
            key, value = _placement(model.scene_bodies[body_index], f"bodies.{body_index}",
                                    deepest)
            require(distance[deepest] >= 0, key, value,
                    f"puts the body {-distance[deepest]:.3g} m inside terrains.{t} "
                    f"({type(terrain).__name__}); move the body or the terrain")


def _placement(spec, key: str, particle: int):
    """The key and value that place a body's ``particle``: a ball's own position for a Balls
    body (one particle per ball), else the body's position."""
    balls = getattr(spec, "balls", None)
    if balls is not None:
        return f"{key}.balls.{particle}.position", balls[particle].position
    return f"{key}.position", getattr(spec, "position", None)
