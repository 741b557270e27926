#!/usr/bin/env bash
# Runs the Exudyn side of the slider-crank comparison: makes a virtual environment beside this
# file (or at $EXUDYN_VENV) with exudyn, numpy and scipy from PyPI on first use, then runs
# slider_crank.py with the arguments given (see its docstring).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
venv="${EXUDYN_VENV:-$here/.venv}"
if ! "$venv/bin/python" -c "import exudyn, numpy, scipy" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet "exudyn==1.13.6" numpy scipy
fi
exec "$venv/bin/python" "$here/slider_crank.py" "$@"
