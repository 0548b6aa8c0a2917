"""Measured order of accuracy of every integrator on a smooth, contact-free problem.

The problem: a small jelly cube (4 particles per edge, the course's 4 m edge and 1 kg particles,
ks = 2000 N/m, lightly damped with kd = 10 N s/m so that it still rings at the final time) with no
gravity and no terrain, released from rest squeezed to 80 % of its length along x. Nothing in it
is discontinuous, so every method shows its order: the error at the final time against a SciPy
``solve_ivp`` DOP853 solution at rtol = atol = 1e-12 on the same forces (``springsim.forces``)
falls as dt^p. The slope p is fitted to log(error) against log(dt).

The steps are chosen per order, so that every error lies in the asymptotic range (below, the
fast modes are resolved; above the reference's and round-off's floor): halvings from 2000 steps
for first-order methods, 250 for second and 125 for fourth. Backward Euler's linear solves run to
a relative residual of 1e-12 here, so that its error is the method's and not the solver's.
"""
import functools
import math
import operator
from dataclasses import dataclass

import numpy as np

from .bodies.cube import Cube
from .forces import forces
from .scene import Scene
from .simulation import Simulation
from .springs import SpringParameters

FINAL_TIME = 0.5   # s
SQUEEZE = 0.8      # length along x at the start, as a share of the rest length
STEP_COUNTS = {1: (2000, 4000, 8000, 16000), 2: (250, 500, 1000, 2000), 4: (125, 250, 500, 1000)}
EXACT_SOLVES = {"implicit_euler": {"cg_tolerance": 1e-12, "cg_max_iterations": 10000}}


@dataclass(frozen=True)
class ConvergenceResult:
    integrator: str
    expected_order: int
    dts: tuple       # s
    errors: tuple    # m, largest position error at the final time

    @property
    def slope(self) -> float:
        """The fitted order: the slope of log(error) against log(dt)."""
        return fitted_slope(self.dts, self.errors)


def fitted_slope(dts, errors) -> float:
    return float(np.polyfit(np.log(dts), np.log(errors), 1)[0])


def squeezed_cube(integrator: str = "rk4", dt: float = 1e-3, options: dict | None = None,
                  particles_per_edge: int = 4) -> Simulation:
    """The problem of the module doc, ready to step."""
    springs = SpringParameters(ks=2000.0, kd=10.0)
    cube = Cube(particles_per_edge=particles_per_edge, position=(0.0, 0.0, 0.0),
                structural=springs, shear=springs, bend=springs)
    scene = Scene(name="squeezed-cube", bodies=[cube], terrains=[], gravity=(0.0, 0.0, 0.0))
    simulation = Simulation(scene, integrator=integrator, dt=dt, **(options or {}))
    x = simulation.state.positions
    centre = x[:, 0].mean()
    x[:, 0] = centre + SQUEEZE * (x[:, 0] - centre)
    return simulation


def reference_positions(simulation: Simulation, final_time: float) -> np.ndarray:
    """The positions at ``final_time`` from DOP853 at rtol = atol = 1e-12, starting from the
    simulation's state."""
    from scipy.integrate import solve_ivp

    arrays = simulation.model.arrays
    inverse_mass = arrays.inv_mass[:, None]
    half = simulation.positions.size

    def derivative(_, y):
        x, v = y[:half].reshape(-1, 3), y[half:].reshape(-1, 3)
        return np.concatenate([v.ravel(), (forces(arrays, x, v) * inverse_mass).ravel()])

    start = np.concatenate([simulation.positions.ravel(), simulation.velocities.ravel()])
    solution = solve_ivp(derivative, (simulation.time, simulation.time + final_time), start,
                         method="DOP853", rtol=1e-12, atol=1e-12)
    if not solution.success:
        raise RuntimeError(f"the reference solve failed: {solution.message}")
    return solution.y[:half, -1].reshape(-1, 3)


def steps_for(final_time: float) -> dict:
    """STEP_COUNTS, with more steps for a final time beyond FINAL_TIME, so that every run keeps
    the default ladder's steps: fewer steps over a longer time would leave the explicit
    methods' stable range (rk4 at 60 s / 125 steps diverged in its first step)."""
    scale = max(1, math.ceil(final_time / FINAL_TIME))
    return {order: tuple(count * scale for count in counts)
            for order, counts in STEP_COUNTS.items()}


def measure_convergence(integrators, final_time: float = FINAL_TIME,
                        step_counts: dict | None = None, on_result=None, workers=None,
                        dask: str | None = None, parallel: bool = False) -> list:
    """A ConvergenceResult per integrator; ``step_counts`` maps an order to its step counts
    (default: ``steps_for(final_time)``). ``on_result(result)`` is called after each integrator.

    With ``parallel`` the runs (one per integrator and step count) and the reference go to
    ``workers`` local processes (default: every core) or the Dask cluster at ``dask``
    (springsim.runner); each is the same computation wherever it runs, so the errors are the
    same."""
    from .integrators import REGISTRY

    step_counts = step_counts or steps_for(final_time)
    runs = [(name, final_time / count, count) for name in integrators
            for count in step_counts[min(step_counts,
                                         key=lambda o: abs(o - REGISTRY[name].order))]]
    tasks = [functools.partial(final_positions, run) for run in runs]
    tasks.append(functools.partial(squeezed_cube_reference, final_time))
    if parallel:
        from .runner import Runner, warm_kernels

        warm_kernels([squeezed_cube(name).scene for name in dict.fromkeys(integrators)])
        with Runner(workers, dask, tasks=len(tasks)) as runner:
            *positions, reference = runner.results(operator.call, tasks)
    else:
        *positions, reference = [task() for task in tasks]
    results = []
    for name in integrators:
        mine = [(dt, float(np.abs(x - reference).max()))
                for (run_name, dt, _), x in zip(runs, positions) if run_name == name]
        results.append(ConvergenceResult(name, REGISTRY[name].order,
                                         tuple(dt for dt, _ in mine),
                                         tuple(error for _, error in mine)))
        if on_result is not None:
            on_result(results[-1])
    return results


def squeezed_cube_reference(final_time: float) -> np.ndarray:
    return reference_positions(squeezed_cube(), final_time)


def final_positions(run) -> np.ndarray:
    """The positions after ``count`` steps of ``dt`` of the squeezed cube, for ``run`` =
    (integrator, dt, count)."""
    name, dt, count = run
    simulation = squeezed_cube(name, dt, EXACT_SOLVES.get(name))
    simulation.step(count)
    return simulation.positions
