"""`springsim play`: the replay's clock, its drawing, and the command in a real window.

Oracles: the timeline shows, at wall time w after Play, the last frame recorded at or before
speed * w (the recorded times, not a frame rate: uneven frames play at their pace), wraps with
loop and stops on the last frame without; the headless viewer draws exactly the recorded positions
of the frame shown (the drawing's arrays and the screenshot's moving cube), its toggles hide and
show polyscope structures, and its energy plot's total is the sum of the recorded parts; under a
virtual display (Xvfb) `springsim play` opens a GLFW window whose screenshot shows the panel and
the orange cube.
"""

import numpy as np
import polyscope as ps
import pytest

from springsim import Simulation, load_scene
from springsim.cli import main
from springsim.export import load_take
from springsim.recording import record, write_npz
from springsim.render import start_renderer
from springsim.replay.timeline import Timeline

WIDTH, HEIGHT = 480, 320


def test_the_timeline_plays_the_recorded_times_at_the_chosen_speed():
    times = np.arange(11) / 10.0                      # 10 fps, 1 s
    timeline = Timeline(times, loop=False)
    timeline.play(now=100.0)
    assert timeline.advance(now=100.25) == 2          # 0.25 s: frame 2 (t = 0.2)
    timeline.set_speed(2.0, now=100.25)
    assert timeline.advance(now=100.5) == 7           # 0.25 + 2 * 0.25 = 0.75 s
    assert timeline.advance(now=101.0) == 10 and not timeline.playing   # the end: stops
    timeline.play(now=200.0)                          # Play at the end starts over
    assert timeline.frame == 0 and timeline.advance(now=200.04) == 0   # 2 x 0.04 < 0.1 s


def test_loop_wraps_and_uneven_frames_keep_their_times():
    times = np.array([0.0, 0.1, 0.2, 0.25])           # a last, shorter interval
    timeline = Timeline(times, loop=True)
    timeline.play(now=0.0)
    assert timeline.advance(now=0.24) == 2
    assert timeline.advance(now=0.25) == 3
    assert timeline.advance(now=0.25 + 0.15) == 1     # wrapped: 0.15 s into the next pass
    assert timeline.playing


def test_seek_and_step_clamp_to_the_recording_and_step_pauses():
    timeline = Timeline(np.arange(5) / 5.0)
    timeline.play(now=0.0)
    timeline.step(3)
    assert (timeline.frame, timeline.playing) == (3, False)
    timeline.step(10)
    assert timeline.frame == 4
    timeline.seek(-7)
    assert timeline.frame == 0
    timeline.toggle(now=5.0)
    assert timeline.playing


@pytest.fixture(scope="module")
def take_path(tmp_path_factory):
    simulation = Simulation(load_scene("jelly-balls", ["bodies.0.particles_per_edge=4"]))
    recording = record(simulation, 1.0, 20.0)
    path = tmp_path_factory.mktemp("play") / "take.npz"
    write_npz(path, recording.arrays())
    return path


@pytest.fixture(scope="module")
def replay(take_path):
    from springsim.replay.window import ReplayViewer

    start_renderer(headless=True, width=WIDTH, height=HEIGHT)   # once per process, shared
    viewer = ReplayViewer(load_take(take_path), headless=True, width=WIDTH, height=HEIGHT)
    yield viewer
    ps.clear_user_callback()


def test_the_replay_draws_the_recorded_positions_of_the_frame_shown(replay):
    take = replay.take
    for frame in (0, 7, take.frame_count - 1):
        replay.timeline.seek(frame)
        replay.run(frames=1)
        np.testing.assert_array_equal(replay.drawing.positions, take.positions[frame])
    ball = take.layout.ball_particles[0]
    cloud = ps.get_point_cloud("balls")
    assert cloud.is_enabled() and take.positions[-1, ball, 1] < take.positions[0, ball, 1]


def test_the_picture_follows_the_frame(replay):
    from springsim.render import capture

    pictures = []
    for frame in (0, replay.take.frame_count - 1):
        replay.timeline.seek(frame)
        replay.run(frames=1)
        pictures.append(capture().astype(int))
    orange = [np.argwhere((p[..., 0] > 150) & (p[..., 0] - p[..., 2] > 60)) for p in pictures]
    assert all(len(o) > 200 for o in orange)
    # the cube falls onto the plane: its pixels move down the picture
    assert orange[1][:, 0].mean() > orange[0][:, 0].mean() + 5


def test_toggles_and_the_energy_plot(replay):
    replay.set_drawn("structural", True)
    assert ps.get_curve_network("springs: structural").is_enabled()
    replay.set_drawn("structural", False)
    assert not ps.get_curve_network("springs: structural").is_enabled()
    arrays = replay.take.arrays
    np.testing.assert_allclose(replay.energies["total"], arrays["kinetic_energy"]
                               + arrays["gravitational_energy"] + arrays["spring_energy"])
    replay.timeline.play()
    replay.run(frames=3)       # the panel builds with the plot and every control


def test_a_recording_from_before_the_layout_replays_its_surface(take_path, tmp_path):
    from springsim.recording_layout import LAYOUT_KEYS
    from springsim.replay.window import ReplayViewer

    with np.load(take_path) as data:
        old = {key: data[key] for key in data.files if key not in LAYOUT_KEYS}
    np.savez(tmp_path / "old.npz", **old)
    viewer = ReplayViewer(load_take(tmp_path / "old.npz"), headless=True, width=WIDTH,
                          height=HEIGHT)
    viewer.timeline.seek(5)
    viewer.run(frames=1)
    np.testing.assert_array_equal(viewer.drawing.positions, old["positions"][5])
    assert ps.has_surface_mesh("surface 0: jelly-balls")
    ps.clear_user_callback()


def test_play_refuses_a_bad_speed_and_a_missing_file(take_path, capsys, tmp_path):
    assert main(["play", str(take_path), "--speed", "0"]) == 2
    assert main(["play", str(tmp_path / "none.npz")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "--speed = 0.0" in err[0] and "no such file" in err[1]


@pytest.mark.external   # Xvfb
def test_play_opens_a_window_under_a_virtual_display(take_path, tmp_path):
    from test_window_xvfb import window_screenshot

    picture = window_screenshot(["play", str(take_path), "--frames", "10"], tmp_path,
                                width=800, height=500)
    assert np.all(picture[:, :300] < 90, axis=-1).mean() > 0.2        # the panel
    scene = picture[:, 360:]
    assert ((scene[..., 0] > 150) & (scene[..., 0] - scene[..., 2] > 60)).mean() > 0.01
