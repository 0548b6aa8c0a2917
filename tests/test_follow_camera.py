"""The default camera frames what moves and follows it (render/follow.py).

Oracles, on recordings made here from known motions (small arrays, no simulation): every
frame's bodies, projected with the camera's own pinhole model, lie inside the picture with a
margin and fill a good part of it; the cape's camera sees the side of the figure the cape is on
(behind it) and keeps the walking figure in sight; the camera's look-at point, distance and
direction change by bounded amounts between frames, even when the bodies jump.
"""
import numpy as np
import pytest

import springsim
from springsim.render.follow import camera_path, start_camera
from springsim.walking_figure import parts, posed, root

WIDTH, HEIGHT, FPS = 320, 180, 30.0
MARGIN = 0.03          # of the picture's width and height, on every side


@pytest.fixture(scope="module")
def cape():
    return springsim.Simulation(springsim.load_scene("cape")).model


def carried_by_figure(points, times):
    """``points`` as the figure carries them: at c(t) + R(t) x, as its every vertex."""
    return np.stack([points @ root(t)[0].T + root(t)[1] for t in times])


def projected_boxes(cameras, positions):
    """(F, 4): each frame's (left, top, right, bottom) px of the points its camera sees."""
    boxes = []
    for camera, points in zip(cameras, positions):
        pixels = camera.project(points, WIDTH, HEIGHT)
        boxes.append([*pixels.min(axis=0), *pixels.max(axis=0)])
    return np.array(boxes)


def assert_inside(cameras, positions):
    for camera, points in zip(cameras, positions):
        depth = (points - camera.eye) @ camera.basis()[2]
        assert np.all(depth > 0)                      # all in front of the camera
    left, top, right, bottom = projected_boxes(cameras, positions).T
    assert np.all(left >= MARGIN * WIDTH) and np.all(right <= (1 - MARGIN) * WIDTH)
    assert np.all(top >= MARGIN * HEIGHT) and np.all(bottom <= (1 - MARGIN) * HEIGHT)


def assert_smooth(cameras):
    """Between frames 1/30 s apart: the look-at point moves at most 4% of the distance, the
    distance changes by at most 4%, and the direction turns by at most 2 degrees."""
    targets = np.array([c.target for c in cameras])
    offsets = np.array([c.eye - c.target for c in cameras])
    distances = np.linalg.norm(offsets, axis=1)
    directions = offsets / distances[:, None]
    assert np.all(np.linalg.norm(np.diff(targets, axis=0), axis=1) <= 0.04 * distances[1:])
    assert np.all(np.abs(np.diff(distances)) <= 0.04 * distances[1:])
    turns = np.degrees(np.arccos(np.clip(np.sum(directions[1:] * directions[:-1], axis=1), -1, 1)))
    assert np.all(turns <= 2.0)


def test_the_cape_is_seen_from_behind_and_stays_in_the_picture_with_the_figure(cape):
    times = np.arange(int(3 * FPS) + 1) / FPS
    positions = carried_by_figure(cape.initial_positions, times)
    cameras = camera_path("auto", cape, positions, WIDTH / HEIGHT, times)
    assert_inside(cameras, positions)
    figure = [posed(t, parts()) for t in times]
    assert_inside(cameras, figure)
    assert_smooth(cameras)
    for camera, t, points in zip(cameras, times, positions):
        turn, centre = root(t)
        back = -turn[:, 2]                     # the figure walks along its own +z
        sight = camera.eye - (centre + [0.0, 1.0, 0.0])
        sight[1] = 0.0
        # from behind, a three-quarter view: the cape is towards the camera
        assert sight @ back > 0.5 * np.linalg.norm(sight)
    # the subject is not lost in the picture: it spans at least half its height
    left, top, right, bottom = projected_boxes(cameras, figure).T
    assert np.all(bottom - top > 0.5 * HEIGHT)


