"""`springsim bench`: how fast an integrator advances a scene."""
import json

from .run import add_scene_arguments, scene_from_arguments

NAME = "bench"
HELP = "time an integrator on a scene: steps/s, ms per step, real-time factor, build time, memory"
MAX_STEPS = 10 ** 9        # a billion steps: days for a large model, hours for a small one
MAX_SECONDS = 3600.0       # wall seconds of timing


def add_arguments(parser) -> None:
    add_scene_arguments(parser)
    length = parser.add_mutually_exclusive_group()
    length.add_argument("--steps", type=int, metavar="N",
                        help="time N steps in one compiled call (for very large models)")
    length.add_argument("--seconds", type=float, metavar="S",
                        help="time whole calls for about S wall seconds (default: 3)")
    parser.add_argument("--json", action="store_true",
                        help="print the figures as one JSON object")


def run(args) -> int:
    from ..benchmark import benchmark
    from ..errors import is_finite, require

    require(args.steps is None or 1 <= args.steps <= MAX_STEPS, "steps", args.steps,
            f"must be a whole number of steps from 1 to {MAX_STEPS:,}")
    require(args.seconds is None or (is_finite(args.seconds) and 0 < args.seconds <= MAX_SECONDS),
            "seconds", args.seconds, f"must be > 0 s and at most {MAX_SECONDS:g} s")
    result = benchmark(scene_from_arguments(args), steps=args.steps, seconds=args.seconds,
                       threads=args.threads)
    print(json.dumps(result) if args.json else "\n".join(report_lines(result)))
    return 0


def report_lines(result: dict) -> list[str]:
    memory = result["peak_memory_mb"]
    rows = [
        ("steps/s", _figure(result["steps_per_second"])),
        ("ms per step", f"{result['ms_per_step']:.4g}"),
        ("real-time factor", f"{result['real_time_factor']:.3g} (simulated s per wall s)"),
        ("timed", f"{result['steps']} steps in {result['wall_seconds']:.3g} s"),
        ("model build", f"{result['build_seconds']:.3g} s"),
        ("warm-up", f"{result['warmup_seconds']:.3g} s (compiling, or loading the cache)"),
        ("peak memory", "unknown" if memory is None else f"{memory:.0f} MB"),
    ]
    heading = (f"{result['scene']}: {result['integrator']}, dt = {result['dt']:g} s, "
               f"{result['particles']} particles, {result['springs']} springs, "
               f"{result['threads']} thread(s) allowed")
    return [heading] + [f"  {label:<18}{text}" for label, text in rows]


def _figure(value: float) -> str:
    """Large rates as whole numbers (46163, not 4.616e+04), small ones to four digits."""
    return f"{value:.0f}" if value >= 1000 else f"{value:.4g}"
