"""The time step of a scene file that names none: from its stiffest particle, so that the
defaults run as they are.

An explicit method is stable while h times the system's fastest rate stays within its stability
region (about 2 for the symplectic and the midpoint methods, 2.8 for RK4). For particle i with
springs of stiffness K_i = sum k and damping C_i = sum kd, and mass m_i, the eigenvalues of
M^-1 K are at most 2 K_i / m_i and those of M^-1 C at most 2 C_i / m_i (Gershgorin's bound: the
row's own term and its neighbours' together). So h = SAFETY / max(sqrt(2 K_i / m_i), 2 C_i / m_i),
the worse of the oscillation and the damping limit (a course cloth, 1 kg particles with twelve
750 N s/m dampers each, is damping-limited: 1e-4 s under RK4). implicit_euler is stable at any step and
takes a frame's: 1/60 s. A scene with no springs keeps the course framework's 1 ms.
"""
from typing import NamedTuple

import numpy as np

# h times the rate bound: RK4's stability region reaches 2.8 on the axes, the other explicit
# methods' about 2 or less (explicit Euler has no margin for undamped oscillation at all)
SAFETY = {"rk4": 1.8}
DEFAULT_SAFETY = 0.9
IMPLICIT_STEP = 1 / 60  # s: one step a frame
NO_SPRINGS_STEP = 1e-3  # s: the course framework's
IMPLICIT = ("implicit_euler", "vbd")   # stable at a frame's step


class StepEstimate(NamedTuple):
    dt: float           # s
    basis: str          # what it was chosen from, in words ("dt = ... s, from <basis>")


def stable_step(model, integrator: str = "rk4") -> StepEstimate:
    """The step of the explicit method ``integrator`` for ``model`` (module doc)."""
    arrays = model.arrays
    no_springs = StepEstimate(NO_SPRINGS_STEP, "the course framework's step (no springs)")
    if len(arrays.springs) == 0:
        return no_springs
    a, b = arrays.springs[:, 0].astype(np.int64), arrays.springs[:, 1].astype(np.int64)
    count = model.particle_count
    ks = arrays.group_ks[arrays.spring_group]
    kd = arrays.group_kd[arrays.spring_group]
    stiffness = np.bincount(a, ks, count) + np.bincount(b, ks, count)
    damping = np.bincount(a, kd, count) + np.bincount(b, kd, count)
    free = ~model.pinned
    rate = np.where(free, np.maximum(np.sqrt(2 * stiffness / model.mass),
                                     2 * damping / model.mass), 0.0)
    worst = int(np.argmax(rate))
    if rate[worst] <= 0:
        return no_springs
    return StepEstimate(float(SAFETY.get(integrator, DEFAULT_SAFETY) / rate[worst]),
                        f"the stiffest particle, {worst}: {stiffness[worst]:.4g} N/m and "
                        f"{damping[worst]:.4g} N s/m of springs on {model.mass[worst]:.4g} kg")


def automatic_step(scene) -> StepEstimate:
    """The step of a scene that names none: a frame's under the IMPLICIT methods, else
    stable_step."""
    from .model import build_model

    if scene.integrator in IMPLICIT:
        return StepEstimate(IMPLICIT_STEP, f"a frame's step, at which {scene.integrator} is "
                            "stable")
    return stable_step(build_model(scene), scene.integrator)
