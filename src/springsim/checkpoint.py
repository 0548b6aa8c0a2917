"""Saved states and run checkpoints: a run continued from a file ends bit for bit as if it had
never stopped.

A state file (``Simulation.save_state``) holds the whole State: positions, velocities, time, the
steps taken, implicit_euler's contact memory and the surface pair lists. A checkpoint
(``springsim run --checkpoint-every``) holds, besides the state, everything the rest of the run
depends on: the run's arguments, its scene written out as a scene file (so a later edit of the
scene file cannot change a resumed run) and the frames recorded so far. Both are NPZ files
written whole or not at all, with a format name and version checked on load, so that a wrong or
foreign file is refused with one line.
"""
import json
import os
import time
import tomllib
import zipfile
from dataclasses import dataclass

import numpy as np

from .errors import SceneError, require
from .scene import Scene
from .collision.pair_lists import EDGES, POINTS, PairList
from .state import ContactMemory, State, solve_pair_list

STATE_FORMAT = "springsim-state"
CHECKPOINT_FORMAT = "springsim-checkpoint"
VERSION = 1
# The run options a checkpoint keeps: those that decide what is simulated and recorded, and where
# it goes (``springsim run``'s argument names).
RUN_OPTIONS = ("scene", "set", "integrator", "dt", "duration", "fps", "out", "plot", "video",
               "export", "checkpoint_every")
SCENE_OPTIONS = ("scene", "set", "integrator", "dt", "duration", "fps")


# --- states -------------------------------------------------------------------------------------

def state_arrays(state: State, prefix: str = "") -> dict:
    """The state as named arrays (the contact memory one array per field)."""
    arrays = {"positions": state.positions, "velocities": state.velocities,
              "time": np.float64(state.time), "steps": np.int64(state.steps)}
    arrays.update({f"contacts.{name}": array
                   for name, array in zip(ContactMemory._fields, state.contacts)})
    arrays.update({f"pairs.{name}": array for name, array in zip(PairList._fields, state.pairs)})
    if state.solve_pairs is not None:
        kept = state.solve_pairs
        arrays.update({"solve_pairs.points": kept.pairs[POINTS],
                       "solve_pairs.edges": kept.pairs[EDGES],
                       "solve_pairs.found_at": kept.found_at, "solve_pairs.reach": kept.reach})
    return {prefix + name: np.asarray(value) for name, value in arrays.items()}


def pair_lists_from_arrays(arrays: dict, prefix: str):
    """The state's pair lists in ``arrays`` (a file from before they were saved has none: the
    first step then finds them, as a fresh run does)."""
    pairs = None
    if all(f"{prefix}pairs.{name}" in arrays for name in PairList._fields):
        pairs = PairList(*(np.asarray(arrays[f"{prefix}pairs.{name}"]).copy()
                           for name in PairList._fields))
    solve_pairs = None
    names = ("points", "edges", "found_at", "reach")
    if all(f"{prefix}solve_pairs.{name}" in arrays for name in names):
        solve_pairs = solve_pair_list(*(arrays[f"{prefix}solve_pairs.{name}"] for name in names))
    return pairs, solve_pairs


def state_from_arrays(arrays: dict, particle_count: int, key: str, path,
                      prefix: str = "") -> State:
    """The State in ``arrays`` (from ``state_arrays``), checked against the model."""
    try:
        positions = arrays[prefix + "positions"]
        state = State(positions.copy(), arrays[prefix + "velocities"].copy(),
                      float(arrays[prefix + "time"]),
                      ContactMemory(*(arrays[f"{prefix}contacts.{name}"].copy()
                                      for name in ContactMemory._fields)),
                      int(arrays[prefix + "steps"]), *pair_lists_from_arrays(arrays, prefix))
    except (KeyError, TypeError, ValueError) as error:
        raise SceneError(key, str(path), f"holds no complete state ({error})") from None
    count = len(positions) if positions.ndim else 0
    require(count == particle_count, key, str(path),
            f"holds a state of {count} particles; this model has {particle_count}")
    state.check(particle_count)
    return state


