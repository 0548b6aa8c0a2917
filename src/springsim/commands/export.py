"""`springsim export RUN.npz OUT`: a recording to USD, MDD or PC2 (with a rest-pose OBJ), or OBJ."""
import sys

NAME = "export"
HELP = ("export a recording (the NPZ of `springsim run`) for Blender, Houdini or Omniverse: "
        ".usd/.usda/.usdc, .mdd or .pc2 (with a rest-pose .obj beside it), or .obj")


def add_arguments(parser) -> None:
    parser.add_argument("recording", help="an NPZ file written by `springsim run`")
    parser.add_argument("out", nargs="+", metavar="OUT",
                        help="file(s) to write; the extension picks the format")
    parser.add_argument("--quiet", action="store_true", help="print nothing when it works")


def run(args) -> int:
    from ..export import check_target, export, load_take

    # every target is checked before the recording is read: a typo costs nothing
    for path in args.out:
        check_target(path, key="OUT")
    take = load_take(args.recording)
    warn_if_legacy(take, "export")
    written = []
    for path in args.out:
        written += export(take, path, key="OUT")
    if not args.quiet:
        print(f"wrote {', '.join(map(str, written))}: {take.frame_count} frames at "
              f"{take.fps:g} fps")
    return 0


def warn_if_legacy(take, command: str) -> None:
    if take.layout.legacy:
        print(f"springsim {command}: {take.name}: a recording from before springsim kept its "
              "bodies' layout: its surface is one mesh, and balls and terrains are left out "
              "(record it again for them)", file=sys.stderr)
