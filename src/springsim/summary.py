"""The summary `springsim run` prints at the end of a run, from its recording."""
import numpy as np


def summary_lines(recording, bodies: list | tuple = ()) -> list[str]:
    """What a user wants to know after a run: how far and how fast it went, and how it ended;
    ``bodies``: (label, text) rows for bodies whose build chose something (a mesh body's
    spacing)."""
    simulated = recording.time[-1] - recording.time[0]
    deepest = int(np.argmax(recording.penetration))
    total = recording.total_energy
    final_energies = {"kinetic": recording.kinetic_energy[-1],
                      "gravitational": recording.gravitational_energy[-1],
                      "spring": recording.spring_energy[-1], "total": total[-1]}
    rows = [
        ("simulated", f"{simulated:g} s in {recording.steps} steps "
                      f"({recording.frame_count} frames at {recording.fps:g} fps)"),
        ("wall time", f"{recording.step_seconds:.3g} s stepping, "
                      f"{recording.wall_seconds:.3g} s with recording"),
        ("speed", f"{_rate(recording.steps, recording.step_seconds):.4g} steps/s, "
                  f"real-time factor {_rate(simulated, recording.step_seconds):.3g}"),
        ("final centre of mass",
         _vector(centre_of_mass(recording.mass, recording.positions[-1])) + " m"),
        ("deepest penetration", _penetration(recording.penetration[deepest],
                                             recording.time[deepest])),
        ("energy at the end", ", ".join(f"{name} {value:.6g} J"
                                        for name, value in final_energies.items())),
        ("total energy change", f"{total[-1] - total[0]:+.6g} J since t = {recording.time[0]:g} s"),
        *bodies,
    ]
    heading = (f"{recording.scene}: {recording.integrator}, dt = {recording.dt:g} s, "
               f"{len(recording.mass)} particles, {len(recording.springs)} springs")
    return [heading] + [f"  {label:<22}{text}" for label, text in rows]


def _penetration(depth: float, time: float) -> str:
    if depth == 0:
        return "0 m (no particle inside a terrain in any frame)"
    return f"{depth:.3g} m (at t = {time:.4g} s)"


def centre_of_mass(mass: np.ndarray, x: np.ndarray) -> np.ndarray:
    return mass @ x / np.sum(mass)


def _rate(amount: float, seconds: float) -> float:
    return amount / seconds if seconds > 0 else float("inf")


def _vector(values) -> str:
    return "(" + ", ".join(f"{value:.4g}" for value in values) + ")"
