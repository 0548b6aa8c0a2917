"""The exported files opened in Blender itself (``bpy`` 4.2, Blender as a Python module).

Oracle: the real client. Blender imports the USD (its own importer, with the stage's up axis and
time codes) and applies the MDD and PC2 caches to the imported rest-pose OBJ through its Mesh
Cache modifier; at the first, a middle and the last frame every surface vertex and every ball
centre is where the recording has it, within 0.1 mm, after Blender's Y-up to Z-up conversion
((x, y, z) -> (x, -z, y)); Blender's frame range has the recording's frame count. Blender runs
once, in a subprocess (tests/blender_check.py), for the whole module.

``bpy`` is installed by ./test.sh (the ``blender`` extra); without it this module is skipped
locally and fails under CI.
"""
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd

from springsim import Simulation, load_scene
from springsim.cli import main
from springsim.recording import record, write_npz

pytestmark = pytest.mark.external   # the external tier (conftest.py): Blender

TOLERANCE = 1e-4   # m: 0.1 mm

if importlib.util.find_spec("bpy") is None:
    if os.environ.get("CI") == "true":
        raise RuntimeError("bpy (Blender as a module) is missing: pip install -e '.[blender]'")
    pytest.skip("bpy is not installed here (./test.sh installs it: pip install -e '.[blender]')",
                allow_module_level=True)


def y_up_to_z_up(points):
    points = np.asarray(points, float)
    return np.stack([points[..., 0], -points[..., 2], points[..., 1]], axis=-1)


@pytest.fixture(scope="module")
def blender(tmp_path_factory):
    """jelly-balls (a 4 x 4 x 4 cube and three balls on the plane), 1 s at 24 fps, exported to
    USD, MDD and PC2 and opened in Blender at the first, a middle and the last frame."""
    folder = tmp_path_factory.mktemp("blender")
    simulation = Simulation(load_scene("jelly-balls", ["bodies.0.particles_per_edge=4"]))
    recording = record(simulation, 1.0, 24.0)
    npz = folder / "take.npz"
    write_npz(npz, recording.arrays())
    paths = [folder / name for name in ("take.usd", "take.mdd", "take.pc2")]
    assert main(["export", "--quiet", str(npz), *map(str, paths)]) == 0
    last = recording.frame_count - 1
    frames = [0, last // 2, last]    # recording frame f is Blender frame f + 1 (--start-frame 1)
    script = Path(__file__).with_name("blender_check.py")
    done = subprocess.run([sys.executable, str(script), str(paths[0]), str(folder / "take.obj"),
                           str(paths[1]), str(paths[2]), *(str(f + 1) for f in frames)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout.strip().splitlines()[-1])
    return simulation, recording, frames, report, paths[0]


def test_blender_sees_the_recordings_frame_range_and_the_file_its_fps(blender):
    _, recording, _, report, usd_path = blender
    usd = report["usd"]
    assert usd["frame_end"] - usd["frame_start"] + 1 == recording.frame_count == 25
    assert usd["frame_start"] == 1
    assert Usd.Stage.Open(str(usd_path)).GetTimeCodesPerSecond() == recording.fps == 24.0


def test_every_surface_vertex_and_ball_centre_is_where_the_recording_has_it(blender):
    simulation, recording, frames, report, _ = blender
    cube = simulation.model.bodies[0]
    surface = np.unique(cube.surface)
    balls = simulation.model.arrays.balls
    for frame in frames:
        seen = report["usd"]["frames"][str(frame + 1)]
        expected = y_up_to_z_up(recording.positions[frame])
        np.testing.assert_allclose(seen["bodies"]["cube0"], expected[surface], atol=TOLERANCE)
        centres = [seen["balls"][f"ball_{number}"] for number in range(len(balls))]
        np.testing.assert_allclose(centres, expected[balls], atol=TOLERANCE)


@pytest.mark.parametrize("cache", ["mdd", "pc2"])
def test_the_point_caches_move_the_rest_mesh_through_the_recording(blender, cache):
    simulation, recording, frames, report, _ = blender
    surface = np.unique(simulation.model.bodies[0].surface)
    balls = simulation.model.arrays.balls
    radius = simulation.model.arrays.radius[balls]
    for frame in frames:
        seen = np.asarray(report[cache][str(frame + 1)])
        expected = y_up_to_z_up(recording.positions[frame])
        np.testing.assert_allclose(seen[:len(surface)], expected[surface], atol=TOLERANCE)
        spheres = seen[len(surface):].reshape(len(balls), -1, 3)
        # each ball's sphere: its vertices lie one radius from the recorded centre
        distance = np.linalg.norm(spheres - expected[balls][:, None], axis=-1)
        np.testing.assert_allclose(distance, np.broadcast_to(radius[:, None], distance.shape),
                                   atol=TOLERANCE)
        np.testing.assert_allclose(spheres.mean(axis=1), expected[balls], atol=TOLERANCE)
