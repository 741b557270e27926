#!/usr/bin/env bash
# Runs the Exudyn side of the slider-crank comparison: makes a virtual environment beside this
# file (or at $EXUDYN_VENV) with exudyn, numpy, scipy and pypardiso (MKL PARDISO, for
# benchmarks/compare_all.sh) from PyPI on first use, then runs slider_crank.py with the arguments
# given (see its docstring), or the script of this folder named first:
#   run.sh [slider_crank_beam.py] ARGS...
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
venv="${EXUDYN_VENV:-$here/.venv}"
if ! "$venv/bin/python" -c "import exudyn, numpy, scipy, pypardiso" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet "exudyn==1.13.6" "numpy==2.4.6" "scipy==1.17.1" "pypardiso==0.4.7"
fi
script=slider_crank.py
if [ $# -gt 0 ] && [ "${1%.py}" != "$1" ]; then
    script=$1
    shift
fi
exec "$venv/bin/python" "$here/$script" "$@"
