"""`springsim play RUN.npz`: replay a recording in the viewer (or, with --web, in a browser)."""
import sys

NAME = "play"
HELP = ("replay a recording (the NPZ of `springsim run`) in the viewer: play, pause, scrub, "
        "speed, loop, energy plot, draw toggles; --web serves it to a browser")


def add_arguments(parser) -> None:
    parser.add_argument("recording", help="an NPZ file written by `springsim run`")
    parser.add_argument("--speed", type=float, default=1.0,
                        help="playback speed, 1 = as recorded (default: 1)")
    parser.add_argument("--no-loop", action="store_true", help="stop at the last frame")
    parser.add_argument("--paused", action="store_true", help="start paused on the first frame")
    parser.add_argument("--width", type=int, default=1280, help="window width in pixels")
    parser.add_argument("--height", type=int, default=800, help="window height in pixels")
    parser.add_argument("--frames", type=int, metavar="N",
                        help="close by itself after N drawn frames (for scripts and tests)")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="after the last frame, save the window (panel included) as a PNG")
    parser.add_argument("--web", action="store_true",
                        help="serve the replay to a browser (viser) instead of opening a window")
    parser.add_argument("--host", default="127.0.0.1",
                        help="with --web: address to listen on (default: 127.0.0.1; forward the "
                             "port to reach it from elsewhere)")
    parser.add_argument("--port", type=int, default=8080, help="with --web: port (default: 8080)")
    parser.add_argument("--seconds", type=float, metavar="S",
                        help="with --web: stop serving after S seconds (for scripts and tests)")


def run(args) -> int:
    import math

    from ..errors import require
    from ..export import load_take
    from .export import warn_if_legacy

    require(math.isfinite(args.speed) and args.speed > 0, "--speed", args.speed, "must be > 0")
    if args.screenshot:
        from ..safe_files import check_output_path
        check_output_path("--screenshot", args.screenshot)
    take = load_take(args.recording)
    warn_if_legacy(take, "play")
    if args.web:
        from ..replay.web import serve
        return serve(take, host=args.host, port=args.port, speed=args.speed,
                     loop=not args.no_loop, playing=not args.paused, seconds=args.seconds)
    return play_in_window(take, args)


def play_in_window(take, args) -> int:
    from ..render import RenderUnavailable

    try:
        from ..replay.window import ReplayViewer

        viewer = ReplayViewer(take, width=args.width, height=args.height,
                              loop=not args.no_loop, speed=args.speed)
    except RenderUnavailable as error:
        print(f"springsim play: {error}", file=sys.stderr)
        return 4
    if not args.paused:
        viewer.timeline.play()
    print(f"springsim play: {take.name}, {take.frame_count} frames at {take.fps:g} fps in a "
          f"{args.width} x {args.height} window ({viewer.backend})", flush=True)
    viewer.run(args.frames)
    if args.screenshot:
        from .view import save_screenshot
        save_screenshot(args.screenshot)
        print(f"wrote {args.screenshot}")
    return 0
