"""Sweeps (springsim.sweep, `springsim sweep`) on local worker processes.

Oracles: free fall (a cube whose springs stay at rest falls as one body: the centre of mass at
y0 - g t^2 / 2 and kinetic energy M (g t)^2 / 2, exact for rk4 and midpoint), agreement of every
row with a run made directly by Simulation and record, equal tables whatever the number of
workers, and the rows a killed sweep leaves behind."""
import csv
import math
import os
import signal

import numpy as np
import pytest

import springsim
from springsim.cli import main
from springsim.errors import SceneError
from springsim.recording import record
from springsim.runner import Runner, WorkerLost
from springsim.scenefile import load_scene
from springsim.simulation import Simulation
from springsim.sweeps import build_grid, parse_variation
from springsim.sweeps.grid import SEED_AMPLITUDE, perturb
from springsim.sweeps.run import results
from test_stability import SMALL_DROP as STABILITY_DROP

# the small cube on the plane of the stability tests, 0.25 s long
SMALL_DROP = "duration = 0.25\n" + STABILITY_DROP

FREE_FALL = """
name = "free-fall"
duration = 0.5
[[bodies]]
type = "cube"
particles_per_edge = 3
edge_length = 1.0
position = [0.0, 10.0, 0.0]
"""


@pytest.fixture
def small_drop(tmp_path):
    path = tmp_path / "small-drop.toml"
    path.write_text(SMALL_DROP)
    return str(path)


def without_timing(rows):
    return [{key: value for key, value in row.items() if key != "wall_seconds"} for row in rows]


def csv_without_timing(path):
    with open(path, newline="") as file:
        return without_timing(list(csv.DictReader(file)))


# --- the grid ---------------------------------------------------------------------------------

def test_values_lists_and_ranges():
    assert parse_variation("bodies.0.structural.ks=1000,2000").values == (1000, 2000)
    assert parse_variation("integrator=rk4,midpoint").values == ("rk4", "midpoint")
    assert parse_variation("drag=0:1:5").values == (0.0, 0.25, 0.5, 0.75, 1.0)
    assert parse_variation("bodies.0.particles_per_edge=3:7:3").values == (3, 5, 7)
    assert parse_variation("gravity=[0, -9.8, 0],[0, -1.62, 0]").values == (
        [0, -9.8, 0], [0, -1.62, 0])


def test_every_combination_is_a_validated_scene_in_product_order(small_drop):
    specs = build_grid(small_drop, [parse_variation("bodies.0.structural.ks=1000,2000"),
                                    parse_variation("integrator=rk4,midpoint")], seeds=2)
    assert len(specs) == 8 and [spec.index for spec in specs] == list(range(8))
    assert [(dict(s.settings)["bodies.0.structural.ks"], s.scene.integrator, s.seed)
            for s in specs[:4]] == [(1000, "rk4", 0), (1000, "rk4", 1),
                                    (1000, "midpoint", 0), (1000, "midpoint", 1)]
    assert specs[-1].scene.bodies[0].structural.ks == 2000.0
    assert len({spec.run_id for spec in specs}) == 8


@pytest.mark.parametrize("vary, key", [
    (["bodies.0.structural.ks=1000,abc"], "bodies.0.structural.ks"),
    (["bodies.0.stiffness=1,2"], "bodies.0.stiffness"),
    (["dt=0.001,-1"], "dt"),
    (["drag=0:1:x"], "drag"),
    (["integrator=rk4,leapfrog"], "integrator"),
])
def test_a_bad_value_anywhere_in_the_grid_is_one_line_and_nothing_runs(capsys, tmp_path,
                                                                       small_drop, vary, key):
    out = tmp_path / "out"
    arguments = [f"--vary={text}" for text in vary]
    code = main(["sweep", small_drop, *arguments, "--out", str(out), "--workers", "1"])
    error = capsys.readouterr().err
    assert code == 2
    assert error.count("\n") == 1 and error.startswith(f"springsim sweep: {key}")
    assert not out.exists()


def test_a_bad_plot_or_output_folder_is_refused_up_front(capsys, tmp_path, small_drop):
    assert main(["sweep", small_drop, "--vary", "drag=0,1", "--out", str(tmp_path / "a"),
                 "--plot", "drag:happiness"]) == 2
    assert "--plot" in capsys.readouterr().err
    blocker = tmp_path / "file"
    blocker.write_text("")
    assert main(["sweep", small_drop, "--vary", "drag=0,1", "--out", str(blocker / "x")]) == 2
    assert "--out" in capsys.readouterr().err


