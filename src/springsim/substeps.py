"""Substeps for fast colliders: no particle passes through a moving terrain within one step.

Contact pushes a particle out of a terrain to the nearest side of its surface. A collider that
moves further in one step than half its thickness can carry its surface past a particle, which
then lies nearer the far side and is pushed out there: the collider has passed through it (a
sphere of 5 cm radius at 10 m/s moves 17 cm in a 1/60 s step). So a step whose terrains would
move more than SHARE of their thickness is taken as that many substeps of equal length, at every
integrator, chosen before the run from the motions alone (a motion is a function of time):
the same scene and step always take the same substeps, so runs stay deterministic and resume
exactly.

A terrain's travel in a step is the largest distance any of its ``motion_probes`` (points of
its surface as placed) moves in dt, sampled over the motion's keyframes (a constant velocity
moves them the same distance at any time). ``thickness()`` is the terrain's thinnest part:
a sphere's diameter, a closed mesh's smallest box side; a plane, a bowl and an open mesh have
no far side (inf) and never ask for substeps. A deforming terrain's own motion is not
substepped: its lookup reaches as far as its vertices move between two samples of its cache
(terrains/deforming_mesh.py).
"""
import math
from typing import NamedTuple

import numpy as np

from .errors import SceneError

SHARE = 0.4          # of its thickness, the most a collider moves in a substep
MAX_SUBSTEPS = 1000  # more than this per step is refused: a smaller dt says what is meant
SAMPLES = 4000       # times sampled over a keyframed motion, at most


class ColliderSubsteps(NamedTuple):
    """The substeps a step of ``dt`` takes, and the terrain that asks for the most."""

    count: int          # substeps per step (1: none)
    terrain: int        # the terrain's number, -1 if none asks
    travel: float       # m that terrain moves in one step, at most
    thickness: float    # m, its thickness


def collider_substeps(terrains, dt: float) -> ColliderSubsteps:
    """The substeps a step of ``dt`` needs for the moving ``terrains`` (module doc)."""
    worst, when = ColliderSubsteps(1, -1, 0.0, math.inf), 0.0
    for number, terrain in enumerate(terrains):
        if getattr(terrain, "motion", None) is None:
            continue
        thickness = terrain.thickness()   # a mesh's reads its file: only for moving ones
        if not math.isfinite(thickness):
            continue
        travel, start = largest_travel(terrain, dt)
        count = travel / (SHARE * thickness)   # inf where the travel is beyond float64
        if count > worst.count:
            worst, when = ColliderSubsteps(count, number, travel, thickness), start
    if worst.count > MAX_SUBSTEPS:
        name, value = blamed(terrains[worst.terrain].motion, when, dt, worst.travel)
        moves = (f"moves the terrain {worst.travel:.3g} m in one step of dt = {dt:g} s: "
                 f"{worst.count:.3g} substeps of {SHARE:g} of its thickness "
                 f"({worst.thickness:.3g} m)" if math.isfinite(worst.travel) else
                 f"moves the terrain further than float64 can measure in one step of dt = "
                 f"{dt:g} s")
        smaller = (f"a smaller dt (about {dt * MAX_SUBSTEPS / worst.count:.2g} s) or "
                   if math.isfinite(worst.travel) else "")
        raise SceneError(f"terrains.{worst.terrain}.motion.{name}", value,
                         f"{moves}; at most {MAX_SUBSTEPS} substeps of {SHARE:g} of its "
                         f"thickness are taken: use {smaller}a slower motion")
    return worst._replace(count=math.ceil(worst.count))


def largest_travel(terrain, dt: float) -> tuple[float, float]:
    """The farthest any of the terrain's probes moves in dt (m), over its motion's times, and
    the step's start time when it does. inf where the motion moves it beyond what float64
    holds (a velocity of 1e300 m/s)."""
    motion, anchor, probes = terrain.motion, terrain.anchor(), terrain.motion_probes()
    travel, when = 0.0, 0.0
    if not len(probes):
        return travel, when
    for t in sample_times(motion, dt):
        with np.errstate(over="ignore", invalid="ignore"):   # beyond float64: inf, refused
            moved = motion.place(probes, t + dt, anchor) - motion.place(probes, t, anchor)
            here = float(np.linalg.norm(moved, axis=1).max())
        if not math.isfinite(here):
            return math.inf, float(t)
        if here > travel:
            travel, when = here, float(t)
    return travel, when


def blamed(motion, start: float, dt: float, travel: float) -> tuple[str, object]:
    """The motion's key and value that make its step from ``start`` (``travel`` m long) as long
    as it is: a constant velocity, or its angular velocity where the velocity alone moves it
    less than half as far; or the keyframe the step heads for (its position, or its rotation
    where the position does not change)."""
    if not motion.keyframes:
        speed = float(np.max(np.abs(motion.velocity)))   # within sqrt(3) of |v|, no overflow
        turning = float(np.max(np.abs(motion.angular_velocity)))
        linear = speed >= turning if math.isinf(travel) else \
            speed * dt >= 0.5 * travel / math.sqrt(3.0)
        return ("velocity", motion.velocity) if linear else \
            ("angular_velocity", motion.angular_velocity)
    times = np.array([frame.time for frame in motion.keyframes], float)
    k = int(np.clip(np.searchsorted(times, start + dt), 1, max(1, len(times) - 1)))
    k = min(k, len(times) - 1)
    frame, before = motion.keyframes[k], motion.keyframes[k - 1] if k > 0 else None
    if before is None or tuple(frame.position) != tuple(before.position):
        return f"keyframes.{k}.position", frame.position
    return f"keyframes.{k}.rotation_degrees", frame.rotation_degrees


def sample_times(motion, dt: float) -> np.ndarray:
    """Step starts to look at: one for a constant velocity, else every half step from a step
    before the first key to the last (no more than SAMPLES), and each key's time, a step
    before it and the middle between keys (so that no short, fast stretch is missed)."""
    if not motion.keyframes:
        return np.zeros(1)
    keys = np.array([frame.time for frame in motion.keyframes], float)
    first, last = keys[0] - dt, keys[-1]
    count = min(SAMPLES, max(2, math.ceil((last - first) / (0.5 * dt)) + 1))
    return np.unique(np.concatenate([np.linspace(first, last, count), keys, keys - dt,
                                     (keys[1:] + keys[:-1]) / 2 - dt / 2]))
