"""The `springsim` command line. Each subcommand is one module in ``springsim.commands`` that
defines ``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``; a new command is a
new file there. Modules import their heavy dependencies inside ``run`` so that start-up stays fast.

Ctrl-C and SIGTERM are taken over (signals.py) as the first thing ``main`` does, and before it
this module loads nothing that takes time (argparse, the commands and importlib.metadata load
inside ``main``), so that a signal in the start-up, even a busy machine's, ends in the one line
too: only the interpreter's own start comes before.
"""
import sys

from . import signals
from .signals import Terminated  # noqa: F401 - where callers have always found it

# Exit codes (README, "The command line").
BAD_INPUT, DIVERGED, NO_RENDERER, WRITE_FAILED = 2, 3, 4, 5


def command_modules():
    import importlib
    import pkgutil

    from . import commands

    names = sorted(info.name for info in pkgutil.iter_modules(commands.__path__)
                   if not info.name.startswith("_"))
    return [importlib.import_module(f"{commands.__name__}.{name}") for name in names]


def build_parser():
    import argparse

    from . import __version__

    class OneLineParser(argparse.ArgumentParser):
        """Usage errors as one line too (exit 2), pointing at --help instead of printing usage."""

        def error(self, message):
            self.exit(BAD_INPUT, f"{self.prog}: {message} (see {self.prog} --help)\n")

    parser = OneLineParser(
        prog="springsim",
        description="Mass-spring physics: jelly cubes, cloth and balls on terrains, with a choice "
                    "of integrators. `springsim COMMAND --help` tells more.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}",
                        help="print the version of springsim and exit")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in command_modules():
        sub = subparsers.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(sub)
        sub.set_defaults(handler=module.run)
    return parser


def main(argv=None) -> int:
    # Ctrl-C and SIGTERM are taken over first, before anything that takes time loads (module doc)
    with signals.handled():
        try:
            from .errors import OutputFailed, SceneError, SimulationDiverged

            args = build_parser().parse_args(argv)
            from .compile_notice import announced   # every compile a command makes is said

            try:
                with quiet_overflow(), one_line_warnings(args.command), \
                        announced(f"the kernels `springsim {args.command}` needs",
                                  say=not getattr(args, "quiet", False)):
                    return args.handler(args)
            except (SceneError, SimulationDiverged, OutputFailed) as error:
                print(f"springsim {args.command}: {error}", file=sys.stderr)
                return (BAD_INPUT if isinstance(error, SceneError)
                        else DIVERGED if isinstance(error, SimulationDiverged) else WRITE_FAILED)
        except KeyboardInterrupt as interrupt:
            terminated = isinstance(interrupt, signals.Terminated)
            print("terminated" if terminated else "interrupted", file=sys.stderr)
            _forget_unhandled_interrupt()
            return 128 + (signals.SIGTERM if terminated else signals.SIGINT)


def _forget_unhandled_interrupt() -> None:
    """CPython kills itself with SIGINT at exit, whatever main returns, once a KeyboardInterrupt
    has left code that C ran with PyRun_String (an extension's lazy import); signals.py keeps
    Ctrl-C out of such code, and this is the net under it: the interrupt was handled here."""
    import contextlib
    import ctypes

    with contextlib.suppress(Exception):   # 3.11's flag; elsewhere it is not exported
        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0


def one_line_warnings(command: str):
    """Warnings as one line each, as errors are (Python's own format adds the source line)."""
    import contextlib
    import warnings

    def show(message, category, filename, lineno, file=None, line=None):
        print(f"springsim {command}: warning: {message}", file=sys.stderr)

    @contextlib.contextmanager
    def block():
        with warnings.catch_warnings():
            warnings.showwarning = show
            yield

    return block()


def quiet_overflow():
    """A blowing-up state overflows on its way to the divergence check; that one line is the
    answer, so NumPy's overflow and invalid-value warnings are not printed before it."""
    import numpy as np

    return np.errstate(over="ignore", invalid="ignore", divide="ignore")


if __name__ == "__main__":
    sys.exit(main())