def test_a_seed_nudges_free_particles_reproducibly_within_its_amplitude(small_drop):
    scene = load_scene(small_drop, ["bodies.0.pinned=[0, 5]"])
    plain = Simulation(scene)
    nudged = [Simulation(load_scene(small_drop, ["bodies.0.pinned=[0, 5]"])) for _ in range(3)]
    for simulation, seed in zip(nudged, (4, 4, 5)):
        perturb(simulation, seed)
    amplitude = SEED_AMPLITUDE * plain.model.arrays.rest_length.min()
    offsets = nudged[0].positions - plain.positions
    assert np.abs(offsets).max() <= amplitude and np.abs(offsets).max() > 0.5 * amplitude
    assert not offsets[[0, 5]].any()
    assert np.array_equal(nudged[0].positions, nudged[1].positions)
    assert not np.array_equal(nudged[0].positions, nudged[2].positions)


# --- the rows -----------------------------------------------------------------------------------

def test_free_fall_rows_are_the_analytic_fall(tmp_path):
    scene = tmp_path / "free-fall.toml"
    scene.write_text(FREE_FALL)
    table = springsim.sweep(str(scene), vary={"integrator": ["rk4", "midpoint"],
                                              "dt": [0.01, 0.005]}, workers=2)
    assert [row["run"] for row in table] == [0, 1, 2, 3]
    t, g, mass = 0.5, 9.8, 27.0
    for row in table:
        assert row["status"] == "ok" and row["message"] == ""
        assert row["simulated_s"] == pytest.approx(t, abs=1e-12)
        assert row["steps"] == round(t / row["dt"])
        assert row["centre_of_mass_y_m"] == pytest.approx(10.0 - g * t ** 2 / 2, abs=1e-9)
        assert row["kinetic_energy_j"] == pytest.approx(mass * (g * t) ** 2 / 2, rel=1e-9)
        assert row["largest_speed_m_s"] == pytest.approx(g * t, rel=1e-9)
        assert row["spring_energy_j"] == pytest.approx(0.0, abs=1e-12)
        assert row["deepest_penetration_m"] == 0.0


def test_a_row_agrees_with_the_same_run_made_directly(small_drop):
    table = springsim.sweep(small_drop, vary={"bodies.0.structural.ks": [1500]}, workers=1)
    simulation = Simulation(load_scene(small_drop, ["bodies.0.structural.ks=1500"]))
    expected = results(record(simulation, 0.25, 60.0))
    assert {key: table[0][key] for key in expected} == expected


def test_diverging_and_failing_runs_are_rows_and_the_rest_finish(small_drop):
    # dt 0.05 blows up explicit Euler; a cube placed at y = -3 starts inside the plane
    table = springsim.sweep(small_drop, vary={"dt": [0.001, 0.05],
                                              "bodies.0.position": [[0, 1, 0], [0, -3, 0]]},
                            overrides=["integrator=explicit_euler", "duration=1.0"], workers=2)
    statuses = [(row["dt"], row["bodies.0.position"][1], row["status"]) for row in table]
    assert statuses == [(0.001, 1, "ok"), (0.001, -3, "error"), (0.05, 1, "diverged"),
                        (0.05, -3, "error")]
    assert "inside terrains.0" in table[1]["message"] and "\n" not in table[1]["message"]
    assert table[2]["message"].startswith("simulation diverged at t = ")
    assert table[2]["centre_of_mass_y_m"] is None and table[2]["steps"] > 0


# --- workers, determinism, resume -------------------------------------------------------------

def test_one_and_two_workers_write_the_same_table(tmp_path, small_drop):
    vary = ["bodies.0.structural.ks=1000,3000", "integrator=rk4,symplectic_euler"]
    one = springsim.sweep(small_drop, vary, seeds=2, workers=1, out=str(tmp_path / "one"))
    two = springsim.sweep(small_drop, vary, seeds=2, workers=2, out=str(tmp_path / "two"))
    assert without_timing(one) == without_timing(two)
    assert (csv_without_timing(tmp_path / "one" / "results.csv")
            == csv_without_timing(tmp_path / "two" / "results.csv"))
    assert len({row["centre_of_mass_x_m"] for row in one}) > 4   # the seeds do move the cube


