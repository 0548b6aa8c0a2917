#!/usr/bin/env bash
# The test suite: set up the virtual environment (first time only), compile the kernels (first
# time only), run pytest. Tiers (tests/conftest.py): the default tier runs every cheap oracle;
# `--tier slow` the long scenarios, `--tier external` the tests in Blender, Chromium, Xvfb and
# Dask, `--tier all` every tier (what CI runs). The tests run on every core (pytest-xdist, -n auto;
# `-n 0` runs them in one process). Other arguments go to pytest (e.g. ./test.sh -k friction,
# ./test.sh --tier all -x).
set -euo pipefail
cd "$(dirname "$0")"
tiers=default
workers=(-n auto --dist loadfile)   # every core, a test file to a worker (its fixtures built once)
previous=""
for argument in "$@"; do
    case "$argument" in
        --tier=*) tiers=${argument#--tier=} ;;
        -n|-n*|--numprocesses*|--dist*) workers=() ;;   # the caller chose
    esac
    [ "$previous" = "--tier" ] && tiers=$argument
    previous=$argument
done
source scripts/ensure-venv.sh
[[ "$tiers" == *all* ]] && tiers=$tiers,external
# the system packages the tiers need (scripts/system-packages.txt)
SYSTEM_TIERS=$tiers source scripts/ensure-system.sh
if [[ "$tiers" == *external* ]]; then
    # Blender as a module (~500 MB, once), for the external tier alone
    if ! .venv/bin/pip show --quiet bpy >/dev/null 2>&1; then
        setup_stage installing \
            "installing Blender as a Python module for the external tier (bpy, ~500 MB, once)" \
            .venv/bin/pip install --progress-bar off -e ".[blender]"
    fi
fi
# the kernels the tests call, compiled once before them (later: loaded from the cache in
# seconds), so that no test's output holds the first-compile notice: every integrator's serial
# step and gradient tape, and the threaded steps of explicit Euler (test_threads.py, default tier)
# and vertex block descent (test_vbd.py; the other threaded steps, minutes each, no test calls)
threaded="explicit_euler vbd"
if ! .venv/bin/python -c "import sys; from springsim.warmup import is_warm; \
from springsim.integrators import integrator_names; \
sys.exit(0 if all(is_warm(name, ['serial', 'plain', 'keeping']) for name in integrator_names()) \
         and all(is_warm(name, ['threaded']) for name in sys.argv[1:]) else 1)" $threaded; then
    setup_stage compiling "compiling the kernels the tests call (springsim warmup; first run only)" \
        .venv/bin/springsim warmup --variants serial plain keeping
    [ -z "$threaded" ] || setup_stage compiling \
        "compiling the threaded steps of $threaded for the thread tests (first run only)" \
        .venv/bin/springsim warmup --integrators $threaded --variants threaded
fi
exec .venv/bin/python -m pytest ${workers[@]+"${workers[@]}"} "$@"
