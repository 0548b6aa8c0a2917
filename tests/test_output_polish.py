"""Output without repeats, noise or stray bytes, and frame rates checked before any array is
made (issue 56, items 9 and 11).

Oracles: the files a command names are the files on disk, each once; a printed scene is a
portable file (no path of this machine) whose numbers are the ones the scene was written with,
and it reads back to the same scene; a warning names the user's line; an fps the guide says is
refused is refused in one line.
"""
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from springsim.cli import main
from springsim.presets import PRESETS
from springsim.scenefile import AutomaticStep, load_scene

SMALL_RUN = ["jelly-plane", "--set", "bodies.0.particles_per_edge=3", "--integrator", "rk4",
             "--dt", "0.001"]


@pytest.fixture
def recording(tmp_path):
    path = tmp_path / "take.npz"
    assert main(["run", *SMALL_RUN, "--duration", "0.05", "--quiet", "--out", str(path)]) == 0
    return path


def test_export_names_each_file_once(tmp_path, recording, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["export", str(recording), "take.mdd", "take.pc2"]) == 0
    line = capsys.readouterr().out.strip()
    named = line.removeprefix("wrote ").split(":")[0].split(", ")
    assert named == ["take.mdd", "take.obj", "take.pc2"], line
    assert all(Path(name).is_file() for name in named)


def test_export_refuses_an_fps_too_high_before_making_its_frames(tmp_path, recording, capsys):
    # 1e12 frames a second over 0.05 s: 5e10 frames, which NumPy could not even number
    assert main(["export", str(recording), str(tmp_path / "x.mdd"), "--fps", "1e12"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "--fps = 1000000000000.0" in lines[0] and "frames" in lines[0]
    assert not (tmp_path / "x.mdd").exists()


def test_run_refuses_fps_1e9_as_the_guide_says(tmp_path, capsys):
    out = tmp_path / "take.npz"
    assert main(["run", *SMALL_RUN, "--duration", "0.01", "--fps", "1e9",
                 "--out", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "fps = 1000000000.0" in lines[0], lines
    assert not out.exists()


def test_a_printed_scene_is_portable_and_has_no_float_noise(tmp_path, capsys):
    assert main(["scenes", "cape", "--short"]) == 0
    text = capsys.readouterr().out
    assert str(Path.home()) not in text and "/.cache/" not in text
    assert 'file = "builtin:walking-figure.obj"' in text
    assert 'file = "builtin:walking-figure.pc2"' in text
    assert text.count("# builtin:NAME") == 1   # said once, above the first
    assert noisy_numbers(text) == []
    path = tmp_path / "cape.toml"
    path.write_text(text)
    printed, built_in = load_scene(str(path)), load_scene("cape")
    assert printed.terrains[1].file == built_in.terrains[1].file
    assert printed.terrains[1].animation.file == built_in.terrains[1].animation.file
    assert printed.bodies[0].pins[0].region == built_in.bodies[0].pins[0].region


def noisy_numbers(text: str) -> list[str]:
    """The numbers of a printed scene that no person wrote: more than 6 significant digits
    (1.5899999999999999, a float sum's). dt = 1/60 s has no shorter decimal."""
    values = text.replace(f"dt = {1 / 60!r}\n", "")
    numbers = re.findall(r"(?<![\w.])-?\d+\.\d+(?:e-?\d+)?", values)
    assert numbers
    return [n for n in numbers if len(n.lstrip("-").split("e")[0].replace(".", "").lstrip("0")) > 6]


@pytest.mark.parametrize("name", PRESETS)
def test_no_printed_built_in_scene_has_float_noise(name, capsys):
    """Every built-in scene, printed whole: cloth-sweep's pin region said 2.1900000000000004."""
    assert main(["scenes", name]) == 0
    assert noisy_numbers(capsys.readouterr().out) == []


def test_the_automatic_step_warning_names_the_users_line(tmp_path):
    """Through springsim's own code (a sweep's grid loads the scene), the warning still points
    at the line that called springsim, and reads as a sentence."""
    from springsim.sweeps.grid import build_grid

    path = tmp_path / "nodt.toml"
    path.write_text('integrator = "implicit_euler"\n[[bodies]]\ntype = "cube"\n'
                    'particles_per_edge = 3\n')
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        build_grid(str(path), [])
    step = [w for w in said if issubclass(w.category, AutomaticStep)]
    assert len(step) == 1 and step[0].filename == __file__
    assert str(step[0].message).endswith(
        "dt = 0.0167 s, from a frame's step, at which implicit_euler is stable")


def test_a_run_on_a_terminal_leaves_no_stray_escape(tmp_path):
    """Numba's coloured errors started colorama, whose exit hook wrote ESC[0m to the terminal
    after every run."""
    import os
    import pty
    import select
    import subprocess
    import sys

    leader, follower = pty.openpty()
    command = [sys.executable, "-m", "springsim", "run", *SMALL_RUN, "--duration", "0.01",
               "--out", str(tmp_path / "take.npz")]
    environment = {k: v for k, v in os.environ.items()
                   if k != "NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING"}
    process = subprocess.Popen(command, stdin=follower, stdout=follower, stderr=follower,
                               env=environment, cwd=tmp_path)
    os.close(follower)
    shown = b""
    while True:
        ready, _, _ = select.select([leader], [], [], 120)
        try:
            chunk = os.read(leader, 4096) if ready else b""
        except OSError:   # the terminal closed with the process
            break
        if not chunk:
            break
        shown += chunk
    os.close(leader)
    assert process.wait(timeout=120) == 0, shown
    assert b"wrote" in shown and b"\x1b[0m" not in shown, shown[-200:]