def test_a_killed_sweep_keeps_its_rows_and_resumes_where_it_stopped(tmp_path, small_drop):
    out = str(tmp_path / "out")
    vary = {"drag": "0:0.5:3", "integrator": ["rk4", "midpoint"]}
    complete = springsim.sweep(small_drop, vary, workers=1, out=str(tmp_path / "whole"),
                               save="npz")
    finished = []

    def stop_after_two(row):
        finished.append(row["run"])
        if len(finished) == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        springsim.sweep(small_drop, vary, workers=1, out=out, save="npz", on_row=stop_after_two)
    kept = list(csv.DictReader(open(os.path.join(out, "results.csv"))))
    assert sorted(int(row["run"]) for row in kept) == sorted(finished)
    with open(os.path.join(out, "results.csv"), "a") as file:
        file.write("5,deadbeef,0.5,mid")   # a line cut short when the sweep was killed
    ran = []
    resumed = springsim.sweep(small_drop, vary, workers=1, out=out, save="npz",
                              on_row=lambda row: ran.append(row["run"]))
    assert sorted(ran) == sorted(set(range(6)) - set(finished))
    assert without_timing(resumed) == without_timing(complete)
    assert (csv_without_timing(os.path.join(out, "results.csv"))
            == csv_without_timing(tmp_path / "whole" / "results.csv"))
    for row in resumed:
        with np.load(os.path.join(out, row["npz"])) as data:
            assert data["positions"].shape[0] == 16 and str(data["integrator"]) == row["integrator"]
    again = []
    springsim.sweep(small_drop, vary, workers=1, out=out, save="npz", on_row=again.append)
    assert again == []


def test_a_folder_of_another_sweep_is_refused(tmp_path, small_drop):
    out = str(tmp_path / "out")
    springsim.sweep(small_drop, {"drag": [0.0]}, workers=1, out=out)
    with pytest.raises(SceneError, match="--out"):
        springsim.sweep(small_drop, {"drag": [0.5]}, workers=1, out=out)
    with pytest.raises(SceneError, match="another sweep"):
        springsim.sweep(small_drop, {"dt": [0.001]}, workers=1, out=out)


def test_sweep_command_writes_the_table_and_the_chart(capsys, tmp_path, small_drop):
    out = tmp_path / "out"
    code = main(["sweep", small_drop, "--vary", "bodies.0.structural.ks=500:2000:3",
                 "--vary", "integrator=rk4,midpoint", "--duration", "0.1", "--workers", "2",
                 "--out", str(out), "--plot", "bodies.0.structural.ks:spring_energy_j"])
    assert code == 0
    assert "6 runs (6 ok)" in capsys.readouterr().out
    rows = list(csv.DictReader(open(out / "results.csv")))
    assert [row["bodies.0.structural.ks"] for row in rows] == ["500", "500", "1250", "1250",
                                                               "2000", "2000"]
    assert all(math.isclose(float(row["simulated_s"]), 0.1) for row in rows)
    chart = out / "spring_energy_j-vs-bodies.0.structural.ks.png"
    assert chart.read_bytes().startswith(b"\x89PNG\r\n\x1a\n")


# --- worker processes that die ------------------------------------------------------------------

def test_a_worker_that_dies_once_is_retried_and_one_that_always_dies_is_reported(tmp_path):
    marker = tmp_path / "died-once"

    def task(item):
        if item == "once" and not marker.exists():
            marker.write_text("")
            os.kill(os.getpid(), signal.SIGKILL)
        if item == "always":
            os.kill(os.getpid(), signal.SIGKILL)
        return item

    with Runner(workers=2) as runner:
        outcomes = {o.index: o for o in runner.map(task, ["a", "once", "always", "b"])}
    assert [outcomes[i].value for i in (0, 1, 3)] == ["a", "once", "b"]
    assert marker.exists()
    assert isinstance(outcomes[2].error, WorkerLost)


def test_the_moving_worlds_keys_vary_like_any_other():
    """Wind and motion keys take part in a grid: each run's scene has its own values."""
    key = "terrains.1.motion.keyframes.1"
    specs = build_grid("cloth-sweep", [parse_variation(f"{key}.time=0.5,1"),
                                       parse_variation(f"{key}.position.2=2,3")])
    seen = {(spec.scene.terrains[1].motion.keyframes[1].time,
             spec.scene.terrains[1].motion.keyframes[1].position[2]) for spec in specs}
    assert seen == {(0.5, 2.0), (0.5, 3.0), (1.0, 2.0), (1.0, 3.0)}
    flag = build_grid("flag", [parse_variation("wind.velocity.0=2,6"),
                               parse_variation("wind.gusts.strength=0,0.5")])
    assert {(spec.scene.wind.velocity[0], spec.scene.wind.gusts.strength) for spec in flag} == {
        (2.0, 0.0), (2.0, 0.5), (6.0, 0.0), (6.0, 0.5)}
