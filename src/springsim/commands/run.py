"""`springsim run`: simulate a scene with a progress bar, print a summary, save the frames."""
import re
import sys

NAME = "run"
HELP = "simulate a scene and save its frames (positions, velocities, energies) as an NPZ file"
MAX_DEFAULT_NAME = 120   # bytes of a scene name kept in the default output's name


DEFAULT_FPS = 60.0


def add_arguments(parser) -> None:
    add_scene_arguments(parser, scene_optional=True)   # --resume takes it from the checkpoint
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="simulated time in s (default: the scene's duration)")
    parser.add_argument("--fps", type=float,
                        help=f"frames recorded per simulated second (default: {DEFAULT_FPS:g})")
    parser.add_argument("--out", metavar="PATH",
                        help="the NPZ file to write (default: here, named after the scene file, "
                             "or after the built-in scene)")
    parser.add_argument("--plot", metavar="IMAGE",
                        help="also chart the energies over time (.png, .pdf or .svg)")
    parser.add_argument("--video", metavar="PATH",
                        help="also render the frames as a video (.mp4, .gif, or a folder for "
                             "PNG frames) with springsim.render")
    parser.add_argument("--export", action="append", default=[], metavar="PATH",
                        help="also export the frames: .usd/.usda/.usdc, .mdd or .pc2 (with a "
                             "rest-pose .obj), .obj, NAME_####.obj (an OBJ a frame) "
                             "(repeatable; see `springsim export`)")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bar and no summary (errors are still shown)")
    parser.add_argument("--checkpoint-every", type=float, metavar="SECONDS",
                        help="every SECONDS of wall-clock time, save the run so far to "
                             "OUT.checkpoint.npz (0: after every frame), for --resume; removed "
                             "when the run completes")
    parser.add_argument("--resume", metavar="CHECKPOINT",
                        help="continue the run a checkpoint holds (its scene and options); "
                             "the output is the same as had it never stopped")


def add_scene_arguments(parser, scene_optional: bool = False, recording: bool = False) -> None:
    """The scene and the options that change it, shared with `springsim bench`; ``recording``:
    the command also takes a recording in place of the scene."""
    parser.add_argument("scene", nargs="?" if scene_optional else None,
                        help="a built-in scene (see `springsim scenes`) or a .toml file"
                             + (", or a recording (an NPZ file of `springsim run`)"
                                if recording else ""))
    parser.add_argument("--integrator", help="integrator name (default: the scene's)")
    parser.add_argument("--dt", type=float, metavar="SECONDS",
                        help="time step in s (default: the scene's)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change one key of the scene, e.g. bodies.0.particles_per_edge=7 "
                             "(repeatable; see docs/scene-files.md)")
    parser.add_argument("--threads", type=int, metavar="N",
                        help="most threads a step may use (default: all cores; the results are "
                             "the same for any number)")


def scene_from_arguments(args):
    """The scene with --set applied, then --integrator, --dt and --duration where given."""
    from ..sampling import check_duration
    from ..scenefile import load_scene, toml_value

    if getattr(args, "duration", None) is not None:
        check_duration(args.duration)   # the frame sampler's rule, whatever TOML says of inf
    overrides = list(args.set)
    for key in ("integrator", "dt", "duration"):
        value = getattr(args, key, None)
        if value is not None:
            overrides.append(f"{key}={toml_value(value)}")
    return load_scene(args.scene, overrides)


