#!/usr/bin/env bash
# The test suite: install the system packages the tests need where this machine allows it
# (scripts/system-packages.txt), set up the virtual environment (first time only), run pytest.
# Arguments go to pytest (e.g. ./test.sh -k friction).
set -euo pipefail
cd "$(dirname "$0")"
source scripts/ensure-system.sh
source scripts/ensure-venv.sh
# Blender as a module (~500 MB) for the tests that open exports in Blender; run.sh needs none of it
.venv/bin/pip show --quiet bpy >/dev/null 2>&1 || .venv/bin/pip install --quiet -e ".[blender]"
# every integrator's kernels compiled once before the tests (later: loaded from the cache in
# seconds), so that no test's output holds the first-compile notice
if ! .venv/bin/python -c "import sys; from springsim.warmup import is_warm; \
from springsim.integrators import integrator_names; \
sys.exit(0 if all(map(is_warm, integrator_names())) else 1)"; then
    .venv/bin/springsim warmup
fi
exec .venv/bin/python -m pytest "$@"
