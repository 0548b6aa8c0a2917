"""Simulation: a model, a state and an integrator, advanced in whole steps.

Every public method checks its arguments and the state's arrays before any compiled call, so
misuse is a one-line SceneError naming the argument, never a Numba typing error or a write past
the end of an array.
"""
import contextlib
import copy
import math
import numbers

import numpy as np

from . import signals
from .energy import energies
from .errors import SceneError, SimulationDiverged, require
from .integrators import available_threads, get_integrator
from .model import build_model
from .scene import Scene, check_bodies_outside_terrains, section_settings
from .spring_runs import PARTITION
from .state import State
from .substeps import ColliderSubsteps, collider_substeps
from .surfaces import body_surface

# The most steps one call may take: time advances by steps * dt in float64, exact in whole steps
# up to 2^53 (and an int64 step counter holds that with room to spare).
MAX_STEPS = 2 ** 53


def integrator_settings(scene, overrides: dict) -> dict:
    """The scene's settings for its integrator (those it declares in OPTIONS), then overrides."""
    from .integrators import REGISTRY

    integrator = REGISTRY.get(scene.integrator)
    settings = section_settings(scene, integrator) if integrator is not None else {}
    return {**settings, **overrides}


def check_threads(threads) -> int:
    """threads, or all cores for None; one clear error for anything else."""
    cores = available_threads()
    if threads is None:
        return cores
    require(isinstance(threads, (int, np.integer)) and not isinstance(threads, bool)
            and 1 <= threads <= cores, "threads", threads,
            f"must be a whole number from 1 to {cores} (this machine's cores)")
    return int(threads)


