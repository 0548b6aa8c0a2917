"""`springsim render SCENE --out FILE`: simulate a scene and render it to a video, headless."""
import sys

NAME = "render"
HELP = ("simulate a scene and render it with no display to .mp4, .gif or a folder of PNGs "
        "(the viewer's drawing, polyscope on EGL)")
DRAWABLE = ("surfaces", "particles", "structural", "shear", "bend", "face", "balls", "terrains")


def add_arguments(parser) -> None:
    parser.add_argument("scene", help="a built-in scene name or a scene file")
    parser.add_argument("--out", required=True,
                        help="output: FILE.mp4, FILE.gif, or a folder for PNG frames")
    parser.add_argument("--duration", type=float, default=None,
                        help="simulated seconds (default: the scene's duration)")
    parser.add_argument("--fps", type=float, default=30.0, help="frames per second (default 30)")
    parser.add_argument("--width", type=int, default=960, help="pixels (default 960)")
    parser.add_argument("--height", type=int, default=540, help="pixels (default 540)")
    parser.add_argument("--camera", default="auto",
                        help="auto (frames the whole motion), front, side, top, or follow "
                             "(moves with the bodies)")
    parser.add_argument("--draw", default="surfaces,balls,terrains",
                        help="comma-separated parts to draw, among " + ", ".join(DRAWABLE)
                             + " (default surfaces,balls,terrains)")
    parser.add_argument("--integrator", default=None, help="integrator (default: the scene's)")
    parser.add_argument("--dt", type=float, default=None, help="time step in s")


def run(args) -> int:
    import springsim
    from springsim.render import (CAMERA_NAMES, DrawOptions, RenderUnavailable, record,
                                  render_video)
    from springsim.render.video import check_output
    from springsim.errors import require

    require(args.camera in CAMERA_NAMES, "camera", args.camera,
            "must be one of " + ", ".join(CAMERA_NAMES))
    draw = DrawOptions.only([name.strip() for name in args.draw.split(",") if name.strip()])
    check_output(args.out, args.width, args.height, args.fps)
    sim = springsim.Simulation(springsim.load_scene(args.scene), integrator=args.integrator,
                               dt=args.dt)
    duration = sim.scene.duration if args.duration is None else args.duration
    times, positions = record(sim, duration, args.fps)
    try:
        path = render_video(sim.model, times, positions, args.out, fps=args.fps,
                            width=args.width, height=args.height, camera=args.camera, draw=draw)
    except RenderUnavailable as error:
        print(f"springsim render: {error}", file=sys.stderr)
        return 4
    print(f"wrote {path} ({len(times)} frames, {args.width} x {args.height} px, "
          f"{times[-1]:.3g} s simulated)")
    return 0
