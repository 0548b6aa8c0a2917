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
exec .venv/bin/python -m pytest "$@"
