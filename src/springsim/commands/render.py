"""`springsim render SCENE --out FILE`: simulate a scene (or read a recording) and render it to a
video, headless."""
import sys

from .run import add_scene_arguments

NAME = "render"
HELP = ("simulate a scene, or read a recording (the NPZ of `springsim run`), and render it with no "
        "display to .mp4, .gif or a folder of PNGs "
        "(the viewer's drawing, polyscope on EGL)")
DEFAULT_FPS = 30.0
DRAWABLE = ("surfaces", "particles", "structural", "shear", "bend", "face", "balls", "terrains",
            "pins", "wind", "contacts")


def add_arguments(parser) -> None:
    add_scene_arguments(parser, recording=True)
    parser.add_argument("--out", required=True, metavar="PATH",
                        help="FILE.mp4, FILE.gif, or a folder for PNG frames")
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="simulated time in s (default: the scene's duration)")
    parser.add_argument("--fps", type=float,
                        help="video frames per second; frame k is the state after round(k/(fps dt)) "
                             "steps, or a recording's frames interpolated at k / fps (default: 30 "
                             "for a scene, the recording's rate for a recording)")
    parser.add_argument("--width", type=int, default=960, help="pixels (default: 960)")
    parser.add_argument("--height", type=int, default=540, help="pixels (default: 540)")
    parser.add_argument("--camera", default="auto",
                        help="auto (frames what moves and follows it, facing the side of the "
                             "bodies that the terrains moving with them leave open), front, side "
                             "or top (follow it from those sides), still (stays put, framing the "
                             "whole motion), or follow (the same as auto) (default: auto)")
    parser.add_argument("--draw", default="surfaces,balls,terrains,pins,wind",
                        help="comma-separated parts to draw, among " + ", ".join(DRAWABLE)
                             + " (default: surfaces,balls,terrains,pins,wind)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars and no summary")


def run(args) -> int:
    from ..errors import require
    from ..render import CAMERA_NAMES, DrawOptions, RenderUnavailable, render_video
    from ..render.frames import simulate_frames
    from ..render.video import check_output
    from ..sampling import plan_frames
    from ..simulation import Simulation
    from ..sizes import scene_counts
    from ..export import names_recording
    from .run import scene_from_arguments

    # everything is checked before simulating, so that a long run never ends in a typo
    require(args.camera in CAMERA_NAMES, "--camera", args.camera,
            "must be one of " + ", ".join(CAMERA_NAMES))
    draw = DrawOptions.only([name.strip() for name in args.draw.split(",") if name.strip()])
    if names_recording(args.scene):
        model, times, positions, args.fps = recorded_frames(args)
        check_output(args.out, args.width, args.height, args.fps, key="--out")
    else:
        args.fps = DEFAULT_FPS if args.fps is None else args.fps
        check_output(args.out, args.width, args.height, args.fps, key="--out")
        scene = scene_from_arguments(args)
        plan_frames(scene.duration, args.fps, scene.dt, scene_counts(scene)[0])
        sim = Simulation(scene, threads=args.threads)
        model = sim.model
        if not args.quiet and not sys.stderr.isatty():   # a log: one line, not a bar
            print(f"simulating {scene.name} for {scene.duration:g} s", flush=True)
        times, positions = simulate_frames(sim, sim.scene.duration, args.fps,
                                           progress=not args.quiet)
    try:
        path = render_video(model, times, positions, args.out, fps=args.fps,
                            width=args.width, height=args.height, camera=args.camera, draw=draw,
                            progress=not args.quiet)
    except RenderUnavailable as error:
        print(f"springsim render: {error}", file=sys.stderr)
        return 4
    if not args.quiet:
        print(f"wrote {path}: {len(times)} frames of {args.width} x {args.height} px, "
              f"{times[-1]:.3g} s simulated")
    return 0


def recorded_frames(args):
    """The model, times, positions and fps of the recording ``args.scene`` names, at --fps and
    up to --duration where given; the options that change a scene are refused with one line."""
    from ..errors import require
    from ..export import load_take, resampled
    from ..replay.recorded_model import recorded_model
    from ..sampling import check_duration
    from .export import warn_if_legacy

    for option, value in (("--integrator", args.integrator), ("--dt", args.dt),
                          ("--set", args.set or None)):
        require(value is None, option, value, f"changes a scene; {args.scene} is a recording, "
                "whose frames are already simulated (record it again with `springsim run`)")
    if args.duration is not None:
        check_duration(args.duration)
    take = load_take(args.scene, key="scene")
    warn_if_legacy(take, "render")
    take = resampled(take, take.fps if args.fps is None else args.fps, args.duration)
    return recorded_model(take), take.time, take.positions, take.fps
