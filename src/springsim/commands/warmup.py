"""`springsim warmup`: compile every integrator's kernels now, once, instead of at first use."""

NAME = "warmup"
HELP = ("compile (or load) the kernels of every integrator now, so that later runs start in "
        "seconds (./run.sh and ./test.sh run it the first time)")


def add_arguments(parser) -> None:
    parser.add_argument("--integrators", nargs="+", metavar="NAME",
                        help="integrators to compile (default: all)")


def run(args) -> int:
    from ..errors import require
    from ..integrators import integrator_names
    from ..warmup import warm

    names = args.integrators or integrator_names()
    for name in names:
        require(name in integrator_names(), "--integrators", name,
                "must be one of " + ", ".join(integrator_names()))
    print(f"springsim warmup: compiling the kernels of {len(names)} integrator"
          f"{'s' if len(names) != 1 else ''} once (a few minutes on the first install; "
          "seconds when they are cached)", flush=True)
    warm(names, say=lambda line: print(line, flush=True))
    return 0
