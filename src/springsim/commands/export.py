"""`springsim export RUN.npz OUT`: a recording (or a scene, simulated first) to USD, MDD or PC2
(with a rest-pose OBJ), OBJ, or an OBJ a frame."""
import sys
from dataclasses import replace

from ..export.take import START_FRAME

NAME = "export"
HELP = ("export a recording (the NPZ of `springsim run`), or a scene simulated first, for "
        "Blender, Houdini or Omniverse: .usd/.usda/.usdc, .mdd or .pc2 (with a rest-pose .obj "
        "beside it), .obj, or an OBJ sequence (NAME_####.obj)")


def add_arguments(parser) -> None:
    parser.add_argument("recording", help="an NPZ file written by `springsim run`, or a scene "
                        "(built-in or .toml) to simulate with its own settings first")
    parser.add_argument("out", nargs="+", metavar="OUT",
                        help="file(s) to write; the ending picks the format (NAME_####.obj: "
                        "an OBJ a frame, the #s replaced by the frame number)")
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="a scene's simulated time in s, or the part of a recording to "
                             "export (default: the whole)")
    parser.add_argument("--fps", type=float,
                        help="frames per second of the files (default: the recording's); other "
                             "rates interpolate linearly between recorded frames")
    parser.add_argument("--start-frame", type=int, default=START_FRAME, metavar="N",
                        help=f"the first frame's number (USD time code, PC2 start frame; "
                             f"default: {START_FRAME}, Blender's and Houdini's first frame)")
    parser.add_argument("--quiet", action="store_true", help="print nothing when it works")


def run(args) -> int:
    from ..export import check_target, export, listed, resampled
    from ..sampling import check_fps

    if args.fps is not None:
        check_fps(args.fps)

    # every target is checked before the recording is read: a typo costs nothing
    for path in args.out:
        module = check_target(path, key="OUT")
        if hasattr(module, "check_start_frame"):   # a format that numbers files by frame
            module.check_start_frame(path, args.start_frame, "--start-frame")
    take = read_take(args)
    if args.fps is not None and (args.fps != take.fps or args.duration is not None):
        take = resampled(take, args.fps, args.duration)
    take = replace(take, start_frame=args.start_frame)
    written = []
    for path in args.out:
        written += export(take, path, key="OUT")
    if not args.quiet:
        print(f"wrote {listed(written)}: {take.frame_count} frames at "
              f"{take.fps:g} fps from frame {take.start_frame}")
    return 0


def read_take(args):
    """The recording ``args.recording`` names, or the scene it names simulated first."""
    from ..export import names_recording, load_take, resampled, take_from_arrays
    from ..sampling import check_duration

    if args.duration is not None:
        check_duration(args.duration)
    if names_recording(args.recording):
        take = load_take(args.recording)
        warn_if_legacy(take, "export")
        return take if args.duration is None else resampled(take, take.fps, args.duration)
    from ..recording import record
    from ..scenefile import load_scene
    from ..simulation import Simulation
    from .run import DEFAULT_FPS, on_frames

    fps = DEFAULT_FPS if args.fps is None else args.fps
    scene = on_frames(load_scene(args.recording, [] if args.duration is None
                                 else [f"duration={args.duration!r}"]), fps)
    recording = record(Simulation(scene), scene.duration, fps, progress=not args.quiet)
    return take_from_arrays(recording.arrays(), scene.name)


def warn_if_legacy(take, command: str) -> None:
    if take.layout.legacy:
        print(f"springsim {command}: {take.name}: a recording from before springsim kept its "
              "bodies' layout: its surface is one mesh, and balls and terrains are left out "
              "(record it again for them)", file=sys.stderr)
