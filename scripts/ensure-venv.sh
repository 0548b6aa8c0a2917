# Sourced by run.sh and test.sh from the repository root: creates .venv and installs springsim
# with its test dependencies the first time, and again whenever pyproject.toml changes; the
# first time, it also compiles the default integrator's kernels (`springsim warmup`). Each
# stage says what it does before it starts: together they take minutes, and pip is quiet.
if [ ! -x .venv/bin/springsim ] || [ ! -x .venv/bin/pytest ] || [ pyproject.toml -nt .venv/.installed ]; then
  first_time=$([ -e .venv/.installed ] && echo no || echo yes)
  echo "setup: creating the virtual environment .venv (first run only)" >&2
  python3 -m venv .venv
  echo "setup: updating pip in .venv" >&2
  .venv/bin/pip install --quiet --upgrade pip
  echo "setup: installing springsim and its dependencies into .venv (a few minutes, first run only)" >&2
  .venv/bin/pip install --quiet -e ".[all,test]"
  touch .venv/.installed
  if [ "$first_time" = yes ]; then
    echo "setup: compiling the default integrator's kernels (springsim warmup; about 2 minutes, first run only)" >&2
    .venv/bin/springsim warmup --integrators rk4
  fi
fi