def save_state(path, simulation) -> None:
    """Write ``simulation``'s state to the NPZ file ``path``, whole or not at all."""
    from .recording import write_npz

    write_npz(path, {"format": STATE_FORMAT, "version": VERSION,
                     "particle_count": simulation.model.particle_count,
                     "scene": simulation.scene.name, "integrator": simulation.integrator.name,
                     "dt": simulation.dt, **state_arrays(simulation.state)})


def load_state(path, particle_count: int, key: str = "path") -> State:
    """The state in a file ``save_state`` wrote, for a model of ``particle_count`` particles."""
    return state_from_arrays(read_file(path, STATE_FORMAT, key), particle_count, key, path)


def read_file(path, kind: str, key: str) -> dict:
    """Every array of a springsim NPZ file of format ``kind``; a SceneError naming ``key``
    for a missing, unreadable, foreign or newer file."""
    path = os.fspath(path)
    require(os.path.isfile(path), key, path,
            "no such file" if not os.path.exists(path) else "is not a regular file")
    try:
        loaded = np.load(path, allow_pickle=False)
        require(isinstance(loaded, np.lib.npyio.NpzFile), key, path,
                f"is not a {kind} file (an .npy array, not an NPZ file)")
        with loaded:
            arrays = {name: loaded[name] for name in loaded.files}
    except OSError as error:
        raise SceneError(key, path, f"cannot be read ({error.strerror or error})") from None
    except (ValueError, EOFError, zipfile.BadZipFile):
        raise SceneError(key, path, f"is not a {kind} file (not an NPZ file)") from None
    found = str(arrays["format"]) if "format" in arrays else ""
    require(found == kind, key, path, f"is not a {kind} file"
            + (f" but a {found} file" if found else " (it has no springsim format name)"))
    version = arrays.get("version")
    require(version is not None and version.shape == () and 1 <= int(version) <= VERSION, key,
            path, f"has format version {version}; this springsim reads versions 1 to {VERSION}")
    return arrays


# --- run checkpoints ----------------------------------------------------------------------------

def checkpoint_path(out: str) -> str:
    """Where a run writing ``out`` keeps its checkpoint: ``x.npz`` -> ``x.checkpoint.npz``."""
    stem = out[:-len(".npz")] if out.endswith(".npz") else out
    return stem + ".checkpoint.npz"


def check_interval(seconds) -> float:
    require(isinstance(seconds, (int, float)) and np.isfinite(seconds) and seconds >= 0,
            "--checkpoint-every", seconds,
            "must be a number of wall-clock seconds >= 0 (0: after every frame)")
    return float(seconds)


class Checkpoints:
    """``record``'s on_frame callback: writes the checkpoint at most every ``every`` wall-clock
    seconds (after the frame that crosses the interval)."""

    def __init__(self, path: str, every: float, simulation, arguments: dict, scene_toml: str,
                 clock=time.monotonic):
        self.path, self.every, self.simulation = path, check_interval(every), simulation
        self.arguments, self.scene_toml, self.clock = arguments, scene_toml, clock
        self.last = clock()

    def __call__(self, recording, frame: int) -> None:
        if self.clock() - self.last >= self.every:
            write_checkpoint(self.path, self.simulation, recording, frame, self.arguments,
                             self.scene_toml)
            self.last = self.clock()   # the interval counts from the end of the write


def write_checkpoint(path, simulation, recording, frame: int, arguments: dict,
                     scene_toml: str) -> None:
    """The run at ``frame`` (its state, frames 0 to ``frame`` and its arguments), whole."""
    from .recording import write_npz

    per_frame = frame_fields(simulation, recording.fps)
    arrays = {name: value[:frame + 1] if name in per_frame else value
              for name, value in recording.arrays().items()}
    write_npz(path, {"format": CHECKPOINT_FORMAT, "version": VERSION,
                     "particle_count": simulation.model.particle_count,
                     "arguments": json.dumps(arguments), "scene_toml": scene_toml,
                     "frames_done": frame + 1,
                     **state_arrays(simulation.state, "state."),
                     **{f"recording.{name}": value for name, value in arrays.items()}})


def frame_fields(simulation, fps: float) -> set:
    """The Recording fields that hold one row per frame (the others describe the model)."""
    from .recording import Recording

    one, two = (Recording.empty(simulation, count, fps).arrays() for count in (1, 2))
    return {name for name in one if np.shape(one[name]) != np.shape(two[name])}


