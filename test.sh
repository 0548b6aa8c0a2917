#!/usr/bin/env bash
# The test suite: set up the virtual environment (first time only) and run pytest.
# Arguments go to pytest (e.g. ./test.sh -k friction).
set -euo pipefail
cd "$(dirname "$0")"
if [ ! -x .venv/bin/pytest ] || [ pyproject.toml -nt .venv/.installed ]; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --upgrade pip
  .venv/bin/pip install --quiet -e ".[test]"
  touch .venv/.installed
fi
exec .venv/bin/python -m pytest "$@"
