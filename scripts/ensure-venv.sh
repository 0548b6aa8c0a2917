# Sourced by run.sh and test.sh from the repository root: creates .venv and installs springsim
# with its test dependencies the first time, and again whenever pyproject.toml changes.
if [ ! -x .venv/bin/springsim ] || [ ! -x .venv/bin/pytest ] || [ pyproject.toml -nt .venv/.installed ]; then
  python3 -m venv .venv
  .venv/bin/pip install --quiet --upgrade pip
  .venv/bin/pip install --quiet -e ".[all,test]"
  touch .venv/.installed
fi
