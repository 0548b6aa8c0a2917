"""How long a new user waits: the first `./run.sh` of a fresh clone, with an empty kernel cache.

Clones this checkout's HEAD into a temporary folder, runs its `./run.sh` there with a cache of
its own (XDG_CACHE_HOME), and prints when each setup stage began, when the run's summary
appeared (the first result: issue 56's bar is 90 s on this 2-core machine) and when it all
ended, with the load average before and after (another job on the cores slows the compile).
Nothing is installed outside the temporary folder; pip's own cache is used as it is.

    .venv/bin/python benchmarks/first_run.py [--rounds 1]
"""
import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIRST_RESULT = "final centre of mass"   # a summary line of `springsim run`


def first_run(folder: Path) -> dict:
    """{what: seconds since the start} of one first ./run.sh in a clone made in ``folder``."""
    clone, cache = folder / "clone", folder / "cache"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
    environment = {**os.environ, "XDG_CACHE_HOME": str(cache)}
    environment.pop("VIRTUAL_ENV", None)
    started, marks = time.monotonic(), {}
    process = subprocess.Popen(["bash", "run.sh"], cwd=clone, env=environment, text=True,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    for line in process.stdout:
        now = time.monotonic() - started
        if line.startswith("setup: ") and not line.startswith("setup: ..."):
            marks[line[len("setup: "):].split(" (")[0].strip()] = now
        elif FIRST_RESULT in line:
            marks["the run's summary (the first result)"] = now
    if process.wait() != 0:
        sys.exit(f"./run.sh failed in {clone}")
    marks["./run.sh ended"] = time.monotonic() - started
    return marks


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=1)
    args = parser.parse_args()
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, text=True,
                            capture_output=True).stdout.strip()
    print(f"first ./run.sh of a clone of {ROOT} at {commit}, {os.cpu_count()} cores")
    for round_number in range(1, args.rounds + 1):
        load_before = os.getloadavg()[0]
        with tempfile.TemporaryDirectory(prefix="springsim-first-run-") as folder:
            marks = first_run(Path(folder))
        print(f"round {round_number} (load average {load_before:.2f} before, "
              f"{os.getloadavg()[0]:.2f} after):")
        for what, seconds in marks.items():
            print(f"  {seconds:7.1f} s  {what}")


if __name__ == "__main__":
    main()
