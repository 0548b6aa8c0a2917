"""One run of a sweep: a pure function from its RunSpec to its row of results.

Whatever happens inside (the run diverges, a key is refused, the model cannot be built), the
answer is a row with a status, so one bad run never ends a sweep. The row holds only numbers and
strings (and, with ``save``, the run's NPZ as bytes), so it travels from a worker process or a
Dask worker on another machine back to the parent, which writes every file.
"""
import copy
import io
import time

import numpy as np

from ..errors import SimulationDiverged
from ..recording import record
from ..simulation import Simulation
from ..summary import centre_of_mass
from .grid import perturb

# The results of a run, in the order results.csv gives them (see the README's sweep section).
RESULTS = ("centre_of_mass_x_m", "centre_of_mass_y_m", "centre_of_mass_z_m",
           "deepest_penetration_m", "kinetic_energy_j", "gravitational_energy_j",
           "spring_energy_j", "total_energy_j", "largest_speed_m_s", "steps", "simulated_s")
TIMINGS = ("wall_seconds",)   # the only columns that differ between two runs of one sweep
NPZ = "_npz"                  # the key of the recording's bytes in a row (never a column)


def run_one(spec) -> dict:
    """The row of ``spec``: status (ok, diverged, error), message, RESULTS and wall_seconds."""
    started = time.perf_counter()
    row = {"status": "ok", "message": ""}
    try:
        simulation = Simulation(copy.deepcopy(spec.scene))
        perturb(simulation, spec.seed)
        recording = record(simulation, simulation.scene.duration, spec.fps)
        row.update(results(recording))
        if spec.save:
            row[NPZ] = npz_bytes(recording)
    except SimulationDiverged as error:
        row.update(status="diverged", message=str(error), steps=error.step,
                   simulated_s=float(error.time))
    except Exception as error:   # noqa: BLE001 - any failure is this run's, reported in its row
        row.update(status="error", message=f"{type(error).__name__}: {error}")
    row["message"] = " ".join(row["message"].split())   # one line in the table
    row["wall_seconds"] = time.perf_counter() - started
    return row


def results(recording) -> dict:
    """The RESULTS of a finished recording: the centre of mass and energies at the end, and the
    deepest penetration and largest particle speed over every recorded frame."""
    centre = centre_of_mass(recording.mass, recording.positions[-1])
    speeds = np.linalg.norm(recording.velocities, axis=2)
    return {
        "centre_of_mass_x_m": float(centre[0]), "centre_of_mass_y_m": float(centre[1]),
        "centre_of_mass_z_m": float(centre[2]),
        "deepest_penetration_m": float(recording.penetration.max()),
        "kinetic_energy_j": float(recording.kinetic_energy[-1]),
        "gravitational_energy_j": float(recording.gravitational_energy[-1]),
        "spring_energy_j": float(recording.spring_energy[-1]),
        "total_energy_j": float(recording.total_energy[-1]),
        "largest_speed_m_s": float(speeds.max()),
        "steps": int(recording.steps), "simulated_s": float(recording.time[-1]),
    }


def npz_bytes(recording) -> bytes:
    """The recording as the NPZ file `springsim run` writes."""
    buffer = io.BytesIO()
    np.savez(buffer, **recording.arrays())
    return buffer.getvalue()
