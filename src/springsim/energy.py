"""Energies of a state, in joules."""
import numpy as np


def kinetic_energy(model, v) -> float:
    return 0.5 * float(np.sum(model.mass * np.einsum("ij,ij->i", v, v)))


def gravitational_energy(model, x) -> float:
    """Potential energy of gravity, zero at the origin: -sum m g . x (pinned particles included)."""
    return -float(np.sum(model.mass * (x @ model.arrays.gravity)))


def spring_energy(model, x) -> float:
    arrays = model.arrays
    a, b = arrays.springs[:, 0], arrays.springs[:, 1]
    stretch = np.linalg.norm(x[a] - x[b], axis=1) - arrays.rest_length
    return 0.5 * float(np.sum(arrays.group_ks[arrays.spring_group] * stretch ** 2))


def energies(model, state) -> dict:
    kinetic = kinetic_energy(model, state.velocities)
    gravitational = gravitational_energy(model, state.positions)
    spring = spring_energy(model, state.positions)
    return {"kinetic": kinetic, "gravitational": gravitational, "spring": spring,
            "total": kinetic + gravitational + spring}
