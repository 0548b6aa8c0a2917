# Sourced by run.sh and test.sh from the repository root: creates .venv and installs springsim
# with its test dependencies the first time, and again whenever pyproject.toml changes; the
# first time, it also compiles the kernels a run of the default scene takes (`springsim warmup
# --scene jelly-plane`: only those, so that ./run.sh shows its first result soon; test.sh
# compiles every other variant). Each stage says what it does before it starts, and while it
# runs no more than SETUP_TICK seconds (4; the bar is a line within 5 s) pass without a line:
# pip's own lines pass through, and a quiet stretch (a big download, installing the packages,
# compiling) gets "setup: ... still VERB, N s".
SETUP_TICK=${SETUP_TICK:-4}

# setup_stage VERB "what it does" command...: say what it does, run the command with its output
# (stdout and stderr) on stderr line by line, and "setup: ... still VERB, N s" after every
# SETUP_TICK quiet seconds.
setup_stage() {
  local verb=$1 what=$2 started=$SECONDS status=0
  shift 2
  echo "setup: $what" >&2
  "$@" 2>&1 | setup_ticker "$verb" "$started" || status=$?
  return "$status"
}

setup_ticker() {
  local line="" code=0
  while true; do
    code=0
    IFS= read -r -t "$SETUP_TICK" line || code=$?
    if [ "$code" -eq 0 ]; then
      printf '%s\n' "$line" >&2
    elif [ "$code" -gt 128 ]; then   # read timed out: nothing for SETUP_TICK seconds
      [ -n "$line" ] && printf '%s\n' "$line" >&2   # a part line read before the timeout
      echo "setup: ... still $1, $((SECONDS - $2)) s" >&2
    else                             # end of the output
      [ -n "$line" ] && printf '%s\n' "$line" >&2
      return 0
    fi
  done
}

# springsim with what a run needs, then (install_the_rest) the optional parts (meshes, export,
# the browser, sweeps, docs) and the test tools: run.sh sets VENV_REST=later and installs the
# rest after its first run, so that the first result comes sooner; test.sh installs all now.
if [ ! -x .venv/bin/springsim ] || [ pyproject.toml -nt .venv/.installed-core ]; then
  first_time=$([ -e .venv/.installed-core ] && echo no || echo yes)
  setup_stage creating "creating the virtual environment .venv (first run only)" \
    python3 -m venv .venv
  setup_stage updating "updating pip in .venv" \
    .venv/bin/pip install --progress-bar off --upgrade pip
  setup_stage installing "installing springsim and what a run needs into .venv (about 30 s, first run only)" \
    .venv/bin/pip install --progress-bar off -e .
  touch .venv/.installed-core
  if [ "$first_time" = yes ]; then
    setup_stage compiling "compiling the kernels of the default scene on every core (springsim warmup --scene jelly-plane; about 40 s on two cores, first run only)" \
      .venv/bin/springsim warmup --scene jelly-plane
  fi
fi

install_the_rest() {
  if [ ! -x .venv/bin/pytest ] || [ pyproject.toml -nt .venv/.installed ]; then
    setup_stage installing "installing the optional parts (meshes, export, web, sweeps, docs) and the test tools into .venv (about a minute, first run only)" \
      .venv/bin/pip install --progress-bar off -e ".[all,test]"
    touch .venv/.installed
  fi
}

[ "${VENV_REST:-now}" = later ] || install_the_rest
