"""The `springsim` command line. Each subcommand is one module in ``springsim.commands`` that
defines ``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``; a new command is a
new file there. Modules import their heavy dependencies inside ``run`` so that start-up stays fast.
"""
import argparse
import importlib
import pkgutil
import sys

from . import commands
from .errors import SceneError, SimulationDiverged


def command_modules():
    names = sorted(info.name for info in pkgutil.iter_modules(commands.__path__)
                   if not info.name.startswith("_"))
    return [importlib.import_module(f"{commands.__name__}.{name}") for name in names]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="springsim",
        description="Mass-spring physics: jelly cubes, cloth and balls on terrains, with a choice "
                    "of integrators. `springsim COMMAND --help` tells more.")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in command_modules():
        sub = subparsers.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(sub)
        sub.set_defaults(handler=module.run)
    return parser


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except (SceneError, SimulationDiverged) as error:
        print(f"springsim {args.command}: {error}", file=sys.stderr)
        return 2 if isinstance(error, SceneError) else 3
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
