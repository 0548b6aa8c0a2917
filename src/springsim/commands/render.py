"""`springsim render SCENE --out FILE`: simulate a scene and render it to a video, headless."""
import sys

from .run import add_scene_arguments

NAME = "render"
HELP = ("simulate a scene and render it with no display to .mp4, .gif or a folder of PNGs "
        "(the viewer's drawing, polyscope on EGL)")
DRAWABLE = ("surfaces", "particles", "structural", "shear", "bend", "face", "balls", "terrains",
            "contacts")


def add_arguments(parser) -> None:
    add_scene_arguments(parser)
    parser.add_argument("--out", required=True, metavar="PATH",
                        help="FILE.mp4, FILE.gif, or a folder for PNG frames")
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="simulated time in s (default: the scene's duration)")
    parser.add_argument("--fps", type=float, default=30.0,
                        help="video frames per second; frame k is the state after round(k/(fps dt)) "
                             "steps (default: 30)")
    parser.add_argument("--width", type=int, default=960, help="pixels (default: 960)")
    parser.add_argument("--height", type=int, default=540, help="pixels (default: 540)")
    parser.add_argument("--camera", default="auto",
                        help="auto (frames the bodies' whole motion and the terrain near them), "
                             "front, side, top, or follow (moves with the bodies)")
    parser.add_argument("--draw", default="surfaces,balls,terrains",
                        help="comma-separated parts to draw, among " + ", ".join(DRAWABLE)
                             + " (default: surfaces,balls,terrains)")
    parser.add_argument("--quiet", action="store_true", help="no progress bars and no summary")


def run(args) -> int:
    from ..errors import require
    from ..render import CAMERA_NAMES, DrawOptions, RenderUnavailable, render_video
    from ..render.frames import simulate_frames
    from ..render.video import check_output
    from ..sampling import plan_frames
    from ..simulation import Simulation
    from ..sizes import scene_counts
    from .run import scene_from_arguments

    # everything is checked before simulating, so that a long run never ends in a typo
    require(args.camera in CAMERA_NAMES, "--camera", args.camera,
            "must be one of " + ", ".join(CAMERA_NAMES))
    draw = DrawOptions.only([name.strip() for name in args.draw.split(",") if name.strip()])
    check_output(args.out, args.width, args.height, args.fps, key="--out")
    scene = scene_from_arguments(args)
    plan_frames(scene.duration, args.fps, scene.dt, scene_counts(scene)[0])
    sim = Simulation(scene, threads=args.threads)
    times, positions = simulate_frames(sim, sim.scene.duration, args.fps,
                                       progress=not args.quiet)
    try:
        path = render_video(sim.model, times, positions, args.out, fps=args.fps,
                            width=args.width, height=args.height, camera=args.camera, draw=draw,
                            progress=not args.quiet)
    except RenderUnavailable as error:
        print(f"springsim render: {error}", file=sys.stderr)
        return 4
    if not args.quiet:
        print(f"wrote {path}: {len(times)} frames of {args.width} x {args.height} px, "
              f"{times[-1]:.3g} s simulated")
    return 0
