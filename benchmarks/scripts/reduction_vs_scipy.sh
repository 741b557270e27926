#!/usr/bin/env bash
# Reduction against scipy: our whole Craig-Bampton reduction of generated hex8 blocks
# (RBE2 interfaces on both end faces, 20 fixed-interface modes) against scipy's
# eigsh(K_ii, M=M_ii, sigma=0, k=20) with shift-invert (SuperLU) on the same fixed-interface
# matrices -- the eigenproblem inside the reduction, so scipy does strictly less work.
#
#   benchmarks/scripts/reduction_vs_scipy.sh [SIZES]     (default 10k,50k; run from anywhere)
#
# SIZES are those of crates/reduction/benches/common (3k 10k 25k 50k 100k 200k 600k), comma
# separated. scipy's time grows fast: about 1 min at 50k, 70 min and 20.5 GB at 200k on this
# 2-core machine; SCIPY_SIZES (default: SIZES without 600k, which does not fit in 24 GB for
# scipy) chooses the sizes scipy runs.
#
# 1. creates a virtual environment with numpy and scipy from PyPI on first use
#    ($SCIPY_VENV, default benchmarks/scripts/.venv-scipy);
# 2. runs `cargo bench -p reduction --bench craig_bampton` in release with REDUCTION_CB_MTX_DIR
#    set: per size, one process reduces the block (wall, CPU, peak RSS), then writes K_ii and
#    M_ii in Matrix Market and solves them with our eigensolver alone (time, worst relative
#    residual, eigenvalues);
# 3. runs crates/reduction/benches/scipy_eigsh.py on the same files (time, CPU, peak RSS of the
#    process, worst relative residual, largest relative difference to our eigenvalues);
# 4. prints the table and writes it, with the machine and the commands, to
#    benchmarks/results/reduction_scipy.md and into BENCHMARKS.md (benchmarks/scripts/write_section.py).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
sizes=${1:-10k,50k}
scipy_sizes=${SCIPY_SIZES:-$(tr ',' '\n' <<< "$sizes" | grep -vx 600k | paste -sd, -)}
venv=${SCIPY_VENV:-$root/benchmarks/scripts/.venv-scipy}
results="$root/benchmarks/results"
mkdir -p "$results"
if ! "$venv/bin/python" -c "import numpy, scipy" 2>/dev/null; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet "numpy==2.4.6" "scipy==1.17.1"
fi
work=$(mktemp -d /tmp/reduction_vs_scipy.XXXXXX)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
REDUCTION_CB_SIZES=$sizes REDUCTION_CB_MTX_DIR=$work cargo bench -p reduction --bench craig_bampton -- --bench |
    tee "$work/ours.log"
for size in ${scipy_sizes//,/ }; do
    "$venv/bin/python" crates/reduction/benches/scipy_eigsh.py "$work" "$size" | tee "$work/scipy_$size.log"
done
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

"$venv/bin/python" - "$work" "$results/reduction_scipy.md" "$sizes" "$load_before" "$load_after" <<'PY'
import glob, platform, re, subprocess, sys
import scipy, numpy
work, out, sizes, before, after = sys.argv[1:6]

def results(path):
    rows = {}
    for line in open(path):
        if line.startswith("RESULT "):
            kv = dict(f.split("=", 1) for f in line.split()[1:])
            rows[kv["size"]] = kv
    return rows

ours = results(f"{work}/ours.log")
theirs = {}
for p in glob.glob(f"{work}/scipy_*.log"):
    theirs.update(results(p))
sh = lambda c: subprocess.run(c, shell=True, capture_output=True, text=True).stdout.strip()
cpu_model = sh("grep -m1 'model name' /proc/cpuinfo | cut -d: -f2")
memory = sh("free -g | awk '/Mem/{print $2}'")
lines = [
    "# Craig-Bampton reduction against scipy's eigsh",
    "",
    f"Machine: {cpu_model}, {sh('nproc')} cores, "
    f"{memory} GB, {platform.system()} {platform.release()}; {sh('rustc --version')}; "
    f"Python {platform.python_version()}, scipy {scipy.__version__}, numpy {numpy.__version__}. "
    f"Load average before/after: {before} / {after}.",
    "",
    "Problem: hex8 steel block (crates/reduction/benches/common), RBE2 interfaces on both end faces, 20 fixed-interface modes.",
    "Ours: the whole `reduction::reduce` (assembly, factorisation of K_ii, 12 constraint modes, Lanczos, projections,",
    "inertia invariants), one process per size; 'eigen only': `reduction::lowest_modes` alone on the exported K_ii, M_ii
(AMD ordering, as the matrices carry no node positions for nested dissection: slower than inside the reduction).",
    "scipy: `eigsh(K_ii, M=M_ii, sigma=0, k=20)` (ARPACK shift-invert, SuperLU) on the same K_ii, M_ii (Matrix Market),",
    "which is only the eigenproblem inside the reduction. Peak memory: peak RSS of each process (ours: up to the end of",
    "the reduction; scipy: including the matrices read). Residual: max_j |K phi - lambda M phi| / |K phi| (scaled as",
    "`reduction::eigen::relative_residual`). Difference: largest relative difference between the two sets of 20 eigenvalues.",
    "",
    "| block | dofs | ours: whole reduction [s] | peak RSS [MiB] | eigen only [s] | worst residual | scipy eigsh [s] | scipy peak RSS [MiB] | scipy worst residual | eigenvalue difference | time ratio (scipy / our whole reduction) | memory ratio |",
    "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
]
for size in sizes.split(","):
    o = ours.get(size)
    if o is None:
        lines.append(f"| {size} | (our run failed: see the log) |||||||||||")
        continue
    t = theirs.get(size)
    ratio = mem = "-"
    sc = ["-"] * 4
    if t is not None:
        ratio = f"{float(t['eigsh_s']) / float(o['reduce_s']):.1f}x"
        mem = f"{float(t['peak_mib']) / float(o['peak_mib']):.1f}x"
        sc = [f"{float(t['eigsh_s']):.2f}", t["peak_mib"], f"{float(t['worst_residual']):.1e}", f"{float(t['difference']):.1e}"]
    lines.append(
        f"| {size} | {o['dofs']} | {float(o['reduce_s']):.2f} | {o['peak_mib']} | {float(o['eigen_s']):.2f} | "
        f"{float(o['worst_residual']):.1e} | {' | '.join(sc)} | {ratio} | {mem} |"
    )
lines += [
    "",
    f"Command: `benchmarks/scripts/reduction_vs_scipy.sh {sizes}`. Each row's full output (stage times, factor size,",
    "operator applications, frequencies) is printed by the script.",
]
text = "\n".join(lines) + "\n"
open(out, "w").write(text)
print(text)
PY
python3 "$root/benchmarks/scripts/write_section.py" reduction_scipy "$results/reduction_scipy.md" "$root/BENCHMARKS.md"
echo "work files in $work"
