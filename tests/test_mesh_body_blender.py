"""A mesh body's point caches and OBJ sequence apply to the artist's own file in Blender (issue 29,
part 6).

Oracle: the real client. The file's vertices repeat along its UV seam and at its poles (a
vertex per (position, UV) pair, as game exporters write them); springsim simulates the welded
solid but writes a PC2 of the FILE's vertices in the file's order. Blender imports the original
OBJ with its own importer, a Mesh Cache modifier reads the PC2 (it checks the vertex count), and
at the first, a middle and the last frame every vertex is where the recording's surface has it,
within 0.1 mm, after Blender's Y-up to Z-up conversion. The same holds for the MDD, and for each
file of an OBJ sequence imported alone.
"""
import importlib.util
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from springsim import Simulation
from springsim.bodies.mesh import MeshBody
from springsim.cli import main
from springsim.recording import record, write_npz
from springsim.scene import Scene
from springsim.surfaces import body_surface
from springsim.terrains import Plane

pytestmark = pytest.mark.external   # the external tier (conftest.py): Blender

TOLERANCE = 1e-4   # m
DATA = Path(__file__).with_name("data")

if importlib.util.find_spec("bpy") is None:
    if os.environ.get("CI") == "true":
        raise RuntimeError("bpy (Blender as a module) is missing: pip install -e '.[blender]'")
    pytest.skip("bpy is not installed here (./test.sh installs it: pip install -e '.[blender]')",
                allow_module_level=True)


@pytest.fixture(scope="module")
def seamed_take(tmp_path_factory):
    """The seamed sphere dropped on the plane for 0.5 s at 24 fps: (body, simulation, recording,
    its NPZ)."""
    body = MeshBody(file=str(DATA / "uv_sphere_unwelded.obj"), particles=200,
                    position=(0.0, 1.3, 0.0))
    simulation = Simulation(Scene(bodies=[body], terrains=[Plane(point=(0, 0, 0))],
                                  integrator="implicit_euler", dt=1 / 60))
    recording = record(simulation, 0.5, 24.0)
    npz = tmp_path_factory.mktemp("seamed") / "take.npz"
    write_npz(npz, recording.arrays())
    return body, simulation, recording, npz


def z_up(vertices: np.ndarray) -> np.ndarray:
    """springsim's Y-up coordinates as Blender's Z-up world has them after its OBJ import."""
    return np.stack([vertices[:, 0], -vertices[:, 2], vertices[:, 1]], axis=1)


def blender(call: str, *arguments) -> object:
    """What ``blender_check.<call>`` returns, run in a Python with bpy (Blender 4.2)."""
    code = ("import json, sys; sys.path.insert(0, sys.argv[1]); import blender_check; "
            f"print(json.dumps(blender_check.{call}))")
    done = subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent),
                           *map(str, arguments)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("extension, cache_format", [("pc2", "PC2"), ("mdd", "MDD")])
def test_the_point_cache_of_a_mesh_body_moves_the_original_file_in_blender(seamed_take, tmp_path,
                                                                           extension,
                                                                           cache_format):
    body, simulation, recording, npz = seamed_take
    cache = tmp_path / f"take.{extension}"
    assert main(["export", "--quiet", str(npz), str(cache)]) == 0
    last = recording.frame_count - 1
    frames = [0, last // 2, last]
    seen = blender("point_cache(sys.argv[2], sys.argv[3], sys.argv[4], "
                   "[int(f) + 1 for f in sys.argv[5:]])", body.file, cache, cache_format,
                   *frames)
    file_vertices = len(body.mesh().vertices)
    assert file_vertices > len(body.solid().vertices)          # the seam copies are there
    for frame in frames:
        expected = body_surface(simulation.model.bodies[0], recording.positions[frame]).vertices
        assert expected.shape == (file_vertices, 3)
        np.testing.assert_allclose(seen[str(frame + 1)], z_up(expected), atol=TOLERANCE)


def test_an_obj_sequence_of_a_mesh_body_lists_the_files_vertices_in_blender(seamed_take,
                                                                             tmp_path):
    """Each file of the OBJ sequence, imported alone by Blender, has the original file's
    vertices (seam copies and all) in its order, where the recording has them at that frame."""
    body, simulation, recording, npz = seamed_take
    assert main(["export", "--quiet", str(npz), str(tmp_path / "take_####.obj")]) == 0
    last = recording.frame_count - 1
    frames = [0, last // 2, last]
    seen = blender("obj_frames(sys.argv[2:])",
                   *[tmp_path / f"take_{frame + 1:04d}.obj" for frame in frames])
    for frame, vertices in zip(frames, seen):
        expected = body_surface(simulation.model.bodies[0], recording.positions[frame]).vertices
        assert expected.shape == (len(body.mesh().vertices), 3)
        np.testing.assert_allclose(vertices, z_up(expected), atol=TOLERANCE)
