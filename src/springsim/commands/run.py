"""`springsim run`: simulate a scene with a progress bar, print a summary, save the frames."""
import os
import re
import sys

NAME = "run"
HELP = "simulate a scene and save its frames (positions, velocities, energies) as an NPZ file"


def add_arguments(parser) -> None:
    add_scene_arguments(parser)
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="simulated time in s (default: the scene's duration)")
    parser.add_argument("--fps", type=float, default=60.0,
                        help="frames recorded per simulated second (default: 60)")
    parser.add_argument("--out", metavar="PATH",
                        help="the NPZ file to write (default: SCENE_NAME.npz here)")
    parser.add_argument("--plot", metavar="IMAGE",
                        help="also chart the energies over time (.png, .pdf or .svg)")
    parser.add_argument("--video", metavar="PATH",
                        help="also render the frames as a video (.mp4, .gif, or a folder for "
                             "PNG frames) with springsim.render")
    parser.add_argument("--export", action="append", default=[], metavar="PATH",
                        help="also export the frames: .usd/.usda/.usdc, .mdd or .pc2 (with a "
                             "rest-pose .obj), .obj (repeatable; see `springsim export`)")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bar and no summary (errors are still shown)")


def add_scene_arguments(parser) -> None:
    """The scene and the options that change it, shared with `springsim bench`."""
    parser.add_argument("scene", help="a built-in scene (see `springsim scenes`) or a .toml file")
    parser.add_argument("--integrator", help="integrator name (default: the scene's)")
    parser.add_argument("--dt", type=float, metavar="SECONDS",
                        help="time step in s (default: the scene's)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change one key of the scene, e.g. bodies.0.particles_per_edge=7 "
                             "(repeatable; see docs/scene-files.md)")


def scene_from_arguments(args):
    """The scene with --set applied, then --integrator, --dt and --duration where given."""
    from ..scenefile import load_scene, toml_value

    overrides = list(args.set)
    for key in ("integrator", "dt", "duration"):
        value = getattr(args, key, None)
        if value is not None:
            overrides.append(f"{key}={toml_value(value)}")
    return load_scene(args.scene, overrides)


def run(args) -> int:
    from ..export import check_exports, export_recording
    from ..plots import plot_energy, plot_format
    from ..recording import record, write_npz
    from ..simulation import Simulation
    from ..summary import summary_lines

    scene = scene_from_arguments(args)
    out = args.out or default_output(scene.name)
    # Every output is checked before simulating, so that a long run never ends in a typo.
    for option, path in (("--out", out), ("--plot", args.plot), ("--video", args.video)):
        if path:
            check_output_path(option, path)
    if args.plot:
        plot_format(args.plot)
    if args.video:
        from ..render.video import output_format
        output_format(args.video, key="--video")
    check_exports(args.export, key="--export")

    simulation = Simulation(scene)
    recording = record(simulation, scene.duration, args.fps, progress=not args.quiet)
    write_npz(out, recording.arrays())
    written = [out]
    written += export_recording(recording, args.export, key="--export")
    if args.plot:
        plot_energy(recording, args.plot)
        written.append(args.plot)
    if not args.quiet:
        print("\n".join(summary_lines(recording)), flush=True)
    if args.video:
        problem = write_video_of(simulation, recording, args.video)
        if problem:
            print(f"springsim run: wrote {', '.join(written)} but no video: {problem}",
                  file=sys.stderr)
            return 4
        written.append(args.video)
    if not args.quiet:
        print(f"  {'wrote':<22}{', '.join(written)}")
    return 0


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


def default_output(scene_name: str) -> str:
    """``<scene name>.npz`` in the current folder; characters unsafe in a file name become _."""
    safe = re.sub(r"[^\w.-]+", "_", scene_name).strip("._")
    return f"{safe or 'scene'}.npz"


def check_output_path(option: str, path: str) -> None:
    """The folder a file goes to must exist (a video may also be a folder of PNG frames)."""
    from ..errors import require

    folder = os.path.dirname(os.path.abspath(path))
    require(os.path.isdir(folder), option, path, f"the folder {folder} does not exist")
    require(option == "--video" or not os.path.isdir(path), option, path,
            "is a folder; give a file name")
