#!/usr/bin/env bash
# Fill-reducing orderings of K_ii against METIS: fill and flops of the Cholesky factor of the
# hex8 blocks' K_ii (crates/reduction/benches/common) with AMD, our nested dissection
# (fe_model::ordering) and METIS's METIS_NodeND, all analysed by the same faer symbolic
# Cholesky (relaxed supernodes). Symbolic only: a few seconds per size.
#
#   benchmarks/scripts/ordering_vs_metis.sh [SIZES]     (default 50k,200k; run from anywhere)
#
# 1. creates a virtual environment with numpy and pymetis from PyPI on first use
#    ($METIS_VENV, default benchmarks/scripts/.venv-metis);
# 2. runs `cargo bench -p reduction --bench ordering` with REDUCTION_ORDERING_EXPORT: per size,
#    our orderings' figures, and the adjacency of K_ii written to a temporary directory;
# 3. orders each adjacency with METIS (benchmarks/scripts/metis_ordering.py);
# 4. runs the bench again with REDUCTION_ORDERING_IMPORT, which adds the METIS ordering's line.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
sizes=${1:-50k,200k}
venv=${METIS_VENV:-$root/benchmarks/scripts/.venv-metis}
if ! "$venv/bin/python" -c "import numpy, pymetis" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet "numpy==2.4.6" "pymetis==2025.2.2"
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
REDUCTION_CB_SIZES=$sizes REDUCTION_ORDERING_EXPORT=$work \
    cargo bench -p reduction --bench ordering -- --bench > /dev/null
"$venv/bin/python" benchmarks/scripts/metis_ordering.py "$work" "$sizes"
REDUCTION_CB_SIZES=$sizes REDUCTION_ORDERING_IMPORT=$work \
    cargo bench -p reduction --bench ordering -- --bench
