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
                        help="print only the keys that differ from their defaults, and dt (a file "
                             "without dt gets one chosen from its springs)")


def run(args) -> int:
    from ..errors import require
    from ..presets import PRESETS
    from ..scenefile import load_scene, scene_to_toml, with_builtin_mesh_names

    if args.scene is None:
        require(not args.set, "--set", args.set[0] if args.set else None,
                "needs a SCENE to change: springsim scenes SCENE --set KEY=VALUE")
        width = max(len(name) for name in PRESETS)
        for name, (_, description) in PRESETS.items():
            print(f"{name:<{width}}  {description}")
        return 0
    scene = with_builtin_mesh_names(load_scene(args.scene, args.set))
    print(explain_builtin_meshes(scene_to_toml(scene, only_changes=args.short)), end="")
    return 0


def explain_builtin_meshes(text: str) -> str:
    """The first ``file = "builtin:NAME"`` line gets a comment above it: what it is, and how to
    use a mesh of one's own instead."""
    from ..scenefile import BUILTIN_MESH

    lines, said = [], False
    for line in text.splitlines(keepends=True):
        if line.startswith(f'file = "{BUILTIN_MESH}') and not said:
            said = True
            lines.append("# builtin:NAME is a file springsim installs (or makes once, as the "
                         "walking figure), found from\n# any folder; a path of your own is read "
                         "from this file's folder (file = \"my_mesh.obj\" beside it)\n")
        lines.append(line)
    return "".join(lines)
