"""Plain NumPy forces: the slow, obviously-correct reference the Numba kernels are tested against."""
import numpy as np


def reference_forces(model, x, v) -> np.ndarray:
    """Spring, damper, gravity and drag forces (N), as in forces.py, with vectorized NumPy."""
    arrays = model.arrays
    a, b = arrays.springs[:, 0], arrays.springs[:, 1]
    d = x[a] - x[b]
    length = np.linalg.norm(d, axis=1)
    direction = d / length[:, None]
    ks = arrays.group_ks[arrays.spring_group]
    kd = arrays.group_kd[arrays.spring_group]
    closing = np.einsum("ij,ij->i", v[a] - v[b], direction)
    f_a = (-ks * (length - arrays.rest_length) - kd * closing)[:, None] * direction
    force = np.zeros_like(x)
    np.add.at(force, a, f_a)
    np.add.at(force, b, -f_a)
    mass = np.where(arrays.inv_mass > 0, model.mass, 0.0)
    return force + mass[:, None] * arrays.gravity - arrays.drag[:, None] * v
