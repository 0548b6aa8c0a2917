"""`springsim warmup`: compile every integrator's kernels now, once, instead of at first use."""
import time

NAME = "warmup"
HELP = ("compile (or load) the kernels of every integrator now, so that later runs start in "
        "seconds (./run.sh and ./test.sh run it the first time)")


def add_arguments(parser) -> None:
    parser.add_argument("--integrators", nargs="+", metavar="NAME",
                        help="integrators to compile (default: all)")


def run(args) -> int:
    from ..errors import require
    from ..integrators import integrator_names

    names = args.integrators or integrator_names()
    for name in names:
        require(name in integrator_names(), "--integrators", name,
                "must be one of " + ", ".join(integrator_names()))
    print(f"springsim warmup: compiling the kernels of {len(names)} integrator"
          f"{'s' if len(names) != 1 else ''} once (a few minutes on the first install; "
          "seconds when they are cached)", flush=True)
    warm(names, say=lambda line: print(line, flush=True))
    return 0


def warm(integrators, say=print) -> list:
    """Compile (or load) every kernel a run of each integrator uses: one step of a small jelly
    cube on the plane and of a small cloth on a ball; (integrator, seconds) for each."""
    from ..scenefile import load_scene
    from ..simulation import Simulation
    from ..warmup import announced

    scenes = [load_scene("jelly-plane", ["bodies.0.particles_per_edge=3"]),
              load_scene("cloth-balls", ["bodies.0.particles_per_edge=4"])]
    timings = []
    for integrator in integrators:
        started = time.perf_counter()
        with announced(integrator, say=False):
            for scene in scenes:
                simulation = Simulation(scene, integrator=integrator)
                simulation.step(1)
                simulation.energy()
        timings.append((integrator, time.perf_counter() - started))
        say(f"  {integrator:<20}{timings[-1][1]:.1f} s")
    return timings
