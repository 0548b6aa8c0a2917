"""Recording a run: the state sampled every 1/fps s of simulated time, and the NPZ file it goes to.

Frame k is the state after ``round(k / (fps dt))`` steps, so the simulation advances in whole
steps, one compiled call per frame, and ``time`` holds the exact simulated time of each frame
(within dt/2 of k/fps). Frame 0 is the state the recording starts from (t = 0 for a fresh
simulation); the last frame is at ``duration``. When 1/fps is shorter than dt, neighbouring frames
repeat a state: the frame count, and so a video's pace, stays that of the fps asked for.
"""
import contextlib
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass, field, fields

import numpy as np

from .energy import gravitational_energy, kinetic_energy, spring_energy
from .errors import require
from .recording_layout import LAYOUT_KEYS, layout_arrays

# A recording may take at most this share of the machine's memory (two (F, P, 3) float64 arrays).
MEMORY_SHARE = 0.5


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
        self.penetration[frame] = deepest_penetration(model, x)

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


def record(simulation, duration: float, fps: float, progress: bool = False) -> Recording:
    """Run ``simulation`` for ``duration`` s, keeping a frame every 1/fps s.

    ``progress`` shows a tqdm bar on stderr when stderr is a terminal; it disappears when done,
    so that an error (a diverged simulation) is the only line left.
    """
    from tqdm import tqdm

    frame_steps = frame_schedule(duration, fps, simulation.dt)
    check_memory(len(frame_steps), simulation.model.particle_count, fps)
    recording = Recording.empty(simulation, len(frame_steps), fps)
    recording.capture(0, simulation)
    simulation.step(0)  # compile (or load) the kernels now, so the timings are the simulation's
    started = time.perf_counter()
    with tqdm(total=int(frame_steps[-1]), unit="step", desc=simulation.scene.name, leave=False,
              file=sys.stderr, disable=None if progress else True) as bar:
        for frame in range(1, len(frame_steps)):
            count = int(frame_steps[frame] - frame_steps[frame - 1])
            step_started = time.perf_counter()
            simulation.step(count)
            recording.step_seconds += time.perf_counter() - step_started
            recording.steps += count
            recording.capture(frame, simulation)
            bar.update(count)
    recording.wall_seconds = time.perf_counter() - started
    return recording


def frame_schedule(duration: float, fps: float, dt: float) -> np.ndarray:
    """The step count at each frame: frame k at time k/fps, rounded to a whole step."""
    require(math.isfinite(fps) and fps > 0, "fps", fps, "must be > 0 frames per simulated second")
    require(math.isfinite(duration) and duration >= 0, "duration", duration, "must be >= 0 s")
    require(duration / dt < 2.0 ** 53, "dt", dt,
            f"is too small for a {duration:g} s run (more than 2^53 steps): use a larger dt")
    intervals = math.floor(duration * fps + 1e-9)   # 1e-9: 8 s * 60 fps is 480 intervals
    times = np.arange(intervals + 1) / fps
    if duration - times[-1] > dt / 2:
        times = np.append(times, duration)          # a last, shorter interval ends at duration
    return np.rint(times / dt).astype(np.int64)


def check_memory(frame_count: int, particle_count: int, fps: float) -> None:
    """Refuse up front a recording that cannot fit in memory (positions and velocities)."""
    needed = 2 * frame_count * particle_count * 3 * 8
    try:
        available = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return  # no way to tell on this system; let NumPy try
    require(needed <= MEMORY_SHARE * available, "fps", fps,
            f"recording {frame_count} frames of {particle_count} particles needs "
            f"{needed / 1e9:.1f} GB of the machine's {available / 1e9:.1f} GB; lower --fps or "
            f"--duration (`springsim bench` times large models without recording them)")


def deepest_penetration(model, x: np.ndarray) -> float:
    """How deep (m) the deepest particle lies inside any terrain; 0 when none is inside."""
    depth = 0.0
    for terrain in model.terrains:
        depth = max(depth, -float(np.min(terrain.signed_distance(x, model.arrays.radius))))
    return depth


def all_surfaces(model) -> np.ndarray:
    surfaces = [body.surface for body in model.bodies]
    return np.concatenate(surfaces) if surfaces else np.empty((0, 3), np.int32)


def write_npz(path, arrays: dict) -> None:
    """Write ``arrays`` to the NPZ file ``path``, whole or not at all."""
    with atomic_output(path) as file:
        np.savez(file, **arrays)


@contextlib.contextmanager
def atomic_output(path):
    """A binary file that becomes ``path`` only if the block finishes without an error.

    It is written beside ``path`` (so that ``os.replace`` is a rename on one file system, which is
    atomic) and removed on any error, so a reader sees the old file or the new one, never half.
    """
    path = os.path.abspath(os.fspath(path))
    handle, temporary = tempfile.mkstemp(dir=os.path.dirname(path),
                                         prefix=f".{os.path.basename(path)}.", suffix=".part")
    try:
        with os.fdopen(handle, "wb") as file:
            yield file
            file.flush()
            os.fsync(file.fileno())
        os.chmod(temporary, 0o666 & ~_umask())  # mkstemp makes it private; give it the usual mode
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
