"""`springsim scenes`: the built-in scenes, or one scene as a complete TOML scene file."""

NAME = "scenes"
HELP = ("list the built-in scenes; with a SCENE, print it as a complete TOML scene file "
        "to edit (springsim scenes jelly-bowl > my_scene.toml)")


def add_arguments(parser) -> None:
    parser.add_argument("scene", nargs="?",
                        help="a built-in scene or a .toml file to print in full")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="change one key of the printed scene (repeatable)")
    parser.add_argument("--short", action="store_true",
                        help="print only the keys that differ from their defaults")


def run(args) -> int:
    from ..errors import require
    from ..presets import PRESETS
    from ..scenefile import load_scene, scene_to_toml

    if args.scene is None:
        require(not args.set, "--set", args.set[0] if args.set else None,
                "needs a SCENE to change: springsim scenes SCENE --set KEY=VALUE")
        width = max(len(name) for name in PRESETS)
        for name, (_, description) in PRESETS.items():
            print(f"{name:<{width}}  {description}")
        return 0
    text = scene_to_toml(load_scene(args.scene, args.set), only_changes=args.short)
    print(explain_package_files(text), end="")
    return 0


def explain_package_files(text: str) -> str:
    """A ``file = "..."`` line naming a mesh installed with springsim gets a comment above it:
    the path is this installation's (it works from any folder while springsim stays installed
    there), and how to keep the mesh with the scene instead."""
    from pathlib import Path

    package = str(Path(__file__).resolve().parents[1])
    lines = []
    for line in text.splitlines(keepends=True):
        if line.startswith("file = ") and package in line:
            name = Path(line.split("=", 1)[1].strip().strip('"')).name
            lines.append(f"# {name} is installed with springsim: this absolute path works from "
                         "any folder while springsim\n# stays installed here. To keep the mesh "
                         f"with this scene, copy it beside this file and write file = \"{name}\""
                         "\n# (a relative path is read from the scene file's folder).\n")
        lines.append(line)
    return "".join(lines)
