#!/usr/bin/env bash
# The slider-crank comparison (validation problem C2): flexmbs against Exudyn on the same
# rod mesh and FE matrices, same number of modes, time step and end time.
#
#   benchmarks/run_comparison.sh [REPEATS]        (default 5; run from anywhere)
#
# 1. builds the benchmark binaries in release;
# 2. exports the hex20 rod mesh and its K, M (export_rod) for Exudyn;
# 3. computes a converged reference that is not our model: Exudyn's planar ANCF cable with the
#    solid rod's square section (EA, EI, mass per length), refined in elements and time step
#    until the extrema of the midpoint deflection change by less than 1e-5 relative
#    (benchmarks/scripts/ancf_reference.py); and, as a cross-check, our own converged beam model
#    of the same rod: 32 Timoshenko-beam superelements at h = T/800 (solid superelements in
#    series are stiffened by the rigid RBE2 faces at every junction, so not the solid chain);
# 4. runs each configuration REPEATS times, alternating flexmbs and Exudyn (the machine is
#    shared: the medians and the load averages are reported);
# 5. prints the table and writes it, with the machine and the commands, to
#    benchmarks/results/slider_crank.md and into BENCHMARKS.md (benchmarks/scripts/write_section.py).
#
# Exudyn runs its fast module (EXUDYN_MODULE=fast: exudynCPPfast of the same wheel, no range
# checks, AVX2; the same results), and each program's Newton variant is named in the row:
# Exudyn's time integration defaults to modified Newton, flexmbs's to full Newton.
#
# Environment: CARGO_TARGET_DIR (default target), EXUDYN_VENV (default benchmarks/exudyn/.venv),
# SLIDER_T_END (default 2 crank periods, 800 steps: the one-superelement model with the frame at
# interface A, flexmbs as Exudyn, stops converging at t = 0.097 s, 2.3 periods), SLIDER_MODES (default 4).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
repeats=${1:-5}
target=${CARGO_TARGET_DIR:-target}
bin="$target/release"
work=$(mktemp -d /tmp/slider_crank.XXXXXX)
results="$root/benchmarks/results"
mkdir -p "$results"
period=$(python3 -c "import math; print(2 * math.pi / 150)")
h=$(python3 -c "print($period / 400)")
t_end=${SLIDER_T_END:-$(python3 -c "print(2 * $period)")}
modes=${SLIDER_MODES:-4}

cargo build --release -p flexmbs-benchmarks --bin slider_crank --bin export_rod
"$bin/export_rod" --out "$work/rod"
benchmarks/exudyn/run.sh --help > /dev/null # creates the virtual environment on first use

venv=${EXUDYN_VENV:-$root/benchmarks/exudyn/.venv}
"$venv/bin/python" benchmarks/scripts/ancf_reference.py --params "$work/rod/params.txt" --section square --t-end "$t_end" \
    --work "$work/reference" --csv "$work/reference.csv" --markdown "$work/reference.md"
ref_cmd=("$bin/slider_crank" --rod beam --segments 32 --beam-elements 4 --modes 2 --h "$(python3 -c "print($h / 2)")" --t-end "$t_end" --csv "$work/ours_converged.csv" --reference "$work/reference.csv")
echo "our converged beam model: ${ref_cmd[*]}"
"${ref_cmd[@]}" | tee "$work/ours_converged.log"

