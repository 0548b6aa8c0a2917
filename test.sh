#!/usr/bin/env bash
# The test suite: install the system packages the tests need where this machine allows it
# (scripts/system-packages.txt), set up the virtual environment (first time only), run pytest.
# Arguments go to pytest (e.g. ./test.sh -k friction).
set -euo pipefail
cd "$(dirname "$0")"
source scripts/ensure-system.sh
source scripts/ensure-venv.sh
exec .venv/bin/python -m pytest "$@"
