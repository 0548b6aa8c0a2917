"""Recordings and the files made from them.

Oracles: frame k lies within dt/2 of k/fps and there are duration * fps + 1 frames; the recorded
frames are exactly the states of a simulation advanced to the same times (determinism); the
spring counts are the cube's analytic ones; the penetration of hand-placed particles is known;
a failed write leaves the old file and no temporary one; the plotted total is the sum of the parts.
"""
import os

import numpy as np
import pytest
from matplotlib.image import imread

from springsim import Simulation, load_scene
from springsim.errors import SceneError
from springsim.model import build_model
from springsim.plots import plot_energy
from springsim.recording import Recording, deepest_penetration, record, write_npz
from springsim.sampling import check_frame_memory, frame_steps
from springsim.springs import SpringKind

N = 4  # a 4 x 4 x 4 cube: small enough to record in well under a second
SMALL_CUBE = f"bodies.0.particles_per_edge={N}"


@pytest.mark.parametrize("duration, fps, dt", [(8.0, 60.0, 1e-3), (1.0, 60.0, 0.02),
                                               (0.5, 24.0, 1e-4), (2.0, 7.0, 3e-3)])
def test_frames_are_whole_steps_within_half_a_step_of_k_over_fps(duration, fps, dt):
    steps = frame_steps(duration, fps, dt)
    frame_times = np.arange(len(steps)) / fps
    if round(duration * fps, 9).is_integer():
        assert len(steps) == round(duration * fps) + 1
    else:  # one last, shorter interval ends at duration
        frame_times[-1] = duration
    assert steps[0] == 0 and np.all(np.diff(steps) >= 0)
    assert np.all(np.abs(steps * dt - frame_times) <= dt / 2 + 1e-12)
    assert abs(steps[-1] * dt - duration) <= dt / 2 + 1e-12


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """A 0.5 s recording of the small cube at 20 fps, written to an NPZ file and read back."""
    simulation = Simulation(load_scene("jelly-plane", [SMALL_CUBE, "bodies.0.position.1=2"]))
    recording = record(simulation, 0.5, 20.0)
    path = tmp_path_factory.mktemp("run") / "run.npz"
    write_npz(path, recording.arrays())
    with np.load(path) as data:
        arrays = dict(data)
    return path, arrays


def test_the_npz_holds_the_documented_arrays_with_consistent_shapes(small_run):
    _, data = small_run
    frames, particles = 0.5 * 20 + 1, N ** 3
    springs = {SpringKind.STRUCTURAL: 3 * N ** 2 * (N - 1),
               SpringKind.SHEAR: 6 * N * (N - 1) ** 2 + 4 * (N - 1) ** 3,
               SpringKind.BEND: 3 * N ** 2 * (N - 2)}
    assert data["time"].shape == (frames,) and data["time"][0] == 0.0
    assert data["positions"].shape == data["velocities"].shape == (frames, particles, 3)
    for name in ("kinetic_energy", "gravitational_energy", "spring_energy", "penetration"):
        assert data[name].shape == (frames,), name
    assert data["springs"].shape == (sum(springs.values()), 2)
    assert {kind: np.count_nonzero(data["spring_kind"] == kind) for kind in springs} == springs
    assert (str(data["scene"]), str(data["integrator"])) == ("jelly-plane", "rk4")
    assert (float(data["fps"]), float(data["dt"]), int(data["steps"])) == (20.0, 1e-3, 500)


def test_the_frames_are_the_states_of_a_simulation_advanced_to_the_same_times(small_run):
    _, data = small_run
    simulation = Simulation(load_scene("jelly-plane", [SMALL_CUBE, "bodies.0.position.1=2"]))
    for frame, time in enumerate(data["time"]):
        simulation.advance(time - simulation.time)
        assert simulation.time == pytest.approx(time, abs=1e-12)
        np.testing.assert_array_equal(data["positions"][frame], simulation.positions)
        np.testing.assert_array_equal(data["velocities"][frame], simulation.velocities)
        energy = simulation.energy()
        assert data["kinetic_energy"][frame] == energy["kinetic"]
        assert data["gravitational_energy"][frame] == energy["gravitational"]
        assert data["spring_energy"][frame] == energy["spring"]
    # the cube hit the plane (y = -1) within the recording, and contact kept it out
    assert data["positions"][:, :, 1].min() < -1 + 0.05
    assert data["penetration"].max() <= 1e-9


def test_penetration_is_the_depth_of_the_deepest_particle_in_any_terrain():
    terrains = 'terrains=[{type="plane"}, {type="bowl", center=[0, 0, 0], radius=20}]'
    model = build_model(load_scene("jelly-plane", [SMALL_CUBE, terrains]))
    x = model.initial_positions.copy()
    assert deepest_penetration(model, x, 0.0) == 0.0
    x[5] = (0.0, -1.25, 0.0)                       # 0.25 m below the plane y = -1
    assert deepest_penetration(model, x, 0.0) == pytest.approx(0.25)
    x[7] = (0.0, 0.0, 20.5)                        # 0.5 m outside the bowl of radius 20
    assert deepest_penetration(model, x, 0.0) == pytest.approx(0.5)


def test_a_failed_write_leaves_the_old_file_whole_and_no_temporary_file(tmp_path):
    class Unwritable:
        def __array__(self, *args, **kwargs):
            raise RuntimeError("disk full")

    path = tmp_path / "frames.npz"
    write_npz(path, {"time": np.arange(3.0)})
    with pytest.raises(RuntimeError):
        write_npz(path, {"time": np.arange(5.0), "positions": Unwritable()})
    assert os.listdir(tmp_path) == ["frames.npz"]
    with np.load(path) as data:
        np.testing.assert_array_equal(data["time"], np.arange(3.0))


def test_a_recording_too_large_for_memory_is_refused_before_it_starts():
    with pytest.raises(SceneError) as error:
        check_frame_memory(481, 10 ** 9, 2, 60.0)    # 23 TB of frames
    assert error.value.key == "fps" and "lower fps or duration" in error.value.allowed


def test_the_energy_plot_draws_the_three_energies_and_their_sum(small_run, tmp_path):
    path, data = small_run
    figure = plot_energy(str(path), tmp_path / "energy.png")
    lines = {line.get_label(): line.get_ydata() for line in figure.axes[0].get_lines()}
    assert set(lines) == {"kinetic", "gravitational", "spring", "total"}
    np.testing.assert_array_equal(lines["kinetic"], data["kinetic_energy"])
    np.testing.assert_array_equal(
        lines["total"], lines["kinetic"] + lines["gravitational"] + lines["spring"])
    image = imread(tmp_path / "energy.png")
    assert image.shape[:2] == (450, 800)             # 8 x 4.5 in at 100 dpi
    assert Recording.load(path).frame_count == len(data["time"])
