"""springsim: mass-spring physics (jelly cubes, cloth, balls) on terrains, with a choice of
integrators. SI units throughout: metres, kilograms, seconds.

    import springsim
    sim = springsim.Simulation(springsim.load_scene("jelly-plane"), integrator="rk4", dt=1e-3)
    sim.advance(2.0)
    sim.positions, sim.velocities, sim.time, sim.energy()
"""
import os as _os

# Numba's coloured error messages start colorama, whose exit hook writes a colour reset (ESC[0m)
# to a terminal after every run; springsim says its errors in its own one-line messages
_os.environ.setdefault("NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING", "1")

TYPE_CHECKING = False   # typing's own, without importing typing (10 ms of the start-up)
if TYPE_CHECKING:   # what the reference documents; imported at first use at run time (below)
    from .errors import SceneError, SimulationDiverged
    from .gradients import gradient
    from .integrators import integrator_names
    from .presets import preset_names
    from .scene import Scene
    from .scenefile import load_scene
    from .simulation import Simulation
    from .sweeps import sweep

__all__ = ["__version__", "Simulation", "Scene", "SceneError", "SimulationDiverged", "load_scene",
           "integrator_names", "preset_names", "sweep", "gradient"]

# Where each public name lives, imported at its first use (PEP 562): the command line starts,
# and takes over Ctrl-C (signals.py), before NumPy and Numba load, which takes about a second,
# and before importlib.metadata (for __version__), which takes 50 ms: this module imports nothing.
_PUBLIC = {"Simulation": "simulation", "Scene": "scene", "SceneError": "errors",
           "SimulationDiverged": "errors", "load_scene": "scenefile",
           "integrator_names": "integrators", "preset_names": "presets", "sweep": "sweeps",
           "gradient": "gradients"}


def _version() -> str:
    """pyproject.toml's version, as installed: one place says it."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("springsim")
    except PackageNotFoundError:   # a source tree on sys.path with no install
        return "0+unknown"


def __getattr__(name):
    if name == "__version__":
        globals()[name] = value = _version()
        return value
    if name not in _PUBLIC:
        raise AttributeError(f"module 'springsim' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f".{_PUBLIC[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *_PUBLIC, "__version__"})
