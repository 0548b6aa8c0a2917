"""Recording a run: the state at each frame of the one frame sampler (``sampling.py``: frame k is
the state after ``round(k / (fps dt))`` steps, the last at ``duration``), and the NPZ file it goes
to, written whole or not at all (``safe_files.py``). The simulation advances in whole steps, one
compiled call per frame, and ``time`` holds the exact simulated time of each frame.
"""
import math
import sys
import time
from dataclasses import dataclass, field, fields

import numpy as np

from .energy import gravitational_energy, kinetic_energy, spring_energy
from .recording_layout import LAYOUT_KEYS, layout_arrays
from .safe_files import atomic_output
from .sampling import frame_steps
from .compile_notice import announced, kernels_of
from .clearance import terrain_clearance



@dataclass
class Recording:
    scene: str
    integrator: str
    dt: float                          # s
    fps: float                         # frames per simulated second
    time: np.ndarray                   # (F,) s
    positions: np.ndarray              # (F, P, 3) m
    velocities: np.ndarray             # (F, P, 3) m/s
    kinetic_energy: np.ndarray         # (F,) J
    gravitational_energy: np.ndarray   # (F,) J
    spring_energy: np.ndarray          # (F,) J
    penetration: np.ndarray            # (F,) m, deepest particle inside any terrain, >= 0
    springs: np.ndarray                # (S, 2) particle numbers
    spring_kind: np.ndarray            # (S,) SpringKind
    mass: np.ndarray                   # (P,) kg
    surface: np.ndarray                # (T, 3) triangles of the bodies' surfaces
    steps: int = 0                     # steps taken while recording
    step_seconds: float = 0.0          # wall time spent in the integrator
    wall_seconds: float = 0.0          # wall time of the whole recording loop
    layout: dict = field(default_factory=dict)  # bodies, balls, terrains (recording_layout.py)

    @classmethod
    def empty(cls, simulation, frame_count: int, fps: float) -> "Recording":
        model = simulation.model
        particles = model.particle_count
        frame_shape = (frame_count, particles, 3)
        return cls(
            scene=simulation.scene.name, integrator=simulation.integrator.name,
            dt=simulation.dt, fps=float(fps), time=np.zeros(frame_count),
            positions=np.zeros(frame_shape), velocities=np.zeros(frame_shape),
            kinetic_energy=np.zeros(frame_count), gravitational_energy=np.zeros(frame_count),
            spring_energy=np.zeros(frame_count), penetration=np.zeros(frame_count),
            springs=np.asarray(model.springs), spring_kind=np.asarray(model.spring_kind),
            mass=np.asarray(model.mass), surface=all_surfaces(model), layout=layout_arrays(model))

    @property
    def frame_count(self) -> int:
        return len(self.time)

    @property
    def total_energy(self) -> np.ndarray:
        return self.kinetic_energy + self.gravitational_energy + self.spring_energy

    def capture(self, frame: int, simulation) -> None:
        model, x, v = simulation.model, simulation.positions, simulation.velocities
        self.time[frame] = simulation.time
        self.positions[frame] = x
        self.velocities[frame] = v
        self.kinetic_energy[frame] = kinetic_energy(model, v)
        self.gravitational_energy[frame] = gravitational_energy(model, x)
        self.spring_energy[frame] = spring_energy(model, x)
        self.penetration[frame] = deepest_penetration(model, x, simulation.time)

    def arrays(self) -> dict:
        """Everything, as the arrays an NPZ file holds (strings and numbers as 0-d arrays)."""
        plain = {f.name: np.asarray(getattr(self, f.name)) for f in fields(self)
                 if f.name != "layout"}
        return {**plain, **self.layout}

    @classmethod
    def load(cls, path) -> "Recording":
        with np.load(path) as data:
            values = {f.name: data[f.name] for f in fields(cls) if f.name != "layout"}
            values["layout"] = {key: data[key] for key in LAYOUT_KEYS if key in data}
        for name in ("scene", "integrator"):
            values[name] = str(values[name])
        for name in ("dt", "fps", "step_seconds", "wall_seconds"):
            values[name] = float(values[name])
        values["steps"] = int(values["steps"])
        return cls(**values)


def record(simulation, duration: float, fps: float, progress: bool = False, on_frame=None,
           start=None) -> Recording:
    """Run ``simulation`` for ``duration`` s, keeping a frame every 1/fps s.

    ``progress`` shows a tqdm bar on stderr when stderr is a terminal; it disappears when done,
    so that an error (a diverged simulation) is the only line left. ``on_frame(recording,
    frame)`` is called after each frame is captured (checkpoints). ``start`` continues a
    recording: ``(recording, first frame still to record)``, with the simulation at the state of
    the frame before (checkpoint.Resumed.start).
    """
    from tqdm import tqdm

    steps = frame_steps(duration, fps, simulation.dt, simulation.model.particle_count)
    with announced(kernels_of(simulation), say=progress):
        simulation.step(0)  # compile (or load) the kernels now, so the timings are the simulation's
        if start is None:   # a capture measures the penetration with a kernel of its own
            recording, first = Recording.empty(simulation, len(steps), fps), 1
            recording.capture(0, simulation)
        else:
            recording, first = start
    started = time.perf_counter() - recording.wall_seconds
    with tqdm(total=int(steps[-1]), initial=int(steps[first - 1]), unit="step",
              desc=simulation.scene.name, leave=False, file=sys.stderr,
              disable=None if progress else True) as bar:
        end = recording.time[0] + duration
        for frame in range(first, len(steps)):
            count = int(steps[frame] - steps[frame - 1])
            step_started = time.perf_counter()
            if frame == len(steps) - 1:   # the last frame is at the duration, exactly
                count, rest = last_steps(end - simulation.time, simulation.dt)
                simulation.step(count)
                if rest > 0:
                    simulation.step_shorter(rest)
                    count += 1
            else:
                simulation.step(count)
            recording.step_seconds += time.perf_counter() - step_started
            recording.steps += count
            recording.capture(frame, simulation)
            bar.update(count)
            if on_frame is not None:
                # a checkpoint keeps the time so far: a resumed run's wall time includes it
                recording.wall_seconds = time.perf_counter() - started
                on_frame(recording, frame)
    recording.wall_seconds = time.perf_counter() - started
    return recording


def last_steps(seconds: float, dt: float) -> tuple[int, float]:
    """The whole steps of ``dt`` that fit in ``seconds``, and the shorter step after them that
    ends exactly there (0 when they end within a millionth of a step of it)."""
    whole = max(0, math.floor(seconds / dt + 1e-6))
    rest = seconds - whole * dt
    return whole, (rest if rest > 1e-6 * dt else 0.0)


def deepest_penetration(model, x: np.ndarray, t: float) -> float:
    """How deep (m) the deepest particle at ``x`` lies inside any terrain where that terrain
    is at time ``t`` (s), moving and deforming ones included; 0 when none is inside."""
    return max(0.0, -float(np.min(terrain_clearance(model, x, t), initial=np.inf)))


def all_surfaces(model) -> np.ndarray:
    # particle-number triangles only: an embedded surface (a mesh body) numbers its own vertices
    surfaces = [body.surface for body in model.bodies if body.embedding is None]
    return np.concatenate(surfaces) if surfaces else np.empty((0, 3), np.int32)


def write_npz(path, arrays: dict) -> None:
    """Write ``arrays`` to the NPZ file ``path``, whole or not at all."""
    with atomic_output(path) as file:
        np.savez(file, **arrays)
