"""Run by the extension in springsim's own Python, never inside Blender:

    PYTHON worker.py SCENE.toml STREAM.pc2 TAKE.pc2 FPS

simulates the scene exactly as ``springsim run SCENE.toml --fps FPS --export TAKE.pc2`` does (the
same scene loading, frame plan, recording and PC2 export), and on top of it streams every frame
as soon as it is computed into STREAM.pc2, a PC2 of the same points whose sample count grows, for
Blender to show while the run goes on. TAKE.pc2 (with its rest OBJ) is springsim's output, written
whole at the end or not at all. Errors are springsim's one line on stderr with its exit codes
(2: bad input, 3: diverged, 5: a file could not be written).
"""
import importlib.util
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def _own_point_cache():
    """The extension's point_cache.py, loaded from its file: this folder is not put on the path
    (its module names must not shadow those of the Python that runs springsim)."""
    spec = importlib.util.spec_from_file_location("_springsim_blender_point_cache",
                                                  os.path.join(HERE, "point_cache.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class Stream:
    """``record``'s on_frame: appends each new frame's surface points to the stream cache."""

    def __init__(self, path, scene_name):
        self.path, self.scene_name, self.pieces = path, scene_name, None
        self.cache = _own_point_cache()

    def __call__(self, recording, frame):
        from springsim.export.geometry import point_pieces, stacked_vertices
        from springsim.recording_layout import read_layout

        first = frame
        if self.pieces is None:
            layout = read_layout(recording.arrays(), self.scene_name)
            self.pieces = point_pieces(layout, recording.positions[0])
            first = 0
        points = stacked_vertices(self.pieces, recording.positions[first:frame + 1])
        self.cache.append(self.path, points, start_frame=1.0)


def simulate(scene_path, stream_path, take_path, fps) -> None:
    from springsim.commands.run import step_fps
    from springsim.export import check_exports, export_recording
    from springsim.recording import record
    from springsim.sampling import plan_frames
    from springsim.scenefile import load_scene
    from springsim.simulation import Simulation
    from springsim.sizes import scene_counts

    scene = load_scene(scene_path)
    fps = step_fps(scene.dt, fps, duration=scene.duration, quiet=True)
    check_exports([take_path], key="--export")
    plan_frames(scene.duration, fps, scene.dt, scene_counts(scene)[0])
    simulation = Simulation(scene)
    recording = record(simulation, scene.duration, fps, on_frame=Stream(stream_path, scene.name))
    export_recording(recording, [take_path], key="--export")


def main(argv) -> int:
    if sys.path and os.path.abspath(sys.path[0] or os.curdir) == HERE:
        del sys.path[0]
    try:
        from springsim.cli import quiet_overflow
        from springsim.errors import OutputFailed, SceneError, SimulationDiverged
    except ImportError as error:
        print(f"springsim is not installed in {sys.executable} ({error})", file=sys.stderr)
        return 6
    scene_path, stream_path, take_path, fps = argv
    try:
        with quiet_overflow():
            simulate(scene_path, stream_path, take_path, float(fps))
    except SceneError as error:
        print(f"springsim run: {error}", file=sys.stderr)
        return 2
    except SimulationDiverged as error:
        print(f"springsim run: {error}", file=sys.stderr)
        return 3
    except OutputFailed as error:
        print(f"springsim run: {error}", file=sys.stderr)
        return 5
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
