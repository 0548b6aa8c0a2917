"""`springsim warmup`: compile every variant of every integrator's kernels now, once, instead of
at first use."""
NAME = "warmup"
VARIANTS = ("serial", "plain", "threaded", "keeping")   # Integrator.variants' names
HELP = ("compile (or load) the kernels of every integrator now, serial, threaded and the "
        "gradient's, so that later runs start in seconds (./run.sh and ./test.sh run it the "
        "first time)")


def add_arguments(parser) -> None:
    parser.add_argument("--integrators", nargs="+", metavar="NAME",
                        help="integrators to compile (default: all)")
    parser.add_argument("--variants", nargs="+", metavar="VARIANT",
                        help="the variants to compile: serial, plain (the serial step of a "
                             "model with no body contact, balls, pins, attachments, terms or "
                             "mesh terrains), threaded (models of 131,072 particles and more), "
                             "keeping (the gradient's tape) (default: all)")
    parser.add_argument("--scene", metavar="SCENE",
                        help="compile only what a run of this scene takes (its integrator's "
                             "step for its model, with --integrators for another), not every "
                             "variant")
    parser.add_argument("--jobs", type=int, metavar="N",
                        help="processes that compile at once (default: one per core)")


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
    require(args.jobs is None or args.jobs >= 1, "--jobs", args.jobs,
            "must be a whole number >= 1")
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
    warm(names, say=lambda line: print(line, flush=True), scene=scene, variants=args.variants,
         jobs=args.jobs)
    return 0


def warm(integrators, say=print, scene=None, variants=None, jobs=None) -> list:
    """Compile (or load) every kernel each integrator's runs use, on ``jobs`` processes (one
    per core by default; warmup.py): the parts every step calls, then each integrator's step
    on each warmup scene (warmup.warmup_scenes: the model's, the step's and the recording's
    kernels) with each variant of it (serial, threaded, keeping the tape:
    Integrator.variants) not yet compiled (those named in ``variants``). With ``scene``, what
    that scene's run calls alone. (integrator, seconds) for each, the parts first."""
    from ..warmup import compile_jobs, part_tasks, run_tasks, step_tasks, warmup_scenes

    scenes = warmup_scenes() if scene is None else [scene]
    jobs = compile_jobs() if jobs is None else jobs
    parts = run_tasks(part_tasks(integrators, scenes), jobs, say)
    steps = run_tasks(step_tasks(integrators, scenes, () if scene is not None else variants),
                      jobs, say)
    timings = [("the steps' parts", sum(seconds for _, seconds in parts))]
    timings += [(task.integrator, seconds) for task, seconds in steps]
    for name, seconds in timings:
        say(f"  {name:<20}{seconds:.1f} s")
    return timings