@dataclass
class Resumed:
    """A checkpoint opened to continue its run."""

    path: str
    scene: Scene           # as the checkpoint wrote it
    arguments: dict        # the run's options (RUN_OPTIONS)
    arrays: dict
    frames: int            # frames recorded so far

    def start(self, simulation, frame_count: int):
        """Put the checkpoint's state into ``simulation``; the recording so far (sized for
        ``frame_count`` frames) and the first frame still to record, for ``record``'s start."""
        from .recording import Recording

        frames = self.frames
        require(1 <= frames <= frame_count, "--resume", self.path,
                f"holds {frames} frames, but its run records {frame_count}")
        simulation.state = state_from_arrays(self.arrays, simulation.model.particle_count,
                                             "--resume", self.path, prefix="state.")
        recording = Recording.empty(simulation, frame_count, self.arguments["fps"])
        per_frame = frame_fields(simulation, recording.fps)
        for name in recording.arrays():
            if not hasattr(recording, name):
                continue   # the layout (recording_layout.py), made again from the model
            saved = self.arrays.get(f"recording.{name}")
            require(saved is not None, "--resume", self.path, f"has no recording.{name}")
            if name in per_frame:
                target = getattr(recording, name)[:frames]
                require(saved.shape == target.shape, "--resume", self.path,
                        f"holds recording.{name} of shape {saved.shape}, not {target.shape}")
                target[...] = saved
            elif saved.shape == ():    # a number or a name: its kind as the field holds it
                setattr(recording, name, type(getattr(recording, name))(saved.item()))
        return recording, frames


def open_checkpoint(args) -> Resumed:
    """The checkpoint ``args.resume``, with ``args`` completed from the run it continues:
    the scene and its options come from the checkpoint (giving them again is refused), the
    outputs from the command line where given, else from the checkpoint."""
    from .scenefile import scene_from_table

    given = [name for name in SCENE_OPTIONS if getattr(args, name, None) not in (None, [])]
    require(not given, "--resume", args.resume,
            "continues the run the checkpoint holds, with its scene and options: give no "
            + ", ".join("scene" if name == "scene" else "--" + name for name in given))
    arrays = read_file(args.resume, CHECKPOINT_FORMAT, "--resume")
    try:
        arguments = json.loads(str(arrays["arguments"]))
        if not isinstance(arguments, dict):
            raise ValueError("its arguments are not a table")
        scene = scene_from_table(tomllib.loads(str(arrays["scene_toml"])))
        frames = int(arrays["frames_done"])
    except (KeyError, TypeError, ValueError, tomllib.TOMLDecodeError) as error:
        raise SceneError("--resume", args.resume, f"holds no readable run ({error})") from None
    scene.validate()
    for name in RUN_OPTIONS:
        if name in SCENE_OPTIONS or getattr(args, name, None) in (None, []):
            setattr(args, name, arguments.get(name, getattr(args, name, None)))
    return Resumed(args.resume, scene, arguments, arrays, frames)


def record_run(simulation, args, out: str, resumed: Resumed | None = None):
    """``springsim run``'s recording: from the start or from the checkpoint ``resumed``, writing
    a checkpoint beside ``out`` every ``args.checkpoint_every`` s when that is given."""
    from .recording import record
    from .sampling import frame_steps
    from .scenefile import scene_to_toml

    checkpoints = None
    if args.checkpoint_every is not None:
        arguments = {**run_arguments(args), "out": out}
        checkpoints = Checkpoints(checkpoint_path(out), args.checkpoint_every, simulation,
                                  arguments, scene_to_toml(simulation.scene))
    start = None
    if resumed is not None:
        frame_count = len(frame_steps(simulation.scene.duration, args.fps, simulation.dt,
                                      simulation.model.particle_count))
        start = resumed.start(simulation, frame_count)
    return record(simulation, simulation.scene.duration, args.fps, progress=not args.quiet,
                  on_frame=checkpoints, start=start)


def run_arguments(args) -> dict:
    """The options of a ``springsim run`` that a checkpoint keeps (RUN_OPTIONS)."""
    return {name: getattr(args, name, None) for name in RUN_OPTIONS}
