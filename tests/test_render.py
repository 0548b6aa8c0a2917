"""Headless rendering (polyscope on EGL, no GPU needed) and the videos of `springsim render`.

Oracles: every built-in scene's first frame is a real picture (not mostly background; three
large colours, or many), and its bodies appear where a pinhole camera with the same parameters
projects them; each camera sees every point it frames, tightly; MP4, GIF and PNG output read back
with the requested frame count, size and rate; a failed write leaves no file behind.
"""
import numpy as np
import pytest

import imageio.v2 as imageio_v2
import imageio.v3 as iio
import springsim
from springsim.cli import main
from springsim.errors import SceneError
from springsim.render import (DrawOptions, SceneDrawing, camera_path, draw_frame,
                              scene_points, start_renderer, write_video)
from springsim.render.camera import body_points
from springsim.render.follow import FILL
from springsim.render.frames import simulate_frames
from springsim.render.video import FrameWriter

WIDTH, HEIGHT = 320, 180
NOTHING = DrawOptions.only([])


@pytest.fixture(scope="module")
def renderer():
    """polyscope's headless backend; it can start once per process, so every module shares it."""
    return start_renderer(headless=True, width=WIDTH, height=HEIGHT)


def background() -> np.ndarray:
    """The colour of an empty picture (polyscope tone-maps the background colour it is given)."""
    sim = springsim.Simulation(springsim.load_scene("jelly-plane"))
    x = sim.positions
    empty = draw_frame(SceneDrawing(sim.model, NOTHING, x), camera_path("auto", sim.model, x[None],
                                                                       1.0)[0], x)
    assert np.all(empty == empty[0, 0])
    return empty[0, 0].astype(float)


def not_background(image: np.ndarray) -> np.ndarray:
    return np.any(np.abs(image.astype(float) - background()) > 12, axis=-1)


@pytest.mark.parametrize("name", springsim.preset_names())
def test_first_frame_shows_the_bodies_where_the_camera_points(renderer, name):
    sim = springsim.Simulation(springsim.load_scene(name))
    x = sim.positions[None]
    camera = camera_path("auto", sim.model, x, WIDTH / HEIGHT)[0]
    start_renderer(headless=True, width=WIDTH, height=HEIGHT)

    picture = draw_frame(SceneDrawing(sim.model, DrawOptions(), x[0]), camera, x[0])
    assert picture.shape == (HEIGHT, WIDTH, 3)
    assert not_background(picture).mean() > 0.05
    # shaded round bodies give many colours; flat ones at least background, body and terrain
    _, counts = np.unique(picture.reshape(-1, 3), axis=0, return_counts=True)
    assert len(counts) > 100 or np.count_nonzero(counts > 0.005 * HEIGHT * WIDTH) >= 3

    only_bodies = DrawOptions.only(["surfaces", "balls", "particles"])
    mask = not_background(draw_frame(SceneDrawing(sim.model, only_bodies, x[0]), camera, x[0]))
    rows, columns = np.nonzero(mask)
    assert mask.mean() > 0.01
    # the whole body is inside the picture, and where the pinhole model puts it
    assert rows.min() > 0 and columns.min() > 0
    assert rows.max() < HEIGHT - 1 and columns.max() < WIDTH - 1
    # (the box of the projected particles, not the projection of their mean: a close camera's
    # perspective moves the drawn area's middle towards the near side)
    pixels = camera.project(body_points(sim.model, x[0]), WIDTH, HEIGHT)
    low, high = pixels.min(axis=0), pixels.max(axis=0)
    assert np.all(np.abs([columns.min() - low[0], columns.max() - high[0]]) < 0.06 * WIDTH)
    assert np.all(np.abs([rows.min() - low[1], rows.max() - high[1]]) < 0.06 * HEIGHT)


@pytest.mark.parametrize("camera", ["auto", "front", "side", "top", "follow", "still"])
def test_cameras_frame_every_point_they_are_given(camera):
    sim = springsim.Simulation(springsim.load_scene("jelly-sphere"))
    times, positions = simulate_frames(sim, 0.3, 10, progress=False)
    for frame, view in enumerate(camera_path(camera, sim.model, positions, WIDTH / HEIGHT, times)):
        if camera == "still":   # the whole motion and the terrain near it, tightly
            points, fill = scene_points(sim.model, positions), 1.0
        else:                   # the bodies of the frame, within FILL of the half-sizes
            points, fill = body_points(sim.model, positions[frame]), FILL
        pixels = view.project(points, WIDTH, HEIGHT)
        spread = np.max(np.abs(pixels - (WIDTH / 2, HEIGHT / 2)) / (WIDTH / 2, HEIGHT / 2))
        assert spread <= fill + 1e-9
        assert spread > 0.8 * fill or (camera != "still" and frame > 0)   # no wasted border


def read_video(path):
    """The frames of a video file, and the frames per second it declares."""
    with imageio_v2.get_reader(path) as reader:
        return np.stack([frame for frame in reader]), reader.get_meta_data()["fps"]


