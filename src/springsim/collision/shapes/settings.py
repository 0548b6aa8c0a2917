"""How a body's surface touches other bodies and itself: the keys every deformable body has.

A body with a surface (cube, cloth, mesh body) collides with every other such body, by default:
each of its surface particles against the other body's surface triangles (the collision
pipeline: springsim.collision). ``thickness`` (m) is how far apart the surfaces are kept: a
particle and a triangle of two bodies are kept the mean of their thicknesses apart, those of one
self-colliding body its thickness. A pair's friction and restitution are the means of the two
bodies' values. Balls are in the same contact pass but touch every particle (as a point), with
their own keys (balls.py).
"""
from dataclasses import dataclass

from ...errors import is_finite, require


MAX_THICKNESS = 1.0   # m: beyond, contact would act across whole bodies (and search far)


@dataclass
class SurfaceContact:
    """Contact keys; lengths in m. Each body kind sets its own defaults (docs: README)."""

    thickness: float | None = 0.05   # kept between surfaces (m); None: the kind's default
                                     # for the body (default_thickness)
    self_collision: bool = False     # the body's surface also pushes on itself
    friction: float = 0.4            # kinetic Coulomb coefficient against other surfaces
    static_friction: float = 0.5     # a contact sticks while |f_T| <= static_friction |f_N|
    restitution: float = 0.0         # share of the approach speed given back by a contact

    def contact_thickness(self) -> float:
        """The thickness in use (m): the key, or where it is unset the body's default."""
        return self.default_thickness() if self.thickness is None else self.thickness

    def default_thickness(self) -> float:
        """The thickness of a body whose key is unset (m); a kind may scale it with the body."""
        return 0.05

    def validate_surface_contact(self, key: str) -> None:
        """Check the keys on their own (``validate_thickness`` checks them against the body)."""
        require(self.thickness is None
                or (is_finite(self.thickness) and 0 < self.thickness <= MAX_THICKNESS),
                f"{key}.thickness", self.thickness, f"must be in (0, {MAX_THICKNESS:g}] m")
        require(isinstance(self.self_collision, bool), f"{key}.self_collision",
                self.self_collision, "must be true or false")
        for name in ("friction", "static_friction"):
            value = getattr(self, name)
            require(is_finite(value) and 0 <= value <= 10, f"{key}.{name}", value,
                    "must be in [0, 10]")
        require(self.static_friction >= self.friction, f"{key}.static_friction",
                self.static_friction, f"must be >= friction ({self.friction:g})")
        require(is_finite(self.restitution) and 0 <= self.restitution <= 1,
                f"{key}.restitution", self.restitution, "must be in [0, 1]")

    def validate_thickness(self, key: str) -> None:
        """A self-colliding body's thickness below half its particle spacing (the body's
        ``surface_spacing()``, m): neighbours would start in contact. Checked after the scene's
        size, so that a body too large to build is refused for its size."""
        if self.self_collision:
            spacing = self.surface_spacing()
            require(self.contact_thickness() < 0.5 * spacing, f"{key}.thickness",
                    self.contact_thickness(),
                    f"must be below half the particle spacing ({0.5 * spacing:.4g} m) when "
                    "self_collision is on: neighbours would start in contact")
