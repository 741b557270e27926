#!/usr/bin/env bash
# Cost per generalized-alpha step of a cantilever chain of 1..512 beam superelements
# ("scaling"): wraps `cargo bench -p mbs --bench step -- --bench` (crates/mbs/benches/step.rs),
# fits the cost per superelement-iteration and writes benchmarks/results/chain_scaling.md and the
# table into BENCHMARKS.md (benchmarks/scripts/write_section.py).
#
#   benchmarks/scripts/chain_scaling.sh            (from anywhere; CARGO_TARGET_DIR respected)
#
# The bench prints wall times: run it on an idle machine, or read the load printed beside
# the table (other builds on the 2 cores inflate every row alike).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
cd "$root"
results="$root/benchmarks/results"
mkdir -p "$results"
log=$(mktemp /tmp/chain_scaling.XXXXXX)
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
cargo bench -p mbs --bench step -- --bench | tee "$log"
load_after=$(cut -d' ' -f1-3 /proc/loadavg)
python3 - "$log" "$results/chain_scaling.md" "$load_before" "$load_after" <<'PY'
import re, sys, subprocess
log, out, before, after = sys.argv[1:5]
rows = []
chain = False
for line in open(log):
    if line.startswith("cantilever chain"):
        chain = True
        continue
    m = re.match(r"\s*N =\s*(\d+):\s*(\d+) unknowns,\s*([\d.]+) µs/step,\s*([\d.]+) iterations/step", line)
    if chain and m:
        n, dofs, us, its = int(m[1]), int(m[2]), float(m[3]), float(m[4])
        rows.append((n, dofs, us, its))
if not rows:
    sys.exit(f"no chain rows found in {log}")
# Least-squares fit us = a + b * N * iterations (cost per superelement-iteration b).
xs = [n * its for n, _, _, its in rows]
ys = [us for _, _, us, _ in rows]
mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
b = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)
a = my - b * mx
cpu = subprocess.run("grep -m1 'model name' /proc/cpuinfo | cut -d: -f2", shell=True, capture_output=True, text=True).stdout.strip()
lines = [
    "# Chain of beam superelements: cost per step",
    "",
    f"Machine: {cpu}, 2 cores; load average before {before}, after {after}.",
    "Command: `benchmarks/scripts/chain_scaling.sh` (wraps `cargo bench -p mbs --bench step -- --bench`).",
    "Cantilever of N identical 0.1 m steel beam superelements (static modes only) under gravity, h = 1 ms, generalized-alpha.",
    "",
    "| N | unknowns | µs/step | iterations/step | µs per superelement-iteration | fit a + b N it |",
    "|---:|---:|---:|---:|---:|---:|",
]
for (n, dofs, us, its), x in zip(rows, xs):
    lines.append(f"| {n} | {dofs} | {us:.1f} | {its:.2f} | {us / (n * its):.2f} | {a + b * x:.1f} |")
lines += ["", f"Least-squares fit over all N: {b:.2f} µs per superelement-iteration plus {a:.1f} µs per step:"
          " the cost grows linearly when the last column follows the third."]
text = "\n".join(lines) + "\n"
open(out, "w").write(text)
print(text)
PY
python3 "$root/benchmarks/scripts/write_section.py" chain_scaling "$results/chain_scaling.md" "$root/BENCHMARKS.md"
