"""The largest stable time step of an integrator on a scene, found by bisection.

A trial simulates ``seconds`` of the scene at one time step dt. It is stable when, at every
sample (each SAMPLE_INTERVAL of simulated time, and at the end):
- nothing diverged (the course framework's check: a NaN, or |v|^2 > 1e6 m^2/s^2);
- the energy stayed bounded: the total energy E(t) never rose above E(0) by more than
  ENERGY_SLACK of the scene's energy scale. The built-in scenes are passive (dampers, restitution
  below 1 and friction only remove energy), so a rise is the integrator's doing. The scale is
  the larger of the kinetic plus spring energy seen so far and the work to lift the bodies by
  their own height (m |g| times the height of their bounding box): a blow-up soon exceeds it,
  while explicit Euler's slow drift in free fall (m g^2 h t / 2) stays far below it;
- no particle was deeper than its terrain's contact band epsilon inside a terrain (a moving or
  deforming terrain where it is at the sample's time).

The search starts at ``max_dt``; if that is stable it is the answer (the integrator is stable at
every step asked about). Otherwise dt halves until a trial is stable (unstable trials usually end
within a few steps), then bisects geometrically between the largest stable and the smallest
unstable step until they are within ``tolerance`` (relative) of each other.
"""
import copy
import functools
import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from .errors import SimulationDiverged, require
from .simulation import Simulation
from .clearance import terrain_clearance

SAMPLE_INTERVAL = 0.02   # s of simulated time between energy and penetration checks
ENERGY_SLACK = 0.1       # allowed rise of the total energy, as a share of the energy scale
MIN_DT = 1e-6            # s: below this the search gives up (unstable at every step tried)


@dataclass(frozen=True)
class Trial:
    dt: float              # s
    stable: bool
    reason: str            # why it is unstable ("" when stable)
    simulated: float       # s of scene time simulated before it stopped
    wall_seconds: float


@dataclass(frozen=True)
class StabilityLimit:
    """``largest_stable`` < limit <= ``smallest_unstable``; either may be None: no unstable step
    up to the maximum tried, or no stable one down to MIN_DT."""

    scene: str
    integrator: str
    largest_stable: float | None
    smallest_unstable: float | None
    trials: tuple = field(default_factory=tuple)

    @property
    def capped(self) -> bool:
        """Stable at the largest step tried: the true limit is higher still."""
        return self.largest_stable is not None and self.smallest_unstable is None


def run_trial(make_scene, integrator: str, dt: float, seconds: float,
              options: dict | None = None) -> Trial:
    """Simulate ``seconds`` of ``make_scene()`` at step ``dt`` and judge it (module doc)."""
    started = time.perf_counter()
    simulation = Simulation(make_scene(), integrator=integrator, dt=dt, **(options or {}))
    baseline = simulation.energy()["total"]
    scale = max(lifting_work(simulation.model), motion_energy(simulation.energy()))
    total_steps = max(1, round(seconds / dt))
    chunk = max(1, round(SAMPLE_INTERVAL / dt))
    done, reason = 0, ""
    while done < total_steps and not reason:
        count = min(chunk, total_steps - done)
        try:
            simulation.step(count)
        except SimulationDiverged:
            reason = "diverged"
            break
        done += count
        energy = simulation.energy()
        scale = max(scale, motion_energy(energy))
        if not energy["total"] - baseline <= ENERGY_SLACK * scale:   # NaN fails too
            reason = "energy grew"
        elif deepest_penetration(simulation) > 0.0:
            reason = "penetration"
    return Trial(dt=dt, stable=not reason, reason=reason, simulated=simulation.time,
                 wall_seconds=time.perf_counter() - started)


def find_stability_limit(make_scene, integrator: str, *, seconds: float = 3.0,
                         max_dt: float = 0.1, tolerance: float = 0.05,
                         options: dict | None = None, on_trial=None) -> StabilityLimit:
    """Bracket and bisect the largest stable dt (module doc). ``on_trial(trial)`` is called
    after every trial, for progress output."""
    require(seconds > 0 and math.isfinite(seconds), "seconds", seconds, "must be > 0 s")
    require(max_dt > MIN_DT and math.isfinite(max_dt), "max_dt", max_dt,
            f"must be a finite step > {MIN_DT:g} s")
    require(0 < tolerance < 1, "tolerance", tolerance, "must lie in (0, 1)")
    trials = []

    def trial(dt):
        result = run_trial(make_scene, integrator, dt, seconds, options)
        trials.append(result)
        if on_trial is not None:
            on_trial(result)
        return result.stable

    scene_name = make_scene().name
    stable, unstable = None, None
    dt = max_dt
    while dt >= MIN_DT:
        if trial(dt):
            stable = dt
            break
        unstable, dt = dt, dt / 2
    if stable is not None and unstable is not None:
        while unstable / stable > 1 + tolerance:
            middle = math.sqrt(stable * unstable)
            if trial(middle):
                stable = middle
            else:
                unstable = middle
    return StabilityLimit(scene=scene_name, integrator=integrator, largest_stable=stable,
                          smallest_unstable=unstable, trials=tuple(trials))


@dataclass(frozen=True)
class Search:
    """One search of ``find_stability_limits``: a scene (a Scene, copied for every trial) and an
    integrator, with the arguments of ``find_stability_limit``."""

    scene: object
    integrator: str
    seconds: float = 3.0
    max_dt: float = 0.1
    tolerance: float = 0.05
    options: dict | None = None

    def run(self) -> StabilityLimit:
        return find_stability_limit(functools.partial(copy.deepcopy, self.scene), self.integrator,
                                    seconds=self.seconds, max_dt=self.max_dt,
                                    tolerance=self.tolerance, options=self.options)


def find_stability_limits(searches, workers: int | None = None, dask: str | None = None,
                          on_limit=None) -> list[StabilityLimit]:
    """``search.run()`` for every search, on local worker processes (default: every core) or
    the Dask cluster at ``dask``; in the order given. ``on_limit(limit)`` is called as each search
    finishes. Each search is the same sequence of trials wherever it runs, so the limits are
    those of ``find_stability_limit``."""
    from .runner import Runner, warm_kernels

    searches = list(searches)
    warm_kernels({s.integrator: replace(s.scene, integrator=s.integrator)
                  for s in searches}.values())
    with Runner(workers, dask, tasks=len(searches)) as runner:
        return runner.results(Search.run, searches,
                              None if on_limit is None else lambda _, limit: on_limit(limit))


def motion_energy(energy: dict) -> float:
    return energy["kinetic"] + energy["spring"]


def lifting_work(model) -> float:
    """m |g| times each body's height along g: the energy scale of a scene with gravity (J)."""
    g = np.asarray(model.arrays.gravity, float)
    size = float(np.linalg.norm(g))
    if size == 0.0:
        return 0.0
    down = g / size
    work = 0.0
    for body in model.bodies:
        heights = model.initial_positions[body.start:body.stop] @ down
        work += float(model.mass[body.start:body.stop].sum()) * size * float(np.ptp(heights))
    return work


def deepest_penetration(simulation) -> float:
    """How far (m) the deepest particle is inside any terrain beyond that terrain's contact band
    (zero or less when none is), each terrain where it is at the simulation's time."""
    model = simulation.model
    clearance = terrain_clearance(model, simulation.positions, simulation.time)
    epsilon = np.array([terrain.epsilon for terrain in model.terrains], float)
    return float(np.max(-clearance - epsilon, initial=-np.inf))
