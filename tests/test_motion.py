"""Motion tables (motion.py): poses on the keyframed path, their velocities, and bad input."""
import math

import numpy as np
import pytest

from springsim.errors import SceneError
from springsim.motion import Keyframe, Motion
from springsim.scenefile import scene_from_table


def rotation(pose):
    return pose[:9].reshape(3, 3)


def rodrigues(axis, degrees):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    angle = math.radians(degrees)
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


KEYS = [Keyframe(0.0), Keyframe(0.5, (1.0, 0.0, 0.0), 90.0, (0.0, 0.0, 1.0)),
        Keyframe(1.5, (1.0, 2.0, 0.0), 450.0, (0.0, 0.0, 1.0)),
        Keyframe(2.0, (0.0, 2.0, -1.0), 30.0, (1.0, 1.0, 0.0))]


@pytest.mark.parametrize("interpolation", ["linear", "smooth"])
def test_keyframes_are_met_and_held_outside(interpolation):
    motion = Motion(keyframes=KEYS, interpolation=interpolation, pivot=(0.5, 0.0, 0.0))
    for key in KEYS:
        pose = motion.pose(key.time)
        assert np.allclose(pose[9:12], np.add(motion.pivot, key.position), atol=1e-14)
        assert np.allclose(rotation(pose), rodrigues(key.rotation_axis, key.rotation_degrees),
                           atol=1e-14)
    before, after = motion.pose(-1.0), motion.pose(3.0)
    assert np.array_equal(before[15:], np.zeros(6)) and np.array_equal(after[15:], np.zeros(6))
    assert np.allclose(after[9:12], np.add(motion.pivot, KEYS[-1].position))


def test_linear_is_linear_and_a_turn_about_one_axis_turns_at_its_rate():
    motion = Motion(keyframes=KEYS[:3])
    pose = motion.pose(1.0)   # halfway from key 1 to key 2: 270 degrees about z
    assert np.allclose(pose[9:12], [1.0, 1.0, 0.0], atol=1e-15)
    assert np.allclose(rotation(pose), rodrigues((0, 0, 1), 270.0), atol=1e-14)
    assert np.allclose(pose[15:18], [0.0, 2.0, 0.0], atol=1e-14)        # m/s
    assert np.allclose(pose[18:21], [0.0, 0.0, math.radians(360.0)], atol=1e-13)   # rad/s


@pytest.mark.parametrize("interpolation", ["linear", "smooth"])
def test_velocities_are_the_derivatives_of_the_path(interpolation):
    """c' and w against central differences of c(t) and R(t) (R' R^T = [w])."""
    motion = Motion(keyframes=KEYS, interpolation=interpolation, pivot=(0.2, 0.1, 0.0))
    step = 1e-6
    for t in (0.1, 0.3, 0.7, 1.2, 1.7, 1.95):
        ahead, behind, pose = motion.pose(t + step), motion.pose(t - step), motion.pose(t)
        assert np.allclose((ahead[9:12] - behind[9:12]) / (2 * step), pose[15:18], atol=1e-6)
        spin = (rotation(ahead) - rotation(behind)) / (2 * step) @ rotation(pose).T
        assert np.allclose(spin, -spin.T, atol=1e-6)
        assert np.allclose([spin[2, 1], spin[0, 2], spin[1, 0]], pose[18:21], atol=1e-6)


def test_smooth_is_c1_through_the_keys():
    motion = Motion(keyframes=KEYS, interpolation="smooth")
    for key in KEYS[1:-1]:
        left, right = motion.pose(key.time - 1e-9), motion.pose(key.time + 1e-9)
        assert np.allclose(left[15:], right[15:], atol=1e-6)
    assert np.allclose(motion.pose(KEYS[0].time + 1e-9)[15:], 0.0, atol=1e-6)   # starts at rest


