"""Defaults that work together (issue 28, item 6): a scene file that gives no dt gets the step its
stiffest particle allows (step_size.py), and a divergence suggests a step that works.

Oracles: every body kind alone (a cloth pinned along an edge and a mesh cloth among them), with
every key at its default, runs 5 s without diverging under
the default integrator at the chosen step and under implicit_euler at 1/60 s; the reference cloth
pinned along an edge, which diverges at the old default 1 ms, runs at the step its divergence
message suggests.
"""
import re
from pathlib import Path

import pytest

from springsim import Simulation, SimulationDiverged
from springsim.scenefile import AutomaticStep, load_scene

DATA = Path(__file__).with_name("data")
KINDS = {   # name: the body's type and the keys it gives (every other key at its default)
    "cube": ("cube", ""), "cloth": ("cloth", ""), "balls": ("balls", ""),
    "mesh": ("mesh", f'file = "{DATA / "animal.obj"}"\n'),
    "cloth pinned along an edge": ("cloth", 'pinned = "edge"\n'),
    "mesh cloth": ("cloth", f'file = "{DATA / "uv_sphere_unwelded.obj"}"\n'),
}


def scene_file(tmp_path, kind: str, extra: str = "") -> Path:
    path = tmp_path / f"{kind.replace(' ', '-')}.toml"
    body_type, keys = KINDS[kind]
    path.write_text(f'{extra}[[bodies]]\ntype = "{body_type}"\n{keys}')
    return path


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_every_body_kind_alone_with_its_defaults_runs(tmp_path, kind):
    with pytest.warns(AutomaticStep, match="the scene gives no dt"):
        scene = load_scene(str(scene_file(tmp_path, kind)))
    assert scene.integrator == "rk4"
    Simulation(scene).advance(5.0)                      # raises SimulationDiverged if it blows up
    implicit = load_scene(str(scene_file(tmp_path, kind)),
                          ["integrator=implicit_euler", "dt=0.016666666666666666"])
    Simulation(implicit).advance(5.0)


def test_a_scene_file_that_gives_dt_keeps_it(tmp_path):
    scene = load_scene(str(scene_file(tmp_path, "cube", "dt = 0.0005\n")))
    assert scene.dt == 0.0005


def test_the_step_a_divergence_suggests_works(tmp_path):
    path = tmp_path / "hang.toml"
    path.write_text('dt = 0.001\n[[bodies]]\ntype = "cloth"\npinned = "edge"\n')
    with pytest.raises(SimulationDiverged) as diverged:
        Simulation(load_scene(str(path))).advance(5.0)
    suggested = float(re.search(r"for example ([0-9.e+-]+)\)", str(diverged.value)).group(1))
    assert suggested < 0.0005                            # the old advice (dt / 2) diverged too
    Simulation(load_scene(str(path), [f"dt={suggested!r}"])).advance(5.0)
