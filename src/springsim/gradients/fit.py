"""Fitting parameters to observed motion: L-BFGS-B (SciPy) on the loss and its exact gradient.

Positive parameters (stiffness, damping, masses, rest lengths, drag, a stiffness field) are
fitted in log space, so that a step can never make them negative and a factor of two up or down
is the same distance; the rest (gravity, initial state) as they are. Bounds: a positive
parameter stays within ``BOUND_FACTOR`` of its starting value either way; a friction within
[0, inf) and a restitution within [0, 1], the ranges a scene allows (``RANGES``), so that no
trial step asks for a scene that cannot run. Deterministic: the same scene and take give the
same iterates.
"""
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from ..errors import SceneError, SimulationDiverged, is_finite, require
from . import prepare, run_gradient

BOUND_FACTOR = 1000.0
DIVERGED_LOSS = 1e6   # the loss (over the starting loss) of trial values whose run blows up
POSITIVE_WORDS = ("ks", "kd", "mass", "masses", "particle_mass", "drag", "rest_lengths",
                  "stiffness_field", "spring_ks", "spring_kd")
RANGES = {"friction": (0.0, None), "particle_friction": (0.0, None),
          "restitution": (0.0, 1.0), "ball_restitution": (0.0, 1.0),
          "particle_restitution": (0.0, 1.0)}   # of the rest, by the name's last word


@dataclass
class FitResult:
    values: dict              # name -> fitted value (float or array)
    loss: float
    iterations: int
    evaluations: int
    converged: bool
    message: str
    history: list = field(default_factory=list)   # [(iteration, loss, {name: value})]
    scene: object = None      # the scene with the fitted scene values
    frames: object = None     # (F, P, 3) the positions of the last evaluation


def check_tolerance(tolerance, key: str) -> None:
    """L-BFGS-B stops when the loss changes relatively less than ``tolerance``: a NaN would
    never stop it early and a negative one means nothing."""
    require(not isinstance(tolerance, (bool, str, bytes)) and is_finite(tolerance)
            and np.ndim(tolerance) == 0 and tolerance >= 0, key, tolerance,
            "must be a finite relative change of the loss >= 0 (default 1e-10)")


def is_positive(name: str) -> bool:
    return name.split(".")[-1] in POSITIVE_WORDS or ".stiffness_regions." in name


def fit(scene, loss, wrt, duration, integrator=None, dt=None, threads=None, max_iterations=50,
        tolerance=1e-10, progress=None, **integrator_options):
    """Fit the parameters ``wrt`` names so that ``loss`` is least; ``progress(iteration, loss,
    values)`` is called after each iteration."""
    check_tolerance(tolerance, "tolerance")
    _, simulation, params = prepare(scene, wrt, None, integrator, dt, duration, threads,
                                    **integrator_options)
    loss.check(simulation.model, duration, simulation.dt)
    starts = {}
    for p in params:
        start = np.asarray(p.value if p.stage == "scene" else p.read(simulation.model), float)
        if is_positive(p.name) and not np.all(start > 0):
            raise SceneError(p.name, start.tolist() if start.size < 8 else "an array",
                             "must be > 0 to be fitted (it is fitted in log space)")
        starts[p.name] = start
    sizes = [starts[p.name].size for p in params]
    splits = np.cumsum(sizes)[:-1]

    def unpack(z):
        values = {}
        for p, part in zip(params, np.split(z, splits)):
            value = np.exp(part) if is_positive(p.name) else part
            values[p.name] = value.reshape(starts[p.name].shape)
        return values

    z0 = np.concatenate([np.log(starts[p.name].ravel()) if is_positive(p.name)
                         else starts[p.name].ravel() for p in params])
    bounds = []
    for p in params:
        for value in starts[p.name].ravel():
            bounds.append((np.log(value) - np.log(BOUND_FACTOR), np.log(value)
                           + np.log(BOUND_FACTOR)) if is_positive(p.name)
                          else RANGES.get(p.name.split(".")[-1], (None, None)))
    evaluations = [0]
    last, scale = {}, {}

    def objective(z):
        values = unpack(z)
        fitted_scene, simulation, fitted = prepare(scene, wrt, values, integrator, dt, duration,
                                                   threads, **integrator_options)
        try:
            result = run_gradient(simulation, loss, duration)
        except SimulationDiverged:
            if "start" not in scale:
                raise   # the starting values themselves blow up: say so
            # a trial step too far (an explicit method's springs too stiff for its dt): a loss
            # far above the start's makes the line search step back
            evaluations[0] += 1
            return DIVERGED_LOSS, np.zeros_like(z)
        evaluations[0] += 1
        grads = []
        for p in fitted:
            g = np.ravel(p.gradient(fitted_scene, simulation.model, result))
            grads.append(g * np.ravel(values[p.name]) if is_positive(p.name) else g)
        last.update(loss=result.loss, values=values, frames=result.frames)
        # L-BFGS-B's tolerance is relative to max(|loss|, 1): a loss in m^2 (1e-6 for
        # millimetres) would stop it at once, so it sees the loss over the starting loss
        scale.setdefault("start", result.loss if result.loss > 0 else 1.0)
        return result.loss / scale["start"], np.concatenate(grads) / scale["start"]

    history = []

    def callback(z):
        values = unpack(z)
        history.append((len(history) + 1, last.get("loss"), values))
        if progress is not None:
            progress(len(history), last.get("loss"), values)

    answer = minimize(objective, z0, jac=True, method="L-BFGS-B", bounds=bounds,
                      callback=callback, options={"maxiter": max_iterations, "ftol": tolerance,
                                                  "gtol": 1e-12})
    values = unpack(answer.x)
    fitted_scene = scene
    for p in params:
        if p.stage == "scene":
            fitted_scene = p.apply(fitted_scene, values[p.name])
    return FitResult(values, float(answer.fun) * scale["start"], int(answer.nit), evaluations[0],
                     bool(answer.success), str(answer.message), history, fitted_scene,
                     last.get("frames"))
