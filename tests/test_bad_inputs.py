"""Bad input on the command line: refused before any work with one line naming the key, the value
and what is allowed (exit 2), never a traceback, a warning, a hang or a huge allocation.

Oracles: the exit code, the key that starts the one line, the limits it quotes (the machine's
memory as the test sets it), nothing written, and the peak memory traced while refusing (a
refusal before allocating stays far below what the request would take).
"""
import os
import shutil
import stat
import subprocess
import sys
import tempfile
import tracemalloc
import warnings

import numpy as np
import pytest

from springsim import sizes
from springsim.cli import main
from springsim.safe_files import check_output_path
from springsim.sampling import MAX_FRAMES

SMALL = ["--set", "bodies.0.particles_per_edge=3", "--set", "bodies.0.position.1=2"]
GB = 10 ** 9


@pytest.fixture
def machine_with_16_gb(monkeypatch):
    """The refusals quote the machine's memory; the tests fix it so they hold on any machine."""
    monkeypatch.setattr(sizes, "machine_memory", lambda: 16 * GB)


def refused(capsys, argv, key):
    """Run the command; it must exit 2 with one line starting with ``key = ``, warning-free, and
    without allocating more than 64 MB on the way. Returns the line."""
    tracemalloc.start()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            code = main(argv)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    captured = capsys.readouterr()
    assert (code, captured.out, caught) == (2, "", []), captured.err
    lines = captured.err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"springsim {argv[0]}: {key} = "), lines
    assert peak < 64 * 2 ** 20
    return lines[0]


@pytest.mark.parametrize("argv, key, says", [
    (["run", "jelly-plane", "--fps", "inf"], "fps", "finite"),
    (["run", "jelly-plane", "--fps", "nan"], "fps", "finite"),
    (["run", "jelly-plane", "--fps", "1e9", "--dt", "1e-6"], "fps",
     f"at most {MAX_FRAMES:,} frames"),   # frames at the steps: 8e6 steps of 1e-6 s
    (["render", "jelly-plane", "--out", "x.mp4", "--fps", "1e6"], "fps",
     f"at most {MAX_FRAMES:,} frames"),
    (["render", "jelly-plane", "--out", "x.mp4", "--fps", "inf"], "fps", "finite"),
    (["run", "jelly-plane", "--set", "bodies.0.particles_per_edge=2000"],
     "bodies.0.particles_per_edge", "8,000,000,000 particles"),
    (["run", "jelly-plane", "--set", "bodies.0.particles_per_edge=200"],
     "bodies.0.particles_per_edge", "8,000,000 particles and 126,683,596 springs"),
    (["render", "cloth-balls", "--out", "x.gif", "--set", "bodies.0.particles_per_edge=5000"],
     "bodies.0.particles_per_edge", "25,000,004 particles"),   # 5000^2 + 4 balls
    (["bench", "jelly-plane", "--set", "bodies.0.particles_per_edge=300"],
     "bodies.0.particles_per_edge", "27,000,000 particles"),
])
def test_sizes_are_refused_before_allocating_with_the_estimate_and_the_memory(
        capsys, tmp_path, monkeypatch, machine_with_16_gb, argv, key, says):
    monkeypatch.chdir(tmp_path)
    line = refused(capsys, argv, key)
    assert says in line
    if "particles" in says:
        assert "this machine has 16 GB of memory" in line
    assert os.listdir(tmp_path) == []


def test_frames_that_do_not_fit_in_memory_name_the_estimate_and_the_memory(
        capsys, tmp_path, machine_with_16_gb):
    # 100^3 particles (a model of ~7 GB, allowed) recorded at 60 fps for 8 s: 481 frames of
    # positions and velocities are 23.1 GB, more than half of 16 GB
    line = refused(capsys, ["run", "jelly-plane", "--set", "bodies.0.particles_per_edge=100",
                            "--out", str(tmp_path / "x.npz")], "fps")
    assert "keeping 481 frames of 1,000,000 particles needs about 23.1 GB" in line
    assert "this machine has 16 GB of memory" in line


