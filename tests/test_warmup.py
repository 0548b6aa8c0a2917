"""The first compile is said before it happens (issue: the first run was silent for 100 s).

Oracles: with no mark in the cache folder, a run prints the notice on stderr before its first
step and marks the integrator after it; with the mark, nothing; a terminal gets a spinner, a log
none; `springsim warmup` compiles and marks each integrator asked for; scripts/ensure-venv.sh
says what each stage does before it starts it (a fake python3 and pip record when they run),
and that it still runs after every quiet SETUP_TICK seconds.
"""
import io
import os
import stat
import subprocess
import textwrap
from pathlib import Path

import pytest

from springsim import warmup
from springsim.cli import main

ROOT = Path(__file__).resolve().parent.parent
SMALL = ["--set", "bodies.0.particles_per_edge=3", "--duration", "0.01"]


@pytest.fixture
def cold_cache(tmp_path, monkeypatch):
    """A cache folder with no marks (the kernels themselves stay in Numba's real cache)."""
    folder = tmp_path / "cache"
    folder.mkdir()
    monkeypatch.setattr(warmup, "cache_folder", lambda: folder)
    return folder


def test_a_run_says_it_compiles_before_the_first_step_and_only_then(cold_cache, tmp_path,
                                                                      capsys, monkeypatch):
    from springsim.simulation import Simulation

    step = Simulation.step
    seen = []

    def step_noting_stderr(self, count=1):
        seen.append(capsys.readouterr().err)   # what was printed before this step
        return step(self, count)

    monkeypatch.setattr(Simulation, "step", step_noting_stderr)
    assert main(["run", "jelly-plane", *SMALL, "--out", str(tmp_path / "a.npz")]) == 0
    assert warmup.NOTICE.format(integrator="rk4") + "\n" == seen[0]
    assert (cold_cache / "warm-rk4").exists()
    seen.clear()
    assert main(["run", "jelly-plane", *SMALL, "--out", str(tmp_path / "b.npz")]) == 0
    assert "compiling" not in "".join(seen) + capsys.readouterr().err


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_terminal_gets_a_spinner_and_a_log_none(cold_cache, monkeypatch):
    monkeypatch.setattr(warmup, "SPIN_EVERY", 0.01)
    terminal, log = Terminal(), io.StringIO()
    with warmup.announced("midpoint", terminal):
        import time
        time.sleep(0.1)
    assert "\r| compiling, 0 s" in terminal.getvalue()
    (cold_cache / "warm-midpoint").unlink()
    with warmup.announced("midpoint", log):
        time.sleep(0.05)
    assert log.getvalue() == warmup.NOTICE.format(integrator="midpoint") + "\n"


def test_warmup_compiles_and_marks_each_integrator(cold_cache, capsys):
    assert main(["warmup", "--integrators", "rk4"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("springsim warmup: compiling the kernels of 1 integrator once")
    assert out[1].split()[0] == "rk4" and out[1].endswith(" s")
    assert [path.name for path in cold_cache.iterdir()] == ["warm-rk4"]


def test_warmup_refuses_an_unknown_integrator_in_one_line(capsys):
    assert main(["warmup", "--integrators", "rk5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("springsim warmup: --integrators = 'rk5': must be one of ")
    assert len(err.splitlines()) == 1


def test_ensure_venv_says_what_each_stage_does_before_it_starts(tmp_path):
    """Every command the setup runs (the fake python3, pip, springsim write a line to the same
    log as they start) comes after a line saying what it is for."""
    fake = tmp_path / "bin"
    fake.mkdir()
    log = tmp_path / "log"
    recorder = textwrap.dedent(f"""\
        #!/bin/sh
        echo "RAN $(basename "$0") $*" >> {log}
        """)
    python = recorder + textwrap.dedent("""\
        if [ "$1 $2" = "-m venv" ]; then
          mkdir -p "$3/bin"
          for tool in pip springsim pytest; do
            cp "$0" "$3/bin/$tool"
          done
        fi
        """)
    # the install says nothing for 2.5 s (as pip installing numba and scipy for a minute)
    python += 'case "$*" in *" -e "*) sleep 2.5;; esac\n'
    (fake / "python3").write_text(python)
    (fake / "python3").chmod(stat.S_IRWXU)
    repo = tmp_path / "clone"
    repo.mkdir()
    (repo / "pyproject.toml").write_text("")
    script = (ROOT / "scripts" / "ensure-venv.sh").read_text()
    subprocess.run(["bash", "-c", f"source /dev/stdin 2>>{log}"], input=script, text=True,
                   cwd=repo, check=True, env={**os.environ, "PATH": f"{fake}:{os.environ['PATH']}",
                                              "SETUP_TICK": "1"})
    lines = log.read_text().splitlines()
    # no quiet stretch longer than SETUP_TICK: the silent install is said to go on each second
    install = next(i for i, line in enumerate(lines) if line.startswith("RAN pip install")
                   and " -e " in line)
    assert lines[install + 1:install + 3] == ["setup: ... still installing, 1 s",
                                              "setup: ... still installing, 2 s"], lines
    lines = [line for line in lines if not line.startswith("setup: ... still ")]
    assert [line.split()[1] for line in lines if line.startswith("RAN")] == [
        "python3", "pip", "pip", "springsim"]
    for index, line in enumerate(lines):
        if line.startswith("RAN"):
            assert lines[index - 1].startswith("setup: "), lines
    assert "RAN springsim warmup --integrators rk4" in lines