# name | like-for-like Exudyn row (same modes and Newton variant) | command (the reference CSV is
# appended as --reference). Exudyn rows name themselves in the second field.
configs=(
    "flexmbs, 1 superelement, frame at the centre of mass|Exudyn, $modes modes, full Newton|$bin/slider_crank --segments 1 --modes $modes --h $h --t-end $t_end"
    "flexmbs, 1 superelement, frame at interface A (as Exudyn)|Exudyn, $modes modes, full Newton|$bin/slider_crank --segments 1 --modes $modes --frame node --h $h --t-end $t_end"
    "flexmbs, 2 superelements|Exudyn, $modes modes, full Newton|$bin/slider_crank --segments 2 --modes $modes --h $h --t-end $t_end"
    "flexmbs, 4 superelements, 2 modes|Exudyn, 2 modes, full Newton|$bin/slider_crank --segments 4 --modes 2 --h $h --t-end $t_end"
    "flexmbs, beam rod, 8 superelements, 2 modes|Exudyn, 2 modes, full Newton|$bin/slider_crank --rod beam --segments 8 --modes 2 --h $h --t-end $t_end"
    "flexmbs, 1 superelement, geometric stiffening|Exudyn, $modes modes, full Newton|$bin/slider_crank --segments 1 --modes $modes --geometric-stiffening --h $h --t-end $t_end"
    "flexmbs, 1 superelement, geometric stiffening, modified Newton|Exudyn, $modes modes, modified Newton|$bin/slider_crank --segments 1 --modes $modes --geometric-stiffening --newton modified --h $h --t-end $t_end"
    "flexmbs, 1 superelement, 2 modes, geometric stiffening|Exudyn, 2 modes, full Newton|$bin/slider_crank --segments 1 --modes 2 --geometric-stiffening --h $h --t-end $t_end"
    "flexmbs, 1 superelement, 2 modes, geometric stiffening, modified Newton|Exudyn, 2 modes, modified Newton|$bin/slider_crank --segments 1 --modes 2 --geometric-stiffening --newton modified --h $h --t-end $t_end"
    "flexmbs, beam rod, 1 superelement, 2 modes, geometric stiffening|Exudyn, 2 modes, full Newton|$bin/slider_crank --rod beam --segments 1 --modes 2 --geometric-stiffening --h $h --t-end $t_end"
    "Exudyn ObjectFFRFreducedOrder, $modes modes, modified Newton (default)|Exudyn, $modes modes, modified Newton|env EXUDYN_MODULE=fast benchmarks/exudyn/run.sh --mesh $work/rod --modes $modes --h $h --t-end $t_end --modified-newton"
    "Exudyn ObjectFFRFreducedOrder, $modes modes, full Newton|Exudyn, $modes modes, full Newton|env EXUDYN_MODULE=fast benchmarks/exudyn/run.sh --mesh $work/rod --modes $modes --h $h --t-end $t_end"
    "Exudyn ObjectFFRFreducedOrder, 2 modes, modified Newton (default)|Exudyn, 2 modes, modified Newton|env EXUDYN_MODULE=fast benchmarks/exudyn/run.sh --mesh $work/rod --modes 2 --h $h --t-end $t_end --modified-newton"
    "Exudyn ObjectFFRFreducedOrder, 2 modes, full Newton|Exudyn, 2 modes, full Newton|env EXUDYN_MODULE=fast benchmarks/exudyn/run.sh --mesh $work/rod --modes 2 --h $h --t-end $t_end"
)
: > "$work/runs.txt"
for k in "${!configs[@]}"; do echo "$k|${configs[$k]}" >> "$work/configs.txt"; done
for r in $(seq 1 "$repeats"); do
    for k in "${!configs[@]}"; do
        IFS='|' read -r name match cmd <<< "${configs[$k]}"
        load=$(cut -d' ' -f1 /proc/loadavg)
        out=$($cmd --csv "$work/run_$k.csv" --reference "$work/reference.csv")
        s=$(sed -n 's/^RESULT s_per_step=\([^ ]*\) cpu_per_step=\([^ ]*\) peak_w=\(.*\)$/\1 \2 \3/p' <<< "$out")
        e=$(sed -n 's/^RESULT history_error=\([^ ]*\) peak_error=\(.*\)$/\1 \2/p' <<< "$out")
        echo "$k|$name|$match|$load|$s|$e" | tee -a "$work/runs.txt"
        [ "$r" = 1 ] && echo "$out" > "$work/log_$k.txt"
    done
done

python3 - "$work" "$repeats" "$results/slider_crank.md" "${ref_cmd[*]}" "$h" "$t_end" "$modes" "$bin" <<'PY'
import platform, statistics, subprocess, sys
work, repeats, out, ref_cmd, h, t_end, modes, bin_dir = sys.argv[1:9]
ref_cmd = ref_cmd.replace(bin_dir, "target/release")

def sh(cmd):
    return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()

rows = {}
for line in open(f"{work}/runs.txt"):
    k, name, match, load, s, e = line.rstrip("\n").split("|")
    wall, cpu, peak = map(float, s.split())
    hist, peak_err = map(float, e.split())
    r = rows.setdefault(int(k), {"name": name, "match": match, "wall": [], "cpu": [], "load": [], "peak": peak, "hist": hist, "peak_err": peak_err})
    r["wall"].append(wall)
    r["cpu"].append(cpu)
    r["load"].append(float(load))
exudyn = [k for k in rows if rows[k]["name"].startswith("Exudyn")]
med = lambda k, key: statistics.median(rows[k][key])
# Like-for-like Exudyn rows by their own key (same modes, same Newton variant).
twin = {rows[k]["match"]: k for k in exudyn}
base = exudyn[0]
ref_peak = max(abs(float(l.split(",")[1])) for l in list(open(f"{work}/reference.csv"))[1:])
ours = {}
for l in open(f"{work}/ours_converged.log"):
    if l.startswith("RESULT "):
        ours.update(dict(f.split("=", 1) for f in l.split()[1:]))
