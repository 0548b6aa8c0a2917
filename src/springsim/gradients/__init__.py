"""Exact gradients of a loss on a simulated trajectory: reverse mode, the discrete adjoint of each
step the simulation took (docs/guide/gradients.md).

    loss, grads = springsim.gradient(scene, loss=my_loss, wrt=["bodies.0.structural.ks",
                                     "initial_velocities"], duration=1.0)

The pieces, one concern a file:
- ``physics.py``: the forces and the implicit system in NumPy, and their vector-Jacobian products;
  ``wind.py`` and ``pins.py`` the moving world's forces, ``attachments.py`` the bindings
  between bodies, ``contact.py``, ``terrain_shapes.py``, ``implicit_replay.py`` (backward
  Euler's step as its record says it went) and ``implicit_contact.py`` (its adjoint) terrain
  contact, ``clock.py`` the time each force is taken at;
- ``adjoints.py``: the adjoint of each integrator's step, registered by the integrator's name;
- ``solve.py``: backward Euler's Newton iterations and the adjoint solve of each;
- ``tape.py``: the forward run (the simulation's own kernels) and the backward pass, with
  checkpoints;
- ``parameters.py``: parameter names and how each one's gradient is gathered;
- ``losses.py``: losses against an observed take, marker tracks, or a user's function;
- ``fit.py``: L-BFGS-B on chosen parameters (``springsim fit``).
"""
from dataclasses import dataclass

import numpy as np

from ..errors import SceneError, require
from .adjoints import adjoint_class
from .checks import check_supported, contact_check
from .losses import as_loss
from .parameters import parameter
from .physics import Cotangents, Physical
from .tape import DEFAULT_MEMORY_LIMIT, backward, record


@dataclass
class Result:
    """What one gradient run gives: the loss, the cotangents, the memory its states took."""

    loss: float
    x0_bar: np.ndarray
    v0_bar: np.ndarray
    bar: Cotangents
    stored_bytes: int
    frames: np.ndarray       # (F, P, 3) the positions the loss saw


def prepare(scene, wrt, values=None, integrator=None, dt=None, duration=None, threads=None,
            **integrator_options):
    """(scene, simulation, parameters): the scene with scene-level values applied, a Simulation
    with model-level values applied, and the parameters ``wrt`` names. Every name and value is
    checked here, before any step."""
    from ..scene import Scene
    from ..simulation import Simulation

    require(isinstance(scene, Scene), "scene", type(scene).__name__,
            "must be a springsim Scene (springsim.load_scene gives one)")
    names = [wrt] if isinstance(wrt, str) else list(wrt)
    require(len(names) > 0, "wrt", wrt, "must name at least one parameter")
    require(len(set(names)) == len(names), "wrt", wrt, "names a parameter twice")
    params = [parameter(scene, name) for name in names]
    values = values or {}
    for p in params:
        if p.stage == "scene" and p.name in values:
            scene = p.apply(scene, values[p.name])
    simulation = Simulation(scene, integrator=integrator, dt=dt, threads=threads,
                            **integrator_options)
    while (parts := simulation.substeps().count) > 1:
        # a fast collider's step is taken as parts (substeps.py): the same run as steps of
        # dt / parts, which are the steps the adjoint goes back through
        simulation = Simulation(scene, integrator=integrator, dt=simulation.dt / parts,
                                threads=threads, **integrator_options)
    model = simulation.model
    for p in params:
        if p.stage == "model" and p.name in values:
            model = p.apply(model, values[p.name])
    if model is not simulation.model:
        simulation.model = model
        simulation.reset()
    if duration is not None:
        from ..sampling import check_duration
        check_duration(duration)
    check_supported(simulation)
    return simulation.scene, simulation, params


def run_gradient(simulation, loss, duration: float, memory_limit=DEFAULT_MEMORY_LIMIT) -> Result:
    """Forward run, loss, backward pass (tape.py) for a prepared simulation."""
    dt = simulation.dt
    steps = round(duration / dt)
    require(steps >= 1, "duration", duration, f"must be at least one step of dt = {dt:g} s")
    frame_steps = loss.frame_steps(duration, dt, simulation.model.particle_count)
    frames, tape = record(simulation, steps, frame_steps, memory_limit)
    value, frame_bars = loss(frames)
    if not np.isfinite(value) or not np.all(np.isfinite(frame_bars)):
        raise SceneError("loss", value, "must be a finite number with a finite gradient "
                         "(the loss returned NaN or infinity)")
    physical = Physical.of(simulation.model)
    adjoint = adjoint_class(simulation.integrator)(simulation.integrator, simulation.model)
    x0_bar, v0_bar, bar = backward(simulation, adjoint, physical, tape, frame_steps, frame_bars,
                                     contact_check(simulation, physical))
    # a pinned particle never moves: its initial velocity is zeroed by the model
    v0_bar[~physical.free] = 0.0
    return Result(float(value), x0_bar, v0_bar, bar, tape.stored_bytes, frames)


def gradient(scene, loss, wrt, duration=None, integrator=None, dt=None, fps=None, threads=None,
             memory_limit=DEFAULT_MEMORY_LIMIT, **integrator_options):
    """(loss, {name: gradient}) for the parameters ``wrt`` names (parameters.py), of ``loss``
    on the trajectory of ``scene`` over ``duration`` s (default: the scene's).

    ``loss``: an ObservedTake or MarkerTracks (losses.py), or a function of the positions at
    the frames (F, P, 3), recorded at ``fps`` (default 60, as ``springsim run``), returning
    (value, gradient) or the value alone (then differentiated by finite differences of its
    inputs). ``integrator``, ``dt``, ``threads`` and integrator options as for Simulation."""
    loss = as_loss(loss, fps)
    scene, simulation, params = prepare(scene, wrt, None, integrator, dt, duration, threads,
                                        **integrator_options)
    duration = scene.duration if duration is None else duration
    loss.check(simulation.model, duration, simulation.dt)
    result = run_gradient(simulation, loss, duration, memory_limit)
    return result.loss, {p.name: p.gradient(scene, simulation.model, result) for p in params}


__all__ = ["Result", "gradient", "prepare", "run_gradient"]