@pytest.mark.parametrize("command", [["run", "jelly-plane"],
                                     ["render", "jelly-plane", "--out", "x.mp4"]])
@pytest.mark.parametrize("duration", ["0", "-1", "inf", "nan"])
def test_run_and_render_have_one_rule_for_the_duration(capsys, tmp_path, monkeypatch, command,
                                                       duration):
    monkeypatch.chdir(tmp_path)
    line = refused(capsys, [*command, "--duration", duration], "duration")
    assert line.endswith("must be a finite time > 0 s")


@pytest.mark.parametrize("argv, key, says", [
    (["run", "jelly-plane", "--set", "bodies.0.rotation_degrees=1e300"],
     "bodies.0.rotation_degrees", "finite angle"),
    (["run", "cloth-hang", "--set", "bodies.0.rotation_degrees=-1e300"],
     "bodies.0.rotation_degrees", "finite angle"),
    (["render", "jelly-plane", "--out", "x.mp4", "--width", "100000"], "width", "8192"),
    (["render", "jelly-plane", "--out", "frames", "--height", "99999999"], "height", "8192"),
    (["view", "--width", "70000"], "width", "8192"),
    (["convergence", "--final-time", "inf"], "final-time", "at most 60 s"),
    (["convergence", "--final-time", "nan"], "final-time", "at most 60 s"),
    (["run", "jelly-plane", "--set", "implicit.cg_tolerance=5"], "implicit.cg_tolerance",
     "(0, 1)"),
    (["run", "jelly-plane", "--integrator", "midpoint", "--set",
      "implicit.newton_iterations=0"], "implicit.newton_iterations", ">= 1"),
    (["run", "jelly-plane", "--set", "implicit.cg_max_iterations=-3"],
     "implicit.cg_max_iterations", ">= 1"),
    (["bench", "jelly-plane", "--steps", str(10 ** 20)], "steps", "from 1 to 1,000,000,000"),
    (["bench", "jelly-plane", "--seconds", "1e300"], "seconds", "at most 3600 s"),
    (["view", "--frames", "-1"], "--frames", ">= 0"),
])
def test_each_bad_value_is_blamed_on_its_own_key(capsys, tmp_path, monkeypatch, argv, key,
                                                 says):
    monkeypatch.chdir(tmp_path)
    assert says in refused(capsys, argv, key)
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("setting", ["gravity.1=1e300", "bodies.0.structural.ks=1e300",
                                     "bodies.0.velocity.1=1e300"])
