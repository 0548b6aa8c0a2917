"""Sweeps on a real Dask cluster: a `dask scheduler` and two `dask worker` processes on
127.0.0.1, started here and always killed at the end. The cluster's table must be the local one,
bit for bit apart from wall_seconds, and a worker killed mid-sweep must cost no row."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import springsim
from springsim.cli import main

from test_sweep import SMALL_DROP, csv_without_timing, without_timing

pytestmark = pytest.mark.external   # the external tier (conftest.py): Dask

DASK = str(Path(sys.executable).with_name("dask"))
START_TIMEOUT = 60.0   # s for the scheduler and workers to come up


def start(arguments, log):
    return subprocess.Popen([DASK, *arguments], stdout=log, stderr=subprocess.STDOUT,
                            start_new_session=True)


def stop(process):
    """Kill the process and every process it started (a worker's nanny and its worker)."""
    if process.poll() is None:
        os.killpg(process.pid, signal.SIGKILL)
    process.wait(timeout=30)


@pytest.fixture
def cluster(tmp_path):
    """The scheduler's address and the two worker processes (nanny and worker each)."""
    from distributed import Client

    scheduler_file = tmp_path / "scheduler.json"
    log = open(tmp_path / "cluster.log", "w")
    processes = [start(["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                        "--scheduler-file", str(scheduler_file)], log)]
    try:
        deadline = time.monotonic() + START_TIMEOUT
        while not scheduler_file.exists() or not scheduler_file.stat().st_size:
            assert time.monotonic() < deadline and processes[0].poll() is None, \
                (tmp_path / "cluster.log").read_text()
            time.sleep(0.1)
        address = json.loads(scheduler_file.read_text())["address"]
        workers = [start(["worker", address, "--host", "127.0.0.1", "--nworkers", "1",
                          "--nthreads", "1", "--no-dashboard", "--death-timeout", "30"], log)
                   for _ in range(2)]
        processes += workers
        with Client(address, timeout=START_TIMEOUT) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT)
        yield address, workers
    finally:
        for process in reversed(processes):
            stop(process)
        log.close()


@pytest.fixture
def small_drop(tmp_path):
    path = tmp_path / "small-drop.toml"
    path.write_text(SMALL_DROP)
    return str(path)


def test_the_cluster_writes_the_local_table(cluster, tmp_path, small_drop, capsys):
    address, _ = cluster
    arguments = ["sweep", small_drop, "--vary", "bodies.0.structural.ks=1000,3000",
                 "--vary", "integrator=rk4,implicit_euler", "--seeds", "2", "--save", "npz"]
    assert main(arguments + ["--workers", "2", "--out", str(tmp_path / "local")]) == 0
    assert main(arguments + ["--dask", address, "--out", str(tmp_path / "dask")]) == 0
    capsys.readouterr()
    local = csv_without_timing(tmp_path / "local" / "results.csv")
    assert len(local) == 8 and all(row["status"] == "ok" for row in local)
    assert csv_without_timing(tmp_path / "dask" / "results.csv") == local
    for row in local:   # the recordings come back to this machine from the workers
        assert (tmp_path / "dask" / row["npz"]).stat().st_size > 0


def test_the_address_may_come_from_the_environment(cluster, small_drop, monkeypatch):
    address, _ = cluster
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", address)
    table = springsim.sweep(small_drop, {"drag": [0.0, 0.5]}, duration=0.05)
    assert [row["status"] for row in table] == ["ok", "ok"]


def test_a_worker_killed_mid_sweep_costs_no_row(cluster, small_drop):
    address, workers = cluster
    vary = {"bodies.0.structural.ks": [1000, 1500, 2000, 2500, 3000, 3500]}
    settings = ["bodies.0.particles_per_edge=5", "dt=0.0002", "duration=1.0"]
    local = springsim.sweep(small_drop, vary, overrides=settings, workers=2)
    arrived = []

    def kill_a_worker_at_the_first_row(row):
        arrived.append(row["run"])
        if len(arrived) == 1:
            stop(workers[0])

    remote = springsim.sweep(small_drop, vary, overrides=settings, dask=address,
                             on_row=kill_a_worker_at_the_first_row)
    assert workers[0].poll() is not None and len(arrived) == 6
    assert without_timing(remote) == without_timing(local)
    assert all(row["status"] == "ok" for row in remote)


def test_no_scheduler_at_the_address_is_one_line(capsys, small_drop, monkeypatch, tmp_path):
    monkeypatch.setattr("springsim.runner.CONNECT_TIMEOUT", "1s")
    code = main(["sweep", small_drop, "--set", "dt=0.001", "--vary", "drag=0,1", "--dask",
                 "tcp://127.0.0.1:9", "--out", str(tmp_path / "out")])
    error = capsys.readouterr().err
    assert code == 2 and error.count("\n") == 1
    assert error.startswith("springsim sweep: --dask = 'tcp://127.0.0.1:9': no Dask scheduler")
