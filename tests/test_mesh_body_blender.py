"""A mesh body's point cache applies to the artist's own file in Blender (issue 29, part 6).

Oracle: the real client. The file's vertices repeat along its UV seam and at its poles (a
vertex per (position, UV) pair, as game exporters write them); springsim simulates the welded
solid but writes a PC2 of the FILE's vertices in the file's order. Blender imports the original
OBJ with its own importer, a Mesh Cache modifier reads the PC2 (it checks the vertex count), and
at the first, a middle and the last frame every vertex is where the recording's surface has it,
within 0.1 mm, after Blender's Y-up to Z-up conversion.
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

TOLERANCE = 1e-4   # m
DATA = Path(__file__).with_name("data")

if importlib.util.find_spec("bpy") is None:
    if os.environ.get("CI") == "true":
        raise RuntimeError("bpy (Blender as a module) is missing: pip install -e '.[blender]'")
    pytest.skip("bpy is not installed here (./test.sh installs it: pip install -e '.[blender]')",
                allow_module_level=True)


def test_the_pc2_of_a_mesh_body_moves_the_original_file_in_blender(tmp_path):
    original = DATA / "uv_sphere_unwelded.obj"
    body = MeshBody(file=str(original), particles=200, position=(0.0, 1.3, 0.0))
    simulation = Simulation(Scene(bodies=[body], terrains=[Plane(point=(0, 0, 0))],
                                  integrator="implicit_euler", dt=1 / 60))
    recording = record(simulation, 0.5, 24.0)
    write_npz(tmp_path / "take.npz", recording.arrays())
    assert main(["export", "--quiet", str(tmp_path / "take.npz"), str(tmp_path / "take.pc2")]) == 0
    last = recording.frame_count - 1
    frames = [0, last // 2, last]
    code = ("import json, sys; sys.path.insert(0, sys.argv[1]); import blender_check; "
            "print(json.dumps(blender_check.point_cache(sys.argv[2], sys.argv[3], 'PC2', "
            "[int(f) + 1 for f in sys.argv[4:]])))")
    done = subprocess.run([sys.executable, "-c", code, str(Path(__file__).parent), str(original),
                           str(tmp_path / "take.pc2"), *map(str, frames)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    file_vertices = len(body.mesh().vertices)
    assert file_vertices > len(body.solid().vertices)          # the seam copies are there
    for frame in frames:
        expected = body_surface(simulation.model.bodies[0], recording.positions[frame]).vertices
        assert expected.shape == (file_vertices, 3)
        np.testing.assert_allclose(seen[str(frame + 1)], np.stack(
            [expected[:, 0], -expected[:, 2], expected[:, 1]], axis=1), atol=TOLERANCE)
