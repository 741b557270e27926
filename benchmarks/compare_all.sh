#!/usr/bin/env bash
# All the side-by-side comparisons of flexmbs against the fastest alternatives, in one go, on
# this machine, the programs alternating run by run (medians of REPEATS runs):
#
#   benchmarks/compare_all.sh [--quick] [REPEATS]       (default 3; --quick: 1; run from anywhere)
#
# 1. reduction of the 50k- and 200k-dof hex8 blocks (--quick: 10k): flexmbs's whole
#    Craig-Bampton reduction against scipy's eigsh with MKL PARDISO (pypardiso) as the
#    shift-invert solver, PARDISO's factorisation alone, the eigenvalues compared;
# 2. the C2 slider-crank rod over 4 revolutions: flexmbs's beam superelements against Exudyn's
#    ANCF cable (ObjectANCFCable2D) and geometrically exact beam (ObjectBeamGeometricallyExact),
#    each at the largest time step that brings the rod's extrema within 0.05 % of a converged
#    reference that is not our model (Exudyn's ANCF cable refined in elements and step);
# 3. the solid connecting rod against Exudyn's ObjectFFRFreducedOrder (run_comparison.sh).
#
# Parts 1 and 2 are benchmarks/scripts/compare_all.py (each writes
# benchmarks/results/compare_all_<part>.md and its `compare_all_<part>` block of BENCHMARKS.md);
# part 3 writes the `slider_crank` block. About
# 30 minutes with 3 repetitions on an idle 2-core machine; --quick about 5.
#
# Environment: CARGO_TARGET_DIR (default target), EXUDYN_VENV (default benchmarks/exudyn/.venv:
# exudyn, numpy, scipy, pypardiso from PyPI, made on first use by benchmarks/exudyn/run.sh),
# COMPARE_ONLY (reduction,rod,solid: the parts to run).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
quick=
repeats=
for arg in "$@"; do
    case "$arg" in
        --quick) quick=--quick ;;
        [0-9]*) repeats=$arg ;;
        *) echo "usage: benchmarks/compare_all.sh [--quick] [REPEATS]" >&2; exit 2 ;;
    esac
done
repeats=${repeats:-$([ -n "$quick" ] && echo 1 || echo 3)}
only=${COMPARE_ONLY:-reduction,rod,solid}
target=${CARGO_TARGET_DIR:-target}
venv=${EXUDYN_VENV:-$root/benchmarks/exudyn/.venv}

nice cargo build --release -p flexmbs-benchmarks --bin slider_crank --bin export_rod
bench=$(nice cargo bench -p reduction --bench craig_bampton --no-run --message-format=json |
    python3 -c 'import json, sys
for line in sys.stdin:
    m = json.loads(line)
    if m.get("reason") == "compiler-artifact" and m["target"]["name"] == "craig_bampton" and m.get("executable"):
        print(m["executable"])')
benchmarks/exudyn/run.sh --help > /dev/null # creates the virtual environment on first use
work=$(mktemp -d /tmp/compare_all.XXXXXX)
"$target/release/export_rod" --out "$work/rod_mesh"

parts=$(tr ',' '\n' <<< "$only" | { grep -v '^solid$' || true; } | paste -sd, -)
if [ -n "$parts" ]; then
    "$venv/bin/python" benchmarks/scripts/compare_all.py --root "$root" --bin "$(cd "$target/release" && pwd)" \
        --bench "$bench" --work "$work" --repeats "$repeats" $quick --only "$parts" \
        --command "${COMPARE_ONLY:+COMPARE_ONLY=$only }benchmarks/compare_all.sh${quick:+ --quick} $repeats"
fi
if grep -qx solid <<< "${only//,/$'\n'}"; then
    benchmarks/run_comparison.sh "$repeats"
fi
echo "work files in $work"
