#!/usr/bin/env bash
# The test suite: set up the virtual environment (first time only), compile the kernels (first
# time only), run pytest. Tiers (tests/conftest.py): the default tier runs every cheap oracle;
# `--tier slow` the long scenarios, `--tier external` the tests in Blender, Chromium, Xvfb and
# Dask, `--tier all` every tier (what CI runs). Other arguments go to pytest
# (e.g. ./test.sh -k friction, ./test.sh --tier all -x).
set -euo pipefail
cd "$(dirname "$0")"
tiers=default
previous=""
for argument in "$@"; do
    case "$argument" in
        --tier=*) tiers=${argument#--tier=} ;;
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
# every integrator's kernels compiled once before the tests (later: loaded from the cache in
# seconds), so that no test's output holds the first-compile notice
if ! .venv/bin/python -c "import sys; from springsim.warmup import is_warm; \
from springsim.integrators import integrator_names; \
sys.exit(0 if all(map(is_warm, integrator_names())) else 1)"; then
    .venv/bin/springsim warmup
fi
exec .venv/bin/python -m pytest "$@"
