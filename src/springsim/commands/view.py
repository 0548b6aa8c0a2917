"""`springsim view [SCENE]`: the interactive viewer with the course framework's control panel."""
import sys

NAME = "view"
HELP = ("open a window showing a scene live, with a control panel (integrator, dt, springs, "
        "contact, terrain, draw toggles, recording) and Ctrl + drag to pull a particle")


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?", default="jelly-plane",
                        help="a built-in scene or a .toml file (default: jelly-plane)")
    parser.add_argument("--integrator", help="integrator name (default: the scene's)")
    parser.add_argument("--dt", type=float, metavar="SECONDS", help="time step in s")
    parser.add_argument("--threads", type=int, metavar="N",
                        help="most threads a step may use (default: all cores; the results are "
                             "the same for any number)")
    parser.add_argument("--width", type=int, default=1280, help="window width in pixels")
    parser.add_argument("--height", type=int, default=800, help="window height in pixels")
    parser.add_argument("--start", action="store_true", help="start simulating at once")
    parser.add_argument("--record-folder", default=".", metavar="FOLDER",
                        help="where the Record button writes its MP4 files (default: here)")
    parser.add_argument("--frames", type=int, metavar="N",
                        help="close by itself after N frames (for scripts and tests)")
    parser.add_argument("--screenshot", metavar="PNG",
                        help="after the last frame, save the window (panel included) as a PNG")


def run(args) -> int:
    from ..errors import require
    from ..render import RenderUnavailable
    from ..render.video import check_frame_size
    from ..safe_files import check_output_folder, check_output_path
    from ..viewer.controls import Controls

    check_frame_size(args.width, args.height)
    check_output_folder("--record-folder", args.record_folder)
    if args.screenshot:
        check_output_path("--screenshot", args.screenshot)
    require(args.frames is None or args.frames >= 0, "--frames", args.frames, "must be >= 0")
    controls = Controls(args.scene, integrator=args.integrator, dt=args.dt,
                        threads=args.threads)
    try:
        from ..viewer.window import Viewer

        viewer = Viewer(controls, width=args.width, height=args.height,
                        record_folder=args.record_folder)
    except RenderUnavailable as error:
        print(f"springsim view: {error}", file=sys.stderr)
        return 4
    if args.start:
        controls.start()
    print(f"springsim view: {controls.scene_name} in a {args.width} x {args.height} window "
          f"({viewer.backend})", flush=True)
    try:
        viewer.run(args.frames)
    finally:
        recorded = viewer.close()
        if recorded is not None:
            print(f"wrote {recorded}")
    if args.screenshot:
        save_screenshot(args.screenshot)
        print(f"wrote {args.screenshot}")
    return 0


def save_screenshot(path) -> None:
    import imageio.v3 as iio

    from ..render.backend import capture
    from ..safe_files import atomic_output

    with atomic_output(path) as file:
        iio.imwrite(file, capture(include_ui=True), extension=".png")