@pytest.mark.parametrize("view", ["front", "side", "top"])
def test_named_views_keep_the_walking_figure_in_sight(cape, view):
    times = np.arange(int(3 * FPS) + 1) / FPS
    positions = carried_by_figure(cape.initial_positions, times)
    cameras = camera_path(view, cape, positions, WIDTH / HEIGHT, times)
    figure = [posed(t, parts()) for t in times]
    assert_inside(cameras, positions)
    assert_inside(cameras, figure)
    # followed, not framed once for the whole walk: it stays in the middle of the picture (from
    # above, the figure's 1.8 m of depth, near the camera's distance, skews the perspective)
    left, top, right, bottom = projected_boxes(cameras, figure).T
    middle = np.stack([(left + right) / 2 / WIDTH, (top + bottom) / 2 / HEIGHT], axis=1)
    assert np.all(np.abs(middle - 0.5) < (0.12 if view != "top" else 0.2))


def test_the_viewer_starts_behind_the_cape(cape):
    camera = start_camera("auto", cape, cape.initial_positions, WIDTH / HEIGHT)
    assert camera.eye[2] < -1.0                 # behind the figure, which faces +z at 0 s
    assert_inside([camera], [cape.initial_positions])


def test_the_flag_is_framed_in_the_middle_and_fills_the_picture():
    model = springsim.Simulation(springsim.load_scene("flag")).model
    rest = model.initial_positions
    times = np.arange(31) / FPS
    # the flag waves: out of its plane, growing along the wind (x) from the held edge
    reach = (rest[:, 0] - rest[:, 0].min()) / np.ptp(rest[:, 0])
    positions = np.stack([rest + np.outer(0.4 * reach * np.sin(6 * t + 4 * reach), [0, 0, 1])
                          for t in times])
    cameras = camera_path("auto", model, positions, WIDTH / HEIGHT, times)
    assert_inside(cameras, positions)
    assert_smooth(cameras)
    left, top, right, bottom = projected_boxes(cameras, positions).T
    # the scene's old camera (the flag and the floor under it) left it 37% of the picture across,
    # its middle at 28% of the height
    assert np.all(np.maximum((right - left) / WIDTH, (bottom - top) / HEIGHT) > 0.45)
    middle = np.stack([(left + right) / 2 / WIDTH, (top + bottom) / 2 / HEIGHT], axis=1)
    assert np.all(np.abs(middle - 0.5) < 0.1)


def test_bodies_that_cross_the_world_or_jump_stay_in_the_picture():
    model = springsim.Simulation(springsim.load_scene("jelly-balls")).model
    rest = model.initial_positions
    times = np.arange(91) / FPS
    # across 12 m in 3 s, and a jump of 5 m sideways at 2 s (a reset, a teleport)
    shift = np.outer(4.0 * times, [1.0, 0.0, 0.0]) + np.outer(times >= 2.0, [0.0, 0.0, 5.0])
    positions = rest[None] + shift[:, None, :]
    cameras = camera_path("auto", model, positions, WIDTH / HEIGHT, times)
    radius = model.arrays.radius
    balls = radius > 0
    surfaces = [np.concatenate([x, *(x[balls] + radius[balls, None] * axis
                                     for axis in np.concatenate([np.eye(3), -np.eye(3)]))])
                for x in positions]
    assert_inside(cameras, surfaces)
    # followed, not framed once for the whole way: the bodies are large in every frame
    left, top, right, bottom = projected_boxes(cameras, surfaces).T
    assert np.all(np.maximum((right - left) / WIDTH, (bottom - top) / HEIGHT) > 0.45)
    targets = np.array([c.target for c in cameras])
    distances = np.array([np.linalg.norm(c.eye - c.target) for c in cameras])
    # the jump is eased: the look-at point moves less than a fifth of it a frame
    assert np.max(np.linalg.norm(np.diff(targets, axis=0), axis=1)) < 1.0
    assert np.max(np.abs(np.diff(distances)) / distances[1:]) < 0.1
