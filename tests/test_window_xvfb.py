"""The real window: `springsim view` on a virtual display (Xvfb), in a process of its own
(polyscope starts once per process, and the other tests run it headless).

Oracles: the viewer opens a GLFW window (not the headless backend), runs the requested frames
with the simulation started, and its screenshot has the window's size and shows both the panel
(dark ImGui background on the left) and the orange cube in the free part of the window.
"""
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import imageio.v3 as iio

pytestmark = pytest.mark.external   # the external tier (conftest.py): Xvfb

WIDTH, HEIGHT = 800, 500


def start_xvfb():
    """An Xvfb server on a free display number (it reports the number on a pipe)."""
    xvfb = shutil.which("Xvfb")
    if not xvfb:
        reason = ("Xvfb is missing: apt-get install xvfb xauth (./test.sh installs it when run "
                  "as root; scripts/system-packages.txt)")
        assert os.environ.get("CI", "").lower() not in ("true", "1"), reason  # CI must run it
        pytest.skip(reason)
    read, write = os.pipe()
    server = subprocess.Popen([xvfb, "-displayfd", str(write), "-screen", "0",
                               f"{WIDTH + 200}x{HEIGHT + 200}x24", "-nolisten", "tcp"],
                              pass_fds=(write,), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    os.close(write)
    with os.fdopen(read) as pipe:
        display = pipe.readline().strip()
    assert display, "Xvfb did not start"
    return server, f":{display}"


def window_screenshot(arguments, tmp_path, width=WIDTH, height=HEIGHT):
    """Run ``springsim ARGUMENTS --width --height --screenshot`` on a virtual display; checks
    that it opened a real GLFW window and returns its screenshot (height, width, 3) as ints."""
    server, display = start_xvfb()
    screenshot = tmp_path / "window.png"
    try:
        result = subprocess.run(
            [sys.executable, "-m", "springsim", *arguments, "--width", str(width), "--height",
             str(height), "--screenshot", str(screenshot)],
            env={**os.environ, "DISPLAY": display}, cwd=tmp_path, capture_output=True,
            text=True, timeout=180)
    finally:
        server.terminate()
        server.wait(timeout=30)
    assert result.returncode == 0, result.stderr
    assert "openGL3_glfw" in result.stdout
    picture = iio.imread(screenshot)[..., :3].astype(int)
    assert picture.shape == (height, width, 3)
    return picture


def test_view_opens_a_window_and_takes_a_screenshot(tmp_path):
    picture = window_screenshot(["view", "jelly-plane", "--start", "--frames", "20",
                                 "--record-folder", str(tmp_path)], tmp_path)
    panel, scene = picture[:, :300], picture[:, 360:]
    dark = np.all(panel < 90, axis=-1)
    assert dark.mean() > 0.2                                # ImGui's dark panel
    r, g, b = scene[..., 0], scene[..., 1], scene[..., 2]
    orange = (r > 150) & (r - b > 60) & (g > b)
    assert orange.mean() > 0.02                             # the cube's lit faces
    assert sorted(p.name for p in tmp_path.iterdir()) == ["window.png"]  # nothing else left