class Simulation:
    """Simulate ``scene`` with ``integrator`` (a registered name) and time step ``dt`` (s).

    Both default to the scene's own. ``integrator_options`` go to the integrator and win over the
    scene's ``implicit`` settings (for example ``newton_iterations=2`` for implicit_euler).
    The simulation works on its own copy of ``scene`` (``self.scene``): the caller's is never
    changed. ``threads`` is the most threads a step may use (default: all cores); results are
    the same for any number. ``spring_partition`` is the particles per partition of the force
    loop, at least (spring_runs.py: 65,536 unless given), which fixes the order of its sums:
    the tests and benchmarks set a small one to cut a small model into several.
    """

    def __init__(self, scene, integrator: str | None = None, dt: float | None = None,
                 threads: int | None = None, spring_partition: int = PARTITION,
                 **integrator_options):
        if isinstance(scene, (str, bytes)) or hasattr(scene, "__fspath__"):
            raise SceneError("scene", str(scene), "is a name or a file, not a Scene: load it "
                             f"first, Simulation(springsim.load_scene({str(scene)!r}))")
        require(isinstance(scene, Scene), "scene", type(scene).__name__,
                "must be a springsim Scene (springsim.load_scene gives one)")
        self.threads = check_threads(threads)
        scene = copy.deepcopy(scene)
        if integrator is not None:
            scene.integrator = integrator
        if dt is not None:
            require(_is_finite_number(dt) and dt > 0, "dt", dt,
                    "must be a time step > 0 s (a finite number)")
            scene.dt = dt
        scene.validate()
        self.scene = scene
        self.dt = float(scene.dt)
        self._substeps = {}               # dt -> ColliderSubsteps
        self.substeps()                   # a motion too fast for any substeps fails here,
        self.model = build_model(scene, spring_partition)   # before anything is built
        check_bodies_outside_terrains(self.model)
        self._integrator_options = integrator_settings(scene, integrator_options)
        self.integrator = get_integrator(scene.integrator, **self._integrator_options)
        self.state = State.initial(self.model)
        self._lists_left = (None, None)   # the pair lists the last step left (State.check)
        self._called = set()   # the kinds of compiled call made ("step", "keeping")

    @property
    def steps_taken(self) -> int:
        """Steps taken from the initial state to the current one (kept in the state)."""
        return self.state.steps

    @steps_taken.setter
    def steps_taken(self, count: int) -> None:
        self.state.steps = count

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
        require(_is_whole(count) and 0 <= count <= MAX_STEPS, "count", count,
                f"must be a whole number of steps from 0 to 2^53 = {MAX_STEPS}")
        require(_is_finite_number(self.dt) and self.dt > 0, "dt", self.dt,
                "must be a time step > 0 s (a finite number)")
        self._advance(self.dt, int(count))

    def step_shorter(self, seconds: float) -> None:
        """One step of ``seconds`` (0 < seconds < dt): a run ends exactly at its duration when dt
        does not divide it."""
        require(_is_finite_number(seconds) and 0 < seconds <= self.dt, "seconds", seconds,
                f"must be a time > 0 s and at most dt = {self.dt:g} s")
        self._advance(float(seconds), 1)

    def substeps(self, dt: float | None = None) -> ColliderSubsteps:
        """The substeps each step of ``dt`` (the simulation's) takes so that no moving terrain
        passes through a particle (substeps.py)."""
        dt = self.dt if dt is None else float(dt)
        if dt not in self._substeps:
            self._substeps[dt] = collider_substeps(self.scene.terrains, dt)
        return self._substeps[dt]

    def keeps_stages(self) -> int:
        """How many stage accelerations ``step_keeping`` keeps a step (0: it cannot)."""
        keeps = (getattr(self.integrator, "keeps_stages", None)
                 and self.integrator.keeps_stages(self.model) and self.substeps().count == 1)
        return self.integrator.stages if keeps else 0

    def step_keeping(self, kept: np.ndarray, starts: np.ndarray) -> None:
        """len(kept) steps in one compiled call, as ``step``, that also keep each step's start
        (x, v) in starts[n] (2, P, 3) and its force evaluations' accelerations in kept[n]
        (keeps_stages(), P, 3): the gradient's tape (gradients/tape.py) records them so that its
        adjoint need not evaluate the forces again."""
        self._advance(self.dt, len(kept), (kept, starts))

    def _advance(self, dt: float, count: int, tape: tuple | None = None) -> None:
        self.state.check(self.model.particle_count, self._surface_shapes(), self._lists_left)
        parts = self.substeps(dt).count
        step = dt / parts   # the step the integrator takes (dt itself without substeps)
        # Ctrl-C and SIGTERM wait for the compiled call to return and the state to be whole
        with signals.deferred(), self._first_call_said("keeping" if tape else "step"):
            if tape is None:
                done, particle = self.integrator.advance(self.model, self.state, step,
                                                         count * parts, self.threads)
            else:
                done, particle = self.integrator.advance_keeping(self.model, self.state, step,
                                                                 *tape)
            self._lists_left = (self.state.pairs, self.state.solve_pairs)
            self.state.time += done * step
            self.state.steps += done // parts
        if particle >= 0:
            v = self.state.velocities[particle]
            with np.errstate(over="ignore", invalid="ignore"):   # inf is the honest answer
                speed_squared = float(v @ v)
            raise SimulationDiverged(
                time=self.state.time, step=self.steps_taken, integrator=self.integrator.name,
                dt=step, particle=particle, position=self.state.positions[particle],
                speed_squared=speed_squared, suggested_dt=self._step_to_try(step))

    def _first_call_said(self, kind: str):
        """Around the first compiled call of each kind: a compile it makes is said on stderr
        (compile_notice.announced; from Python too, not only the command line). Later calls pay
        nothing for it."""
        if kind in self._called:
            return contextlib.nullcontext()
        from .compile_notice import announced, kernels_of

        self._called.add(kind)
        return announced(kernels_of(self))

    def _step_to_try(self, dt: float) -> float:
        """A step to suggest after a divergence: half this one, or less where the stiffest
        particle's bound says so (step_size.py; the explicit methods')."""
        from .step_size import IMPLICIT, stable_step

        if self.integrator.name in IMPLICIT:
            return dt / 2
        return min(dt / 2, stable_step(self.model, self.integrator.name).dt)

    def _surface_shapes(self) -> tuple[int, int]:
        """How many surface triangles and edges the model has (the pair lists number them)."""
        arrays = self.model.arrays
        return len(arrays.surface_triangles), len(arrays.surface_edges)

    def advance(self, seconds: float) -> None:
        """Simulate ``seconds`` more (rounded to whole steps)."""
        require(_is_finite_number(seconds) and seconds >= 0, "seconds",
                seconds, "must be a finite number of seconds >= 0")
        steps = round(seconds / self.dt)
        require(steps <= MAX_STEPS, "seconds", seconds,
                f"is more than 2^53 steps of dt = {self.dt:g} s")
        self.step(int(steps))

    def surfaces(self) -> list:
        """Each body's surface at the current state: ``surfaces.Surface`` with ``.name``,
        ``.vertices`` (V, 3) and ``.triangles`` (T, 3); a body of balls has their centres as
        vertices, no triangles, and ``.radii`` (surfaces.py)."""
        radius = self.model.arrays.radius
        return [body_surface(body, self.state.positions, radius) for body in self.model.bodies]

    def energy(self) -> dict:
        """Kinetic, gravitational, spring and total energy (J) of the current state."""
        self.state.check(self.model.particle_count)
        return energies(self.model, self.state)

    def reset(self) -> None:
        """Back to the initial state (its contact memory and pair lists included), with a fresh
        integrator."""
        self.state = State.initial(self.model)
        self.integrator = get_integrator(self.scene.integrator, **self._integrator_options)

    def save_state(self, path) -> None:
        """Write the state (positions, velocities, time, steps, contact memory, pair lists) to the
        NPZ file ``path``, whole or not at all; ``load_state`` continues the run from it bit for
        bit."""
        from .checkpoint import save_state

        self.state.check(self.model.particle_count)
        save_state(path, self)

    def load_state(self, path) -> None:
        """Continue from a state written by ``save_state`` for a model with as many particles."""
        from .checkpoint import load_state

        self.state = load_state(path, self.model.particle_count)


def _is_finite_number(value) -> bool:
    if not isinstance(value, numbers.Real) or isinstance(value, bool):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:   # an int too large for a float
        return False


def _is_whole(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)