def test_constant_velocity_about_a_pivot():
    motion = Motion(velocity=(1.0, 0.0, 0.0), angular_velocity=(0.0, 2.0, 0.0),
                    pivot=(0.0, 0.0, 1.0))
    t = 0.3
    placed = np.array([[0.0, 0.0, 2.0]])
    moved = motion.place(placed, t)
    expected = np.array([0.3, 0.0, 1.0]) + rodrigues((0, 1, 0), math.degrees(2 * t)) @ [0, 0, 1]
    assert np.allclose(moved[0], expected, atol=1e-15)
    pose = motion.pose(t)
    assert np.allclose(pose[15:18], [1.0, 0.0, 0.0]) and np.allclose(pose[18:21], [0, 2.0, 0])


@pytest.mark.parametrize("keyframes, key, words", [
    ([{"time": 0.5}, {"time": 0.2}], "terrains.0.motion.keyframes.1.time", "increasing"),
    ([{"time": 0.5}, {"time": 0.5}], "terrains.0.motion.keyframes.1.time", "increasing"),
    ([{"time": 0.0, "rotation_axis": [0.0, 0.0, 0.0]}],
     "terrains.0.motion.keyframes.0.rotation_axis", "not all zero"),
    ([{"position": [0.0, 0.0, 0.0]}], "terrains.0.motion.keyframes.0", "time"),
])
def test_bad_keyframes_are_one_line_naming_the_key(keyframes, key, words):
    table = {"bodies": [{"type": "balls"}],
             "terrains": [{"type": "plane", "motion": {"keyframes": keyframes}}]}
    with pytest.raises(SceneError) as raised:
        scene_from_table(table).validate()
    assert raised.value.key == key and words in str(raised.value)
    assert "\n" not in str(raised.value)


def test_a_scene_file_motion_table_reads_as_the_issue_writes_it():
    import tomllib

    text = """
[[bodies]]
type = "balls"
[[terrains]]
type = "sphere"
center = [0.0, 1.0, -1.0]
radius = 0.3
[terrains.motion]
interpolation = "linear"
keyframes = [
  {time = 0.0, position = [0.0, 0.0, 0.0]},
  {time = 0.2, position = [0.0, 0.0, 1.5], rotation_degrees = 30.0, rotation_axis = [0.0, 1.0, 0.0]},
]
"""
    scene = scene_from_table(tomllib.loads(text))
    scene.validate()
    motion = scene.terrains[0].motion
    assert motion.keyframes[1].rotation_degrees == 30.0
    centre = scene.terrains[0].place_at([[0.0, 1.0, -1.0]], 0.1)   # turns about itself
    assert np.allclose(centre, [[0.0, 1.0, -0.25]], atol=1e-15)
    with pytest.raises(SceneError, match="terrains.0.motion.velocity"):
        scene.terrains[0].motion.velocity = (1.0, 0.0, 0.0)
        scene.validate()


def test_motion_pins_and_wind_are_written_out_and_read_back():
    """scene_to_toml writes what load_scene reads back: the motion, moving pins and wind."""
    import tomllib

    from springsim.scenefile import apply_override, scene_to_toml

    table = {"bodies": [{"type": "cloth", "particles_per_edge": 3, "pins": [
        {"particles": [0], "motion": {"velocity": [0.0, 1.0, 0.0]}},
        {"particles": [2], "follow": "terrains.0", "stiffness": 50.0}]}],
        "terrains": [{"type": "sphere", "motion": {
            "interpolation": "smooth",
            "keyframes": [{"time": 0.0}, {"time": 1.0, "position": [1.0, 0.0, 0.0]}]}}],
        "wind": {"velocity": [3.0, 0.0, 0.0], "gusts": {"strength": 0.2, "seed": 4}}}
    scene = scene_from_table(table)
    scene.validate()
    again = scene_from_table(tomllib.loads(scene_to_toml(scene)))
    assert again == scene
    moved = apply_override(again, "terrains.0.motion.keyframes.1.time=2.0")
    assert moved.terrains[0].motion.keyframes[1].time == 2.0
    plane = apply_override(scene_from_table({"bodies": [{"type": "balls"}],
                                             "terrains": [{"type": "plane"}]}),
                           "terrains.0.motion.velocity=[0.0, 0.0, 2.0]")
    assert plane.terrains[0].motion.velocity == (0.0, 0.0, 2.0)