def test_a_blow_up_is_one_divergence_line_without_numpy_warnings(setting, tmp_path):
    result = subprocess.run([sys.executable, "-W", "default", "-m", "springsim", "run",
                             "jelly-plane", *SMALL, "--set", setting],
                            cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert (result.returncode, result.stdout) == (3, "")
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and "diverged" in lines[0], lines
    assert os.listdir(tmp_path) == []


# --- outputs: every path of every command checked before the work --------------------------------

@pytest.mark.parametrize("argv, key", [
    (["run", "jelly-plane", "--out", "missing/x.npz"], "--out"),
    (["run", "jelly-plane", "--plot", "missing/e.png"], "--plot"),
    (["run", "jelly-plane", "--video", "missing/v.mp4"], "--video"),
    (["run", "jelly-plane", "--out", "."], "--out"),
    (["render", "jelly-plane", "--out", "missing/x.mp4"], "--out"),
    (["stability", "--csv", "missing/x.csv"], "--csv"),
    (["stability", "--png", "missing/x.png"], "--png"),
    (["convergence", "--png", "missing/c.png"], "--png"),
    (["view", "--record-folder", "missing"], "--record-folder"),
    (["view", "--screenshot", "missing/s.png"], "--screenshot"),
    (["run", "jelly-plane", "--out", "n" * 300 + ".npz"], "--out"),
])
def test_every_output_path_is_checked_before_the_work(capsys, tmp_path, monkeypatch, argv, key):
    monkeypatch.chdir(tmp_path)
    line = refused(capsys, argv, key)
    assert ("does not exist" in line or "is a folder" in line or "must be an existing folder"
            in line or "bytes long; this file system allows at most 255" in line)
    assert os.listdir(tmp_path) == []


def test_a_read_only_folder_is_refused_before_the_work(tmp_path):
    """As root every folder is writable, so the check runs in a child that is an ordinary user
    (nobody) there."""
    outer = tempfile.mkdtemp()                      # pytest's tmp_path is private to its user
    os.chmod(outer, 0o755)
    folder = os.path.join(outer, "read-only")
    os.mkdir(folder, 0o555)
    read, write = os.pipe()
    child = os.fork()
    if child == 0:                                  # the child: check, report, exit at once
        try:
            if os.geteuid() == 0:
                os.setuid(65534)
            check_output_path("--csv", os.path.join(folder, "x.csv"))
            message = b"accepted"
        except BaseException as error:
            message = f"{type(error).__name__}: {error}".encode()
        finally:
            os.write(write, message)
            os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as pipe:
        message = pipe.read().decode()
    os.waitpid(child, 0)
    shutil.rmtree(outer)
    assert message.startswith("SceneError: --csv = ") and message.endswith(
        f"the folder {folder} is not writable"), message


@pytest.mark.parametrize("folder", ["/proc", "/sys"])
def test_a_folder_that_refuses_new_files_whatever_its_permissions_is_refused_before_the_work(
        folder, tmp_path, capsys, monkeypatch):
    """/proc and /sys look writable to root (os.access says yes) but take no new file: the check
    tries to make one, as the writers will, so run, export and the studies stop before any work
    with exit 2 and one line, and write nothing."""
    monkeypatch.chdir(tmp_path)
    assert main(["run", "jelly-plane", *SMALL, "--duration", "0.05", "--quiet"]) == 0
    capsys.readouterr()
    commands = [["run", "jelly-plane", *SMALL, "--duration", "0.05", "--out", f"{folder}/x.npz"],
                ["export", "jelly-plane.npz", f"{folder}/take.usd"],
                ["stability", "--quick", "--csv", f"{folder}/s.csv"]]
    for command in commands:
        assert main(command) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and f"the folder {folder} is not writable" in lines[0], lines
    assert sorted(os.listdir(tmp_path)) == ["jelly-plane.npz"]


def test_a_long_scene_name_without_out_gets_a_shortened_file_name(capsys, tmp_path,
                                                                  monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(["run", "jelly-plane", *SMALL, "--set", f"name={'a' * 300}", "--duration",
                 "0.05", "--quiet"])
    assert code == 0 and os.listdir(tmp_path) == ["a" * 120 + ".npz"]


# --- inputs: scene files read safely -------------------------------------------------------------

def test_a_fifo_a_device_a_folder_and_a_huge_file_are_refused_without_reading(capsys,
                                                                            tmp_path):
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    device = tmp_path / "zero.toml"
    device.symlink_to("/dev/zero")
    folder = tmp_path / "folder.toml"
    folder.mkdir()
    huge = tmp_path / "huge.toml"
    with open(huge, "wb") as file:
        file.truncate(17 * 2 ** 20)                 # sparse: nothing is really written
    for path, says in ((fifo, "is a FIFO"), (device, "is a character device"),
                       (folder, "is a folder"), (huge, "17,825,792 bytes; a scene file may have "
                                                       "at most 16,777,216 (16 MB)")):
        line = refused(capsys, ["run", str(path)], "scene")
        assert says in line
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


# --- the moving world, point caches, pins, wind and mesh files: one line each, by the full key ---

PLATE = ("v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
         "f 1 4 3\nf 1 3 2\n")                       # a 2 m square, its normals up
CLOTH = '[[bodies]]\ntype = "cloth"\nparticles_per_edge = 3\nposition = [0.0, 2.0, 0.0]\n'


def write_pc2(path, frames):
    from springsim.export.pc2 import encode

    frames = np.asarray(frames, float)
    with open(path, "wb") as file:
        encode(file, frames, np.arange(len(frames)) / 24.0, 24.0, 0)


def scene_file(folder, text, files=()):
    """A scene file and the mesh files it names, in ``folder``; returns its path."""
    for name, body in files:
        (folder / name).write_text(body)
    (folder / "bad.toml").write_text(text)
    return str(folder / "bad.toml")


MOVING_SPHERE = (CLOTH + '[[terrains]]\ntype = "sphere"\ncenter = [3.0, 0.0, 0.0]\n'
                 'radius = 0.5\n[terrains.motion]\n')


@pytest.mark.parametrize("text, files, key, says", [
    # a motion whose lengths float64 cannot hold: once an OverflowError in substeps.py
    (MOVING_SPHERE + "velocity = [1e300, 0.0, 0.0]\n", (), "terrains.0.motion.velocity",
     "= (1e+300, 0.0, 0.0): must be three finite numbers, each within +-1e+150"),
    (MOVING_SPHERE + "[[terrains.motion.keyframes]]\ntime = 0.0\n"
                     "[[terrains.motion.keyframes]]\ntime = 1.0\nposition = [0.0, 1e300, 0.0]\n",
     (), "terrains.0.motion.keyframes.1.position", "= (0.0, 1e+300, 0.0): must be three finite "
                                                    "numbers (m), each within +-1e+150"),
    # once blamed on the zero velocity
    (MOVING_SPHERE + "angular_velocity = [0.0, 1.0, 0.0]\n[[terrains.motion.keyframes]]\n"
                     "time = 0.0\n", (), "terrains.0.motion.angular_velocity",
     "= (0.0, 1.0, 0.0): a motion is keyframes or a velocity and angular velocity, not both"),
    # once a ValueError from NumPy's generator, after the model was built
    (CLOTH + "[wind]\nvelocity = [1.0, 0.0, 0.0]\ngusts = {strength = 0.3, seed = -1}\n", (),
     "wind.gusts.seed", "= -1: must be a whole number >= 0"),
    # once a traceback from the faces' fans (-4 of 3 counted back to -1, the padding)
    (CLOTH.replace("particles_per_edge = 3", 'file = "neg.obj"'),
     [("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 -4\n")], "bodies.0.file",
     "has a face naming a vertex it does not have (vertex -4, line 4; 3 are defined before "
     "it: a face names vertices from 1, or -1 to -3 counting back from the last)"),
    # once regrouped silently: six two-number lines read as four vertices
    (CLOTH.replace("particles_per_edge = 3", 'file = "two.obj"'),
     [("two.obj", "v 0 0\nv 1 0\nv 0 1\nv 1 1\nv 0 0\nv 1 1\nf 1 2 3\nf 1 3 4\n")],
     "bodies.0.file", "has a vertex line that is not three numbers (line 1: 'v 0 0'); each "
                      "vertex is 'v x y z'"),
    # once accepted: trimesh's processing dropped the vertex that the cloth reader refuses
    (CLOTH + '[[terrains]]\ntype = "mesh"\nfile = "nan.obj"\n',
     [("nan.obj", PLATE.replace("v 1 0 1", "v 1 nan 1"))], "terrains.0.file",
     "has vertices that are not finite numbers (1; the first is number 2)"),
])
def test_bad_moving_world_and_mesh_input_is_one_line_by_its_full_key(capsys, tmp_path, text,
                                                                      files, key, says):
    path = scene_file(tmp_path, text, files)
    assert says in refused(capsys, ["run", path], key)
    assert not (tmp_path / "bad.npz").exists()


def pin_scene(tmp_path, pin, frames, vertices=None):
    """A 3 x 3 cloth whose pin ``pin`` (TOML lines) follows or reads ``cache.pc2`` (``frames``,
    samples of ``vertices``), above a plate deformed by the same cache."""
    write_pc2(tmp_path / "cache.pc2", frames)
    return scene_file(tmp_path, CLOTH + "[[bodies.pins]]\nparticles = [0]\n" + pin
                      + '[[terrains]]\ntype = "mesh"\nfile = "plate.obj"\n'
                        '[terrains.animation]\nfile = "cache.pc2"\n', [("plate.obj", PLATE)])


def test_a_pin_cache_of_another_count_names_the_body_the_file_and_both_counts(capsys,
                                                                               tmp_path):
    """Once 'pins.0.animation.file = 24: points in the cache ...': no body, and a count for the
    file."""
    plate = np.loadtxt(PLATE.splitlines()[:4], usecols=(1, 2, 3))
    path = pin_scene(tmp_path, '[bodies.pins.animation]\nfile = "cache.pc2"\n', [plate, plate])
    line = refused(capsys, ["run", path], "bodies.0.pins.0.animation.file")
    assert line.endswith(f"= '{tmp_path / 'cache.pc2'}': moves 4 points, but the body has 9 "
                         "particles")


def test_a_pin_riveted_to_a_cache_with_no_area_at_time_0_is_refused(capsys, tmp_path):
    """The plate's first sample is folded flat onto a line (it unfolds later): no triangle has
    a frame to rivet to. Once an IndexError from the nearest-triangle search."""
    plate = np.loadtxt(PLATE.splitlines()[:4], usecols=(1, 2, 3))
    flat = plate * [1.0, 1.0, 0.0]
    path = pin_scene(tmp_path, 'follow = "terrains.0"\n', [flat, plate])
    line = refused(capsys, ["run", path], "bodies.0.pins.0.follow")
    assert line.endswith("= 'terrains.0': rivets each particle to its nearest triangle of "
                         f"terrains.0, but no triangle of its point cache "
                         f"({tmp_path / 'cache.pc2'}) has any "
                         "area at time 0: follow a terrain whose surface has area then, or "
                         "start its animation where it does")


def test_a_nan_in_the_second_file_of_an_obj_sequence_names_that_file(capsys, tmp_path):
    files = [("plate.obj", PLATE), ("walk_0001.obj", PLATE),
             ("walk_0002.obj", PLATE.replace("v 1 0 1", "v 1 nan 1"))]
    path = scene_file(tmp_path, CLOTH + '[[terrains]]\ntype = "mesh"\nfile = "plate.obj"\n'
                                        '[terrains.animation]\nfile = "walk_####.obj"\n', files)
    line = refused(capsys, ["run", path], "terrains.0.animation.file")
    assert "walk_0002.obj': has vertices that are not finite numbers (1; the first is number " \
           "2)" in line and "walk_0001" not in line


def test_a_huge_mesh_file_is_measured_before_a_byte_is_read(capsys, tmp_path,
                                                            machine_with_16_gb):
    """5 GB of one line (sparse: nothing is really written): refused from its size against the
    machine's memory, under the 64 MB that ``refused`` allows."""
    with open(tmp_path / "huge.obj", "wb") as file:
        file.truncate(5 * GB)
    for text, key in ((CLOTH.replace("particles_per_edge = 3", 'file = "huge.obj"'),
                       "bodies.0.file"),
                      (CLOTH + '[[terrains]]\ntype = "mesh"\nfile = "huge.obj"\n',
                       "terrains.0.file")):
        line = refused(capsys, ["run", scene_file(tmp_path, text)], key)
        assert line.endswith(f"= '{tmp_path / 'huge.obj'}': is 5,000,000,000 bytes; reading a "
                             "mesh file that large takes about 100 GB, and this machine has 16 "
                             "GB of memory")


def test_a_mesh_file_of_one_huge_line_is_refused_at_its_first_megabyte(capsys, tmp_path,
                                                                       monkeypatch):
    """On a machine that could read it whole, a 200 MB line is still not an OBJ line: the
    reader stops at the first megabyte."""
    monkeypatch.setattr(sizes, "machine_memory", lambda: 10 ** 6 * GB)
    with open(tmp_path / "line.obj", "wb") as file:
        file.write(b"v 0 0 0 ")
        file.truncate(200 * 2 ** 20)
    text = CLOTH.replace("particles_per_edge = 3", 'file = "line.obj"')
    line = refused(capsys, ["run", scene_file(tmp_path, text)], "bodies.0.file")
    assert "has a line longer than 1,048,576 characters (line 1)" in line
