"""`springsim warmup`: compile every variant of every integrator's kernels now, once, instead of
at first use."""
import time

NAME = "warmup"
VARIANTS = ("serial", "threaded", "keeping")   # Integrator.variants' names
HELP = ("compile (or load) the kernels of every integrator now, serial, threaded and the "
        "gradient's, so that later runs start in seconds (./run.sh and ./test.sh run it the "
        "first time)")


def add_arguments(parser) -> None:
    parser.add_argument("--integrators", nargs="+", metavar="NAME",
                        help="integrators to compile (default: all)")
    parser.add_argument("--variants", nargs="+", metavar="VARIANT",
                        help="the variants to compile: serial, threaded (models of 131,072 "
                             "particles and more), keeping (the gradient's tape) (default: "
                             "all)")
    parser.add_argument("--scene", metavar="SCENE",
                        help="compile only what a run of this scene takes (its integrator's "
                             "step for its model, with --integrators for another), not every "
                             "variant")


def run(args) -> int:
    from ..errors import require
    from ..integrators import integrator_names

    names = args.integrators or integrator_names()
    for name in names:
        require(name in integrator_names(), "--integrators", name,
                "must be one of " + ", ".join(integrator_names()))
    for variant in args.variants or ():
        require(variant in VARIANTS, "--variants", variant,
                "must be one of " + ", ".join(VARIANTS))
    require(args.scene is None or args.variants is None, "--variants", args.variants,
            "goes without --scene (a scene's run takes the variant its model needs)")
    if args.scene is not None:
        from ..scenefile import load_scene

        scene = load_scene(args.scene)
        names = args.integrators or [scene.integrator]
        what = f"the kernels a run of {scene.name} takes"
    else:
        scene = None
        which = ("every variant" if args.variants is None
                 else "the " + ", ".join(args.variants) + " variant"
                 + ("s" if len(args.variants) > 1 else ""))
        what = (f"{which} of the kernels of {len(names)} integrator"
                f"{'s' if len(names) != 1 else ''}")
    print(f"springsim warmup: compiling {what} once (minutes on the first install; seconds "
          "when they are cached)", flush=True)
    warm(names, say=lambda line: print(line, flush=True), scene=scene, variants=args.variants)
    return 0


def warm(integrators, say=print, scene=None, variants=None) -> list:
    """Compile (or load) every kernel each integrator's runs use: a call of no steps on each
    warmup scene (warmup.warmup_scenes: the model's, the step's and the recording's kernels),
    then each variant of the step (serial, threaded, keeping the tape: Integrator.variants) not
    yet compiled (those named in ``variants``), by its arguments' types, without running it.
    With ``scene``, that scene's call alone. (integrator, seconds) for each."""
    from ..compile_notice import announced
    from ..warmup import is_compiled, warmup_scenes

    scenes = warmup_scenes() if scene is None else [scene]
    timings = []
    for integrator in integrators:
        started = time.perf_counter()
        with announced(f"the {integrator} kernels", say=False):
            for each in scenes:
                simulation = _stepped(each, integrator)
                if scene is None:
                    found = simulation.integrator.variants(
                        simulation.model, simulation.state, simulation.dt)
                    for variant, call in found.items():
                        if (variants is None or variant in variants) and not is_compiled(call):
                            call.kernel.compile(_types(call))
        timings.append((integrator, time.perf_counter() - started))
        say(f"  {integrator:<20}{timings[-1][1]:.1f} s")
    return timings


def _stepped(scene, integrator):
    """A simulation of ``scene`` that has compiled (or loaded) its step kernel and those a
    run's recording calls (energies, penetration): a call of no steps compiles the whole step
    kernel, without running it."""
    from ..recording import Recording
    from ..simulation import Simulation

    simulation = Simulation(scene, integrator=integrator)
    simulation.step(0)
    Recording.empty(simulation, 1, 60.0).capture(0, simulation)
    return simulation


def _types(call) -> tuple:
    return tuple(call.kernel.typeof_pyval(argument) for argument in call.arguments)
