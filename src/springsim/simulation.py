"""Simulation: a model, a state and an integrator, advanced in whole steps."""
import math

import numpy as np

from .energy import energies
from .errors import SimulationDiverged, require
from .integrators import get_integrator
from .model import build_model
from .scene import check_bodies_outside_terrains
from .state import State
from .surfaces import body_surface


def integrator_settings(scene, overrides: dict) -> dict:
    """The scene's settings for its integrator (those it declares in OPTIONS), then overrides."""
    from .integrators import REGISTRY

    accepted = getattr(REGISTRY.get(scene.integrator), "OPTIONS", ())
    settings = {name: getattr(scene.implicit, name) for name in accepted
                if hasattr(scene.implicit, name)}
    return {**settings, **overrides}


class Simulation:
    """Simulate ``scene`` with ``integrator`` (a registered name) and time step ``dt`` (s).

    Both default to the scene's own. ``integrator_options`` go to the integrator and win over the
    scene's ``implicit`` settings (for example ``newton_iterations=2`` for implicit_euler).
    """

    def __init__(self, scene, integrator: str | None = None, dt: float | None = None,
                 **integrator_options):
        if integrator is not None:
            scene.integrator = integrator
        if dt is not None:
            scene.dt = dt
        scene.validate()
        self.scene = scene
        self.model = build_model(scene)
        check_bodies_outside_terrains(self.model)
        self._integrator_options = integrator_settings(scene, integrator_options)
        self.integrator = get_integrator(scene.integrator, **self._integrator_options)
        self.dt = float(scene.dt)
        self.state = State.initial(self.model)
        self.steps_taken = 0

    @property
    def positions(self) -> np.ndarray:
        return self.state.positions

    @property
    def velocities(self) -> np.ndarray:
        return self.state.velocities

    @property
    def time(self) -> float:
        return self.state.time

    def step(self, count: int = 1) -> None:
        """Take ``count`` steps of size dt in one compiled call."""
        require(self.dt > 0 and math.isfinite(self.dt), "dt", self.dt, "must be > 0 s")
        require(count >= 0, "steps", count, "must be >= 0")
        done, particle = self.integrator.advance(self.model, self.state, self.dt, count)
        self.state.time += done * self.dt
        self.steps_taken += done
        if particle >= 0:
            v = self.state.velocities[particle]
            raise SimulationDiverged(
                time=self.state.time, step=self.steps_taken, integrator=self.integrator.name,
                dt=self.dt, particle=particle, position=self.state.positions[particle],
                speed_squared=float(v @ v))

    def advance(self, seconds: float) -> None:
        """Simulate ``seconds`` more (rounded to whole steps)."""
        require(seconds >= 0, "seconds", seconds, "must be >= 0")
        self.step(int(round(seconds / self.dt)))

    def surfaces(self) -> list:
        """Each body's surface at the current state: ``surfaces.Surface`` with ``.name``,
        ``.vertices`` (V, 3) and ``.triangles`` (T, 3); a body of balls has their centres as
        vertices, no triangles, and ``.radii`` (surfaces.py)."""
        radius = self.model.arrays.radius
        return [body_surface(body, self.state.positions, radius) for body in self.model.bodies]

    def energy(self) -> dict:
        """Kinetic, gravitational, spring and total energy (J) of the current state."""
        return energies(self.model, self.state)

    def reset(self) -> None:
        """Back to the initial state (its contact memory included), with a fresh integrator."""
        self.state = State.initial(self.model)
        self.steps_taken = 0
        self.integrator = get_integrator(self.scene.integrator, **self._integrator_options)
