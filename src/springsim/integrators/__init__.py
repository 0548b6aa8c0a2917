"""Integrators, chosen by name.

Adding one is one new file in this package that defines an ``Integrator`` subclass decorated with
``@register``, plus its import line at the bottom of this file.
"""
from ..errors import SceneError

REGISTRY: dict[str, type] = {}


class Integrator:
    """Advances a state by whole steps of size dt; subclasses set ``name``, ``order``, ``summary``.

    ``advance(model, state, dt, steps)`` returns ``(steps_done, particle)`` where ``particle`` is
    the first particle found diverging after step ``steps_done`` (and -1 if none did).
    """

    name = ""
    order = 0
    summary = ""

    def __init__(self, **options):
        if options:
            key = next(iter(options))
            raise SceneError(f"integrator option {key}", options[key],
                             f"'{self.name}' takes no options")

    def advance(self, model, state, dt: float, steps: int) -> tuple[int, int]:
        raise NotImplementedError  # every registered integrator overrides this


class KernelIntegrator(Integrator):
    """An integrator whose whole loop of steps is one compiled kernel
    ``kernel(model_arrays, x, v, dt, steps) -> (steps_done, particle)``."""

    kernel = None

    def advance(self, model, state, dt, steps):
        done, particle = self.kernel(model.arrays, state.positions, state.velocities,
                                           float(dt), int(steps))
        return int(done), int(particle)


def register(cls):
    REGISTRY[cls.name] = cls
    return cls


def integrator_names() -> list[str]:
    return list(REGISTRY)


def get_integrator(name: str, **options) -> Integrator:
    if name not in REGISTRY:
        raise SceneError("integrator", name, "must be one of " + ", ".join(REGISTRY))
    return REGISTRY[name](**options)


# The registry: one line per integrator file.
from . import explicit_euler, symplectic_euler, midpoint, rk4, implicit_euler, predict_reevaluate  # noqa: E402,F401,E501