cpu_model = sh("grep -m1 'model name' /proc/cpuinfo | cut -d: -f2")
memory = sh("free -g | awk '/Mem/{print $2}'")
versions = sh("benchmarks/exudyn/.venv/bin/python -c 'import exudyn, numpy, scipy; print(\"exudyn\", exudyn.__version__, \"numpy\", numpy.__version__, \"scipy\", scipy.__version__)'")
loads = [x for r in rows.values() for x in r["load"]]
lines = [
    "# Slider-crank (validation problem C2): flexmbs against Exudyn",
    "",
    f"Machine: {cpu_model}, {sh('nproc')} cores, {memory} GB, {platform.system()} {platform.release()}; {sh('rustc --version')}; Python {platform.python_version()}, {versions}.",
    f"Load average (1 min) at the starts of the runs: {min(loads):.1f} to {max(loads):.1f}, median {statistics.median(loads):.1f} (above 2, other work shared the 2 cores and wall times are inflated):"
    " CPU time is the scheduler's run time of the process's threads during the time loop.",
    "",
    f"Rod: hex20 bar 24 x 2 x 2 (741 nodes, 2223 dofs), square section with the round rod's I, RBE2 end faces, {modes} fixed-interface modes unless said;"
    f" h = T/400 = {float(h):.4e} s, t_end = {float(t_end):.4f} s, generalized-alpha rho_inf = 0.9, Newton to convergence.",
    "",
] + open(f"{work}/reference.md").read().rstrip("\n").split("\n") + [
    f"Its peak |w| = {ref_peak * 1e3:.4f} mm. Our own converged beam model of the same rod against it, `{ref_cmd.replace(work, '$WORK')}`"
    f" (32 Timoshenko-beam superelements, h = T/800): peak {float(ours['peak_error']) * 100:+.2f} %, history {float(ours['history_error']) * 100:.2f} % of the peak.",
    "",
    f"Each configuration run {repeats} times, alternating; medians. Per step = the whole time loop (set-up and reduction excluded on both sides) over the steps.",
    "",
    f"Speed columns: wall time per step against the Exudyn run named ({rows[base]['name']}: Exudyn's default, its time"
    " integration keeps the Jacobian unless `newton.useModifiedNewton` is turned off; full Newton is flexmbs's default),"
    " and against the like-for-like Exudyn run (same number of modes, same Newton variant; CPU time in brackets).",
    "",
    "| configuration | wall s/step | steps/s | CPU s/step | speed vs Exudyn default | vs Exudyn like-for-like (CPU) | peak abs(w) [mm] | max abs(w - w_ref) / max abs(w_ref) | peak error |",
    "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
]
for k in sorted(rows):
    r = rows[k]
    c, w = med(k, "cpu"), med(k, "wall")
    t = twin.get(r["match"])
    like = f"{med(t, 'wall') / w:.1f}x ({med(t, 'cpu') / c:.1f}x)" if t is not None and t != k else "-"
    lines.append(
        f"| {r['name']} | {w:.3e} | {1 / w:.0f} | {c:.3e} | {med(base, 'wall') / w:.1f}x | {like} | {r['peak'] * 1e3:.4f} | {r['hist'] * 100:.1f} % | {r['peak_err'] * 100:+.1f} % |"
    )

def history(k):
    t, w = [], []
    for line in list(open(f"{work}/run_{k}.csv"))[1:]:
        c = line.split(",")
        t.append(float(c[0]))
        w.append(float(c[1]))
    return t, w

same = [k for k in rows if "as Exudyn" in rows[k]["name"]]
if same and exudyn:
    (t0, w0), (t1, w1) = history(same[0]), history(exudyn[0])
    n = min(len(t0), len(t1))
    diff = max(abs(w0[i] - w1[i]) for i in range(n)) / max(abs(x) for x in w1[:n])
    lines += ["", f"Same model on both sides (one solid superelement, frame at interface A, {modes} modes): the flexmbs and Exudyn"
              f" midpoint histories differ by at most {diff * 100:.2f} % of Exudyn's peak ({n} output times), peaks"
              f" {rows[same[0]]['peak'] * 1e3:.4f} mm and {rows[exudyn[0]]['peak'] * 1e3:.4f} mm."]
lines += ["", f"All of it: `benchmarks/run_comparison.sh {repeats}`. The runs ($WORK is its temporary folder; `$WORK/rod` is written by"
          " `export_rod --out $WORK/rod`):", "", "```sh"]
for line in open(f"{work}/configs.txt"):
    k, name, _match, cmd = line.rstrip("\n").split("|", 3)
    lines.append(f"# {name}")
    lines.append(cmd.replace(work, "$WORK").replace(bin_dir, "target/release") + " --csv $WORK/run.csv --reference $WORK/reference.csv")
lines += ["```"]
text = "\n".join(lines) + "\n"
# The discussion below the marker is written by hand: keep it.
marker = "<!-- written by hand below: run_comparison.sh keeps it -->"
try:
    old = open(out).read()
    if marker in old:
        text += "\n" + old[old.index(marker):]
except FileNotFoundError:
    pass
open(out, "w").write(text)
print(text)
PY
python3 "$root/benchmarks/scripts/write_section.py" slider_crank "$results/slider_crank.md" "$root/BENCHMARKS.md"
echo "work files in $work"
