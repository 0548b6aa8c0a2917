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
