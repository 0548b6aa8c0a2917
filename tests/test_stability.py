"""The stability search against linear stability theory, and the `springsim stability` command.

Oracle: one free particle tied by springs to seven pinned ones (the corner of a 2 x 2 x 2 cube),
without gravity, moving a little. Its motion is linear, x'' = -(K x + D x') / m, so each
method's largest stable step is where the spectral radius of its one-step matrix reaches 1.
"""
import csv

import numpy as np
import pytest

from springsim import Simulation
from springsim.bodies.cube import Cube
from springsim.cli import main
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.stability import find_stability_limit

FREE_PARTICLE = 7   # corner (1, 1, 1); the other seven corners are pinned


def corner_scene() -> Scene:
    cube = Cube(particles_per_edge=2, edge_length=1.0, position=(0.0, 0.0, 0.0),
                velocity=(0.01, 0.004, -0.006), bend=SpringParameters(0.0, 0.0),
                pinned=tuple(range(7)))
    return Scene(name="corner", bodies=[cube], terrains=[], gravity=(0.0, 0.0, 0.0))


def linear_system():
    """A of the free particle's y' = A y with y = (x, v), from the model's springs at rest."""
    model = Simulation(corner_scene()).model
    arrays = model.arrays
    stiffness, damping = np.zeros((3, 3)), np.zeros((3, 3))
    for (a, b), group in zip(arrays.springs, arrays.spring_group):
        if FREE_PARTICLE in (a, b):
            d = model.initial_positions[a] - model.initial_positions[b]
            along = np.outer(d, d) / (d @ d)
            stiffness += arrays.group_ks[group] * along
            damping += arrays.group_kd[group] * along
    mass = model.mass[FREE_PARTICLE]
    return np.block([[np.zeros((3, 3)), np.eye(3)], [-stiffness / mass, -damping / mass]])


def one_step_matrix(method: str, h: float, a: np.ndarray) -> np.ndarray:
    z = h * a
    identity = np.eye(len(a))
    if method == "explicit_euler":
        return identity + z
    if method == "midpoint":
        return identity + z + z @ z / 2
    if method == "rk4":
        return identity + z + z @ z / 2 + z @ z @ z / 6 + z @ z @ z @ z / 24
    # symplectic Euler: v' = v + h a(x, v), then x' = x + h v'
    kick = identity.copy()
    kick[3:] += z[3:]
    drift = identity.copy()
    drift[:3, 3:] = h * np.eye(3)
    return drift @ kick


def linear_limit(method: str) -> float:
    """The step where the one-step matrix's spectral radius crosses 1, by bisection."""
    a = linear_system()

    def stable(h):
        return np.abs(np.linalg.eigvals(one_step_matrix(method, h, a))).max() <= 1.0

    low, high = 1e-5, 0.1
    assert stable(low) and not stable(high)
    while high / low > 1 + 1e-9:
        middle = np.sqrt(low * high)
        low, high = (middle, high) if stable(middle) else (low, middle)
    return low


@pytest.mark.parametrize("method", ["explicit_euler", "symplectic_euler", "midpoint", "rk4"])
def test_bisection_brackets_the_linear_stability_limit(method):
    limit = find_stability_limit(corner_scene, method, seconds=2.0, max_dt=0.1, tolerance=0.02)
    expected = linear_limit(method)
    assert limit.largest_stable <= expected * (1 + 1e-3)
    assert limit.smallest_unstable >= expected * (1 - 1e-3)
    assert limit.smallest_unstable / limit.largest_stable <= 1.02
    assert all(not trial.stable for trial in limit.trials if trial.dt > expected * 1.001)


def test_backward_euler_is_stable_at_every_step_tried():
    limit = find_stability_limit(corner_scene, "implicit_euler", seconds=2.0, max_dt=0.1)
    assert limit.capped and limit.largest_stable == 0.1 and len(limit.trials) == 1


SMALL_DROP = """
name = "small-drop"
[[bodies]]
type = "cube"
particles_per_edge = 3
edge_length = 1.0
position = [0.0, 1.0, 0.0]
[[terrains]]
type = "plane"
"""


def test_stability_command_writes_the_table_it_prints(capsys, tmp_path):
    scene = tmp_path / "small-drop.toml"
    scene.write_text(SMALL_DROP)
    table, chart = tmp_path / "limits.csv", tmp_path / "limits.png"
    code = main(["stability", str(scene), "--integrators", "explicit_euler", "implicit_euler",
                 "--seconds", "1", "--tolerance", "0.2", "--csv", str(table), "--png",
                 str(chart), "--quiet"])
    out = capsys.readouterr().out
    assert code == 0
    rows = {row["integrator"]: row for row in csv.DictReader(table.open())}
    assert set(rows) == {"explicit_euler", "implicit_euler"}
    explicit, implicit = rows["explicit_euler"], rows["implicit_euler"]
    assert float(explicit["largest_stable_dt_s"]) < float(explicit["smallest_unstable_dt_s"])
    assert float(explicit["smallest_unstable_dt_s"]) <= 1.2 * float(explicit["largest_stable_dt_s"])
    assert implicit["capped"] == "True"
    assert float(implicit["largest_stable_dt_s"]) >= 10 * float(explicit["largest_stable_dt_s"])
    for row in rows.values():
        assert row["scene"] == "small-drop"
        assert f"{float(row['largest_stable_dt_s']):.3g}" in out
    assert chart.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")


def test_stability_command_refuses_an_unknown_integrator(capsys, tmp_path):
    code = main(["stability", "jelly-plane", "--integrators", "backward_euler", "--csv",
                 str(tmp_path / "x.csv"), "--png", str(tmp_path / "x.png")])
    assert code == 2
    assert "backward_euler" in capsys.readouterr().err
    assert not (tmp_path / "x.csv").exists()


def test_searches_on_worker_processes_find_the_limits_found_here():
    """The runner (springsim.runner) changes where a search runs, not what it finds."""
    from dataclasses import replace

    from springsim.stability import Search, find_stability_limits

    methods = ["explicit_euler", "rk4", "implicit_euler"]
    here = [find_stability_limit(corner_scene, method, seconds=1.0, tolerance=0.1)
            for method in methods]
    there = find_stability_limits([Search(corner_scene(), method, seconds=1.0, tolerance=0.1)
                                   for method in methods], workers=2)
    assert [replace(limit, trials=()) for limit in there] == [replace(limit, trials=())
                                                              for limit in here]
    for mine, theirs in zip(here, there):
        assert ([(t.dt, t.stable, t.reason, t.simulated) for t in theirs.trials]
                == [(t.dt, t.stable, t.reason, t.simulated) for t in mine.trials])