def run(args) -> int:
    from ..checkpoint import check_interval, open_checkpoint, record_run
    from ..errors import require
    from ..export import check_exports, export_recording, listed
    from ..plots import plot_energy, plot_format
    from ..recording import write_npz
    from ..safe_files import check_output_path
    from ..sampling import plan_frames
    from ..sizes import scene_counts
    from ..simulation import Simulation
    from ..summary import summary_lines

    resumed = open_checkpoint(args) if args.resume else None   # completes args from it
    require(args.scene is not None, "scene", None,
            "give a built-in scene (see `springsim scenes`), a .toml file, or --resume CHECKPOINT")
    args.fps = DEFAULT_FPS if args.fps is None else args.fps
    if args.checkpoint_every is not None:
        check_interval(args.checkpoint_every)
    scene = resumed.scene if resumed else on_frames(scene_from_arguments(args), args.fps)
    if not resumed:
        args.fps = step_fps(scene.dt, args.fps, duration=scene.duration, quiet=args.quiet)
    out = args.out or default_output(output_name(args.scene, scene.name))
    # Every output and the frames' memory are checked before simulating, so that a long run
    # never ends in a typo or an allocation the machine cannot hold.
    check_output_path("--out", out)
    if args.plot:
        check_output_path("--plot", args.plot)
        plot_format(args.plot)
    if args.video:
        from ..render.video import output_format
        check_output_path("--video", args.video,
                          folder=output_format(args.video, key="--video") == "png folder")
    check_exports(args.export, key="--export")
    plan_frames(scene.duration, args.fps, scene.dt, scene_counts(scene)[0])

    simulation = Simulation(scene, threads=args.threads)
    recording = record_run(simulation, args, out, resumed)   # record, with checkpoints
    write_npz(out, recording.arrays())
    remove_checkpoint(out, args, resumed)
    written = [out]
    written += export_recording(recording, args.export, key="--export")
    if args.plot:
        plot_energy(recording, args.plot)
        written.append(args.plot)
    if not args.quiet:
        chosen = [(f"bodies.{i} lattice", body.summary())
                  for i, body in enumerate(scene.bodies) if hasattr(body, "summary")]
        substeps = simulation.substeps()
        if substeps.count > 1:
            chosen.append(("collider substeps", f"{substeps.count} a step: terrains."
                           f"{substeps.terrain} moves up to {substeps.travel:.3g} m a step, "
                           f"{substeps.thickness:.3g} m thick"))
        print("\n".join(summary_lines(recording, chosen)), flush=True)
    if args.video:
        problem = write_video_of(simulation, recording, args.video)
        if problem:
            print(f"springsim run: wrote {listed(written)} but no video: {problem}",
                  file=sys.stderr)
            return 4
        written.append(args.video)
    if not args.quiet:
        print(f"  {'wrote':<22}{listed(written)}")
    return 0


def on_frames(scene, fps: float):
    """``scene`` with a dt that is a frame's step (or a whole fraction or multiple of it) written
    to a few digits taken as that step exactly (sampling.frame_step): --dt 0.016667 at 60 or
    30 fps is 1/60 s, so that the frames lie at the exact frame times on whole steps, where
    `fit` with the same options compares them."""
    from ..sampling import check_fps, frame_step

    check_fps(fps)
    scene.dt = frame_step(scene.dt, fps)
    return scene


def step_fps(dt: float, fps: float, duration: float | None = None, quiet: bool = False) -> float:
    """The frame rate to record at: ``fps``, or one frame a step when a step is longer than a
    frame (1/dt; fps/m for a dt of exactly m frames), said on stderr once the frame count is
    known to be allowed (bad input is one line). Frames between two steps would repeat the
    state before them: a take exported from them stutters (every other frame frozen at
    dt = 2/fps). The fps asked for is checked as asked (``--fps 1e9`` is refused, not turned
    into a frame a step)."""
    from ..sampling import check_fps, frame_count

    check_fps(fps)
    if duration is not None:
        frame_count(duration, fps, dt)
    frames = dt * fps
    if frames <= 1:
        return fps
    rate = fps / round(frames) if round(frames) / fps == dt else 1 / dt
    if not quiet:
        print(f"springsim run: dt = {dt:g} s is longer than 1/fps = {1 / fps:g} s: recording "
              f"a frame at every step, at the steps' own times ({rate:g} fps)", file=sys.stderr)
    return rate


def write_video_of(simulation, recording, path) -> str | None:
    """Render the recorded frames with springsim.render; the reason when it cannot, else None."""
    try:
        from .. import render
    except ImportError as error:
        return f"springsim.render failed to load ({error})"
    unavailable = getattr(render, "RenderUnavailable", ())   # no headless OpenGL here, say
    try:
        render.write_video(simulation.model, recording.time, recording.positions, path,
                           fps=recording.fps)
    except unavailable as error:
        return str(error)
    return None


def output_name(scene_argument: str, scene_name: str) -> str:
    """A scene file's output is named after the file (two files of one scene, or a copy of a
    built-in scene, do not overwrite each other's); a built-in scene's after the scene."""
    from pathlib import Path

    from ..presets import PRESETS

    if scene_argument in PRESETS or not Path(scene_argument).is_file():
        return scene_name
    return Path(scene_argument).stem


def remove_checkpoint(out: str, args, resumed) -> None:
    """The run is complete and its NPZ written: its checkpoint (written with --checkpoint-every,
    or resumed from) has nothing more to give, and goes."""
    import os

    from ..checkpoint import checkpoint_path

    if args.checkpoint_every is None and resumed is None:
        return
    try:
        os.unlink(checkpoint_path(out))
    except FileNotFoundError:
        pass


def default_output(scene_name: str) -> str:
    """``<scene name>.npz`` in the current folder; characters unsafe in a file name become _,
    and a name too long for a file system is shortened."""
    safe = re.sub(r"[^\w.-]+", "_", scene_name)
    safe = safe.encode()[:MAX_DEFAULT_NAME].decode(errors="ignore").strip("._")
    return f"{safe or 'scene'}.npz"
