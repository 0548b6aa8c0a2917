"""Errors a user can act on, and the checks that raise them."""
import numpy as np


class SceneError(ValueError):
    """A scene (preset, file or override) asks for something springsim cannot simulate.

    The message names the key, the value given and what is allowed.
    """

    def __init__(self, key: str, value, allowed: str):
        self.key, self.value, self.allowed = key, value, allowed
        super().__init__(one_line(f"{key} = {value!r}: {allowed}"))


class OutputFailed(OSError):
    """A file could not be written (disk full, folder removed, writer failed); the previous file
    at ``path``, if any, is left as it was."""

    def __init__(self, path, reason):
        self.path, self.reason = str(path), reason
        text = reason.strerror if isinstance(reason, OSError) and reason.strerror else reason
        super().__init__(getattr(reason, "errno", None),
                         one_line(f"could not write {self.path}: {text}; any previous file "
                                  f"there is unchanged"))

    def __str__(self):
        return self.strerror


class SimulationDiverged(RuntimeError):
    """The state blew up (NaN, infinity or a speed above the course framework's limit)."""

    def __init__(self, *, time: float, step: int, integrator: str, dt: float, particle: int,
                 position, speed_squared: float, suggested_dt: float | None = None):
        self.time, self.step, self.integrator, self.dt = time, step, integrator, dt
        self.particle, self.position, self.speed_squared = particle, position, speed_squared
        where = "(" + ", ".join(f"{c:.3g}" for c in position) + ")"
        super().__init__(
            f"simulation diverged at t = {time:.6g} s (step {step}) with integrator "
            f"'{integrator}' and dt = {dt:g} s: particle {particle} near {where} has |v|^2 = "
            f"{speed_squared:.3g} (limit 1e6). Try a smaller dt (for example "
            f"{suggested_dt if suggested_dt is not None else dt / 2:.2g}), "
            f"{_more_stable(integrator)}, or softer springs.")


def _more_stable(integrator: str) -> str:
    if integrator == "implicit_euler":
        return "more Newton iterations (implicit.newton_iterations)"
    if integrator == "vbd":
        return "more iterations (vbd.iterations)"
    if integrator == "rk4":
        return "implicit_euler (stable at large steps)"
    return "a more stable integrator (rk4, or implicit_euler for large steps)"


def one_line(text: str) -> str:
    """``text`` with line breaks and other control characters escaped (as repr writes them), so
    that an error is one line whatever a user's key or file name holds."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def is_finite(value) -> bool:
    """True for a finite number or an array of finite numbers; False for anything else."""
    try:
        return bool(np.all(np.isfinite(np.asarray(value, float))))
    except (TypeError, ValueError):
        return False


def require(condition: bool, key: str, value, allowed: str) -> None:
    """Raise a SceneError for ``key`` unless ``condition`` holds."""
    if not condition:
        raise SceneError(key, value, allowed)


MAX_ANGLE = 1e6   # degrees; beyond, float64 rounding leaves no meaningful angle (2778 turns)


def require_angle(value, key: str) -> None:
    """An angle in degrees: finite and within +-MAX_ANGLE."""
    require(is_finite(value) and np.ndim(value) == 0 and abs(float(value)) <= MAX_ANGLE, key,
            value, f"must be a finite angle in degrees, between -{MAX_ANGLE:g} and {MAX_ANGLE:g}")
