"""Charts of a recording. Drawn with matplotlib's Agg canvas directly: no pyplot, no display, and
no change to the global backend of a program that imports springsim."""
from pathlib import Path

from .errors import require
from .recording import Recording
from .safe_files import atomic_output

IMAGE_FORMATS = ("png", "pdf", "svg")


def plot_energy(recording_or_npz_path, out_path):
    """Kinetic, gravitational, spring and total energy over time, written whole to ``out_path``.

    Takes a Recording or the path of an NPZ file `springsim run` wrote. Returns the figure.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    image_format = plot_format(out_path)
    recording = (recording_or_npz_path if isinstance(recording_or_npz_path, Recording)
                 else Recording.load(recording_or_npz_path))
    figure = Figure(figsize=(8, 4.5), dpi=100, layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.add_subplot()
    curves = {"kinetic": recording.kinetic_energy,
              "gravitational": recording.gravitational_energy,
              "spring": recording.spring_energy, "total": recording.total_energy}
    for label, energy in curves.items():
        axes.plot(recording.time, energy, label=label,
                  linewidth=2.0 if label == "total" else 1.2,
                  color="black" if label == "total" else None)
    axes.set_xlabel("time (s)")
    axes.set_ylabel("energy (J)")
    axes.set_title(f"{recording.scene}: {recording.integrator}, dt = {recording.dt:g} s")
    axes.grid(alpha=0.3)
    axes.legend()
    with atomic_output(out_path) as file:
        figure.savefig(file, format=image_format)
    return figure


def plot_format(path) -> str:
    """The image format a path's suffix asks for (checked before a long run, not after)."""
    suffix = Path(path).suffix.lower().lstrip(".")
    require(suffix in IMAGE_FORMATS, "plot", str(path),
            "must end in " + ", ".join(f".{name}" for name in IMAGE_FORMATS))
    return suffix
