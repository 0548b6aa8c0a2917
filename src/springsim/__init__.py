"""springsim: mass-spring physics (jelly cubes, cloth, balls) on terrains, with a choice of
integrators. SI units throughout: metres, kilograms, seconds.

    import springsim
    sim = springsim.Simulation(springsim.load_scene("jelly-plane"), integrator="rk4", dt=1e-3)
    sim.advance(2.0)
    sim.positions, sim.velocities, sim.time, sim.energy()
"""
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _version

from .errors import SceneError, SimulationDiverged
from .integrators import integrator_names
from .presets import preset_names
from .scene import Scene
from .scenefile import load_scene
from .simulation import Simulation
from .sweeps import sweep



def __getattr__(name):
    """``springsim.gradient`` (springsim.gradients.gradient), imported on first use: a plain run
    does not need the adjoint's modules."""
    if name == "gradient":
        from .gradients import gradient

        return gradient
    raise AttributeError(f"module 'springsim' has no attribute {name!r}")


try:
    __version__ = _version("springsim")   # pyproject.toml's, as installed: one place says it
except PackageNotFoundError:              # a source tree on sys.path with no install
    __version__ = "0+unknown"

__all__ = [
    "Scene",
    "SceneError",
    "Simulation",
    "SimulationDiverged",
    "__version__",
    "gradient",
    "integrator_names",
    "load_scene",
    "preset_names",
    "sweep",
]
