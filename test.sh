#!/usr/bin/env bash
# The test suite: set up the virtual environment (first time only) and run pytest.
# Arguments go to pytest (e.g. ./test.sh -k friction).
set -euo pipefail
cd "$(dirname "$0")"
source scripts/ensure-venv.sh
exec .venv/bin/python -m pytest "$@"
