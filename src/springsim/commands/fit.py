"""`springsim fit`: fit scene parameters to observed motion (gradients/fit.py)."""
import json

NAME = "fit"
HELP = ("fit scene parameters (spring constants, masses, gravity, drag, ...) to an observed "
        "take (.npz) or marker tracks (.csv) with exact gradients and L-BFGS-B")


def add_arguments(parser) -> None:
    from .run import add_scene_arguments

    add_scene_arguments(parser)
    parser.add_argument("--observed", required=True, metavar="PATH",
                        help="the observed motion: a springsim NPZ take (every particle, every "
                             "frame) or a CSV of time,marker,x,y,z rows")
    parser.add_argument("--fit", action="append", required=True, metavar="KEY",
                        help="a parameter to fit, e.g. bodies.0.structural.ks (repeatable; "
                             "see docs/guide/gradients.md)")
    parser.add_argument("--duration", type=float, metavar="SECONDS",
                        help="simulated time in s (default: the observation's last time)")
    parser.add_argument("--fps", type=float,
                        help="the frame rate a --dt that rounds a frame's step is read against, "
                             "as `run` reads it (default: the take's, else 60); the "
                             "observation's own times are compared")
    parser.add_argument("--match", choices=("nearest", "index"), default="nearest",
                        help="how a CSV marker is tied to a particle (default: nearest at the "
                             "start)")
    parser.add_argument("--max-iterations", type=int, default=50, metavar="N",
                        help="L-BFGS-B iterations at most (default 50)")
    parser.add_argument("--tolerance", type=float, default=1e-10,
                        help="stop when the loss changes relatively less (default 1e-10)")
    parser.add_argument("--out", metavar="PATH",
                        help="the fitted scene's TOML file (default: SCENE_NAME-fit.toml)")
    parser.add_argument("--plot", metavar="IMAGE",
                        help="also chart the loss per iteration and the fitted against the "
                             "observed motion (.png, .pdf or .svg)")


def run(args) -> int:
    from ..errors import require
    from ..gradients.fit import check_tolerance, fit
    from ..gradients.losses import observed
    from ..safe_files import atomic_output, check_output_path
    from ..scenefile import scene_to_toml
    from .run import DEFAULT_FPS, default_output, on_frames, scene_from_arguments

    require(args.max_iterations >= 1, "--max-iterations", args.max_iterations,
            "must be a whole number >= 1")
    check_tolerance(args.tolerance, "--tolerance")
    loss = observed(args.observed, args.match)
    duration = args.duration
    if duration is None:
        duration = float(max(loss.time))
        args.duration = duration
    # the time base `run` recorded the take on: the same --dt at the same fps is the same step
    fps = args.fps if args.fps is not None else getattr(loss, "fps", None) or DEFAULT_FPS
    scene = on_frames(scene_from_arguments(args), fps)
    out = args.out or default_output(scene.name).removesuffix(".npz") + "-fit.toml"
    check_output_path("--out", out)
    if args.plot:
        from ..plots import plot_format
        check_output_path("--plot", args.plot)
        plot_format(args.plot)

    def progress(iteration, value, values):
        shown = ", ".join(f"{name} = {_short(v)}" for name, v in values.items())
        print(f"iteration {iteration}: loss {value:.6g} ({shown})", flush=True)

    result = fit(scene, loss, args.fit, duration, threads=args.threads,
                 max_iterations=args.max_iterations, tolerance=args.tolerance,
                 progress=progress)
    with atomic_output(out) as file:
        file.write(scene_to_toml(result.scene).encode())
    if args.plot:
        plot_fit(result, loss, args.plot)
    print(json.dumps({"fitted": {k: _plain(v) for k, v in result.values.items()},
                      "loss": result.loss, "iterations": result.iterations,
                      "evaluations": result.evaluations, "converged": result.converged,
                      "scene": out}), flush=True)
    return 0


def _plain(value):
    import numpy as np
    value = np.asarray(value)
    return float(value) if value.ndim == 0 else value.tolist()


def _short(value):
    import numpy as np
    value = np.asarray(value)
    if value.ndim == 0:
        return f"{float(value):.6g}"
    if value.size <= 3:
        return "[" + ", ".join(f"{c:.6g}" for c in value.ravel()) + "]"
    return f"array of {value.size}, mean {value.mean():.6g}"


def plot_fit(result, loss, path) -> None:
    """The loss per iteration, and the observed against the fitted height of the observation's
    mean point over time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..plots import plot_format
    from ..safe_files import atomic_output

    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.semilogy([h[0] for h in result.history], [h[1] for h in result.history], marker="o")
    left.set_xlabel("iteration")
    left.set_ylabel("loss (m²)")
    if hasattr(loss, "positions") and result.frames is not None:
        right.plot(loss.time, loss.positions[:, :, 1].mean(axis=1), label="observed")
        fitted = result.frames   # the frames compared (a take's last, after a shorter step, not)
        right.plot(loss.time[:len(fitted)], fitted[:, :, 1].mean(axis=1), "--", label="fitted")
        right.set_xlabel("time (s)")
        right.set_ylabel("mean height (m)")
        right.legend()
    figure.tight_layout()
    with atomic_output(path) as target:
        figure.savefig(target, format=plot_format(path))
    plt.close(figure)