def test_render_writes_an_mp4_and_a_gif_with_the_frames_asked_for(renderer, tmp_path, capsys):
    mp4, gif = tmp_path / "cube.mp4", tmp_path / "cube.gif"
    common = ["--duration", "0.5", "--fps", "12", "--width", "160", "--height", "96", "--quiet",
              "--set", "bodies.0.particles_per_edge=4"]
    assert main(["render", "jelly-plane", "--out", str(mp4), *common]) == 0
    assert main(["render", "jelly-bowl", "--out", str(gif), "--camera", "follow",
                 "--draw", "surfaces,structural,terrains", *common]) == 0
    video, fps = read_video(mp4)
    assert video.shape == (7, 96, 160, 3) and fps == 12   # frames at k / 12 s, k = 0 .. 6
    assert not_background(video).mean() > 0.05
    assert not np.array_equal(video[0], video[-1])     # the cube moved
    frames = iio.imread(gif, index=None)
    assert frames.shape[:3] == (7, 96, 160)
    durations = [iio.immeta(gif, index=i)["duration"] for i in range(7)]
    assert all(abs(d - 1000 / 12) <= 10 for d in durations)   # GIF keeps 10 ms units
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cube.gif", "cube.mp4"]


def test_write_video_to_a_folder_of_pngs(renderer, tmp_path):
    sim = springsim.Simulation(springsim.load_scene("cloth-hang",
                                                    ["bodies.0.particles_per_edge=6"]))
    times, positions = simulate_frames(sim, 0.1, 40, progress=False)
    folder = write_video(sim.model, times, positions, tmp_path / "frames", fps=40, width=64,
                         height=48, camera="side")
    pictures = sorted(folder.iterdir())
    assert [p.name for p in pictures] == [f"frame_{i:05d}.png" for i in range(5)]
    assert iio.imread(pictures[-1]).shape == (48, 64, 3)


def test_bad_outputs_are_refused_before_rendering_and_leave_nothing(renderer, tmp_path, capsys):
    odd = ["render", "jelly-plane", "--out", str(tmp_path / "odd.mp4"), "--width", "161",
           "--height", "96", "--duration", "0.1", "--quiet"]
    assert main(odd) == 2 and "width" in capsys.readouterr().err
    with pytest.raises(SceneError, match="out"):
        FrameWriter(tmp_path / "movie.avi", 30, 64, 48)
    with pytest.raises(SceneError, match="frame size"):
        with FrameWriter(tmp_path / "broken.mp4", 30, 64, 48) as writer:
            writer.append(np.zeros((48, 64, 3), np.uint8))
            writer.append(np.zeros((40, 64, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


def test_video_frames_are_in_real_time_when_a_frame_is_not_a_whole_number_of_steps():
    """At dt = 1/60 s and 25 fps a frame is 2.4 steps: frame k must still show t = k / 25."""
    sim = springsim.Simulation(springsim.load_scene("jelly-plane",
                                                    ["bodies.0.particles_per_edge=3"]),
                               integrator="implicit_euler", dt=1 / 60)
    times, positions = simulate_frames(sim, 2.0, 25, progress=False)
    assert len(times) == 51
    assert np.all(np.abs(times - np.arange(51) / 25) <= sim.dt / 2 + 1e-12)



@pytest.mark.parametrize("name", [name for name in springsim.preset_names()
                                  if springsim.load_scene(name).terrains])
def test_every_terrain_stands_out_from_the_background(renderer, name):
    """Lit and tone-mapped, a terrain's pixels differ from the sky in brightness by a tenth of
    the range at least (the stairs of jelly-torus, pale grey on pale blue, barely showed)."""
    sim = springsim.Simulation(springsim.load_scene(name))
    x = sim.positions
    # the camera that frames the terrain near the bodies too (``auto`` frames what moves)
    camera = camera_path("still", sim.model, x[None], WIDTH / HEIGHT)[0]
    start_renderer(headless=True, width=WIDTH, height=HEIGHT)
    picture = draw_frame(SceneDrawing(sim.model, DrawOptions.only(["terrains"]), x), camera, x)
    sky = background()
    terrain = np.any(picture.astype(float) != sky, axis=-1)
    assert terrain.mean() > 0.05
    luminance = np.array([0.2126, 0.7152, 0.0722])
    contrast = np.abs(picture[terrain].astype(float) @ luminance - sky @ luminance)
    assert contrast.mean() > 25.5


def test_pins_and_the_wind_are_drawn_where_they_are(renderer):
    """The flag's pins are dots where the camera projects its pinned particles, and the wind is
    an arrow that runs from above the bodies the way the air moves (+x), as projected."""
    from springsim.render.drawing import pinned_particles

    sim = springsim.Simulation(springsim.load_scene("flag"))
    x = sim.positions
    camera = camera_path("auto", sim.model, x[None], WIDTH / HEIGHT)[0]
    start_renderer(headless=True, width=WIDTH, height=HEIGHT)
    pins = not_background(draw_frame(SceneDrawing(sim.model, DrawOptions.only(["pins"]), x),
                                     camera, x))
    held = camera.project(x[pinned_particles(sim.model)], WIDTH, HEIGHT)
    pixels = np.argwhere(pins)[:, ::-1]   # (column, row)
    apart = np.linalg.norm(pixels[:, None, :] - held[None, :, :], axis=-1)
    assert len(pixels) and apart.min(axis=1).max() < 8 and apart.min(axis=0).max() < 8

    drawing = SceneDrawing(sim.model, DrawOptions.only(["wind"]), x)
    arrow = not_background(draw_frame(drawing, camera, x))
    base, tip = camera.project(np.array([drawing.wind.base, drawing.wind.base + drawing.wind.arrow]),
                               WIDTH, HEIGHT)
    along = (tip - base) / np.linalg.norm(tip - base)
    pixels = np.argwhere(arrow)[:, ::-1] - base
    assert len(pixels) > 20
    spread = np.linalg.svd(pixels - pixels.mean(axis=0), full_matrices=False)[2][0]
    assert abs(spread @ along) > 0.95                        # the arrow lies along the wind
    assert (pixels @ along).mean() > 0.25 * np.linalg.norm(tip - base)   # and points its way
