#!/usr/bin/env bash
# The main job: set up a virtual environment (first time only), simulate the default scene
# (the jelly cube on the plane), print a summary, and write jelly-plane.npz and jelly-plane.mp4.
# The first time, what a run needs is installed before it and the rest of the README's after.
# Extra arguments go to `springsim run` (e.g. ./run.sh --integrator midpoint).
set -euo pipefail
cd "$(dirname "$0")"
VENV_REST=later source scripts/ensure-venv.sh
status=0
.venv/bin/springsim run jelly-plane --video jelly-plane.mp4 "$@" || status=$?
install_the_rest   # the first time: what the rest of the README needs, after the first result
exit "$status"
