#!/usr/bin/env bash
# The main job: set up a virtual environment (first time only), simulate the default scene
# (the jelly cube on the plane), print a summary, and write jelly-plane.npz and jelly-plane.mp4.
# Extra arguments go to `springsim run` (e.g. ./run.sh --integrator midpoint).
set -euo pipefail
cd "$(dirname "$0")"
source scripts/ensure-venv.sh
exec .venv/bin/springsim run jelly-plane --video jelly-plane.mp4 "$@"
