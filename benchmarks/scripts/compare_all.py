#!/usr/bin/env python3
"""The side-by-side comparisons of flexmbs against the fastest alternatives, in one go
(`benchmarks/compare_all.sh` builds the programs, makes the Python environment and runs this
with the venv's Python; see that script for the usage).

    compare_all.py --root ROOT --bin DIR --work DIR --repeats K [--quick] [--only reduction,rod]

1. reduction: the craig_bampton bench's hex8 blocks (50k and 200k dofs; --quick: 10k), our whole
   Craig-Bampton reduction (wall, CPU, peak RSS, factorisation stage) against scipy's eigsh
   with MKL PARDISO's Cholesky factor as the shift-invert operator (20 modes, tol 1e-8;
   `crates/reduction/benches/scipy_eigsh.py --solver pardiso`), PARDISO's factorisation alone,
   and the two sets of fixed-interface eigenvalues compared;
2. rod: the C2 slider-crank with the round rod over 4 crank revolutions. A converged
   reference that is not our model: Exudyn's ANCF cable refined in elements and time step
   until the rod's extrema change by less than 1e-5 relative (ancf_reference.py, which
   run_comparison.sh runs for the solid rod's square section). Then, for every configuration
   (flexmbs beam superelements; Exudyn's ANCF cable and geometrically exact 3D beam), the
   largest step of h = T/400, T/800, ... that brings the extrema within 0.05 % of the
   reference, and the timed runs at that step.

Each timed configuration runs K times, the programs alternating run by run; medians. Each part
writes `benchmarks/results/compare_all_<part>.md` and, through write_section.py, the
`compare_all_<part>` block of BENCHMARKS.md, so that the parts can also run separately. The solid-rod comparison against Exudyn's ObjectFFRFreducedOrder is
`benchmarks/run_comparison.sh`, which compare_all.sh runs after this.
"""

import argparse
import math
import os
import platform
import re
import statistics
import subprocess
import sys
import time

import numpy as np

from ancf_reference import converge, extrema, extrema_change, history_error, table

TARGET = 5e-4  # the accuracy asked of every rod row: extrema within 0.05 % of the reference
# Exudyn's fastest build: the exudynCPPfast module of the same wheel (no range checks, AVX2),
# which Exudyn loads when asked; its results are the same to the printed digits.
EXUDYN_FAST = {"EXUDYN_MODULE": "fast"}
REVOLUTIONS = 4
SPEED = 150.0
PERIOD = 2 * math.pi / SPEED
T_END = REVOLUTIONS * PERIOD


def log(*a):
    print(*a, flush=True)


def sh(cmd):
    return subprocess.run(cmd, shell=True, capture_output=True, text=True).stdout.strip()


def load():
    return float(open("/proc/loadavg").read().split()[0])


def run(cmd, env=None, may_fail=False):
    """Runs `cmd` (a list), returns its stdout; fails loudly with its output, or returns None
    when `may_fail` (a solver that does not converge at a step)."""
    e = dict(os.environ)
    e.update(env or {})
    p = subprocess.run(cmd, capture_output=True, text=True, env=e)
    if p.returncode != 0:
        message = f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}"
        if may_fail:
            log(message.splitlines()[0])
            return None
        sys.exit(message)
    return p.stdout


def result_fields(text):
    """The key=value fields of every `RESULT` line of a program's output, merged."""
    out = {}
    for line in text.splitlines():
        if line.startswith("RESULT "):
            out.update(dict(f.split("=", 1) for f in line.split()[1:]))
    return out


def machine():
    info = open("/proc/cpuinfo").read()
    field = lambda k: re.search(rf"^{k}\s*:\s*(.*)$", info, re.M).group(1).strip()
    name, family, model = field("model name"), int(field("cpu family")), int(field("model"))
    flags = field("flags").split()
    arch = ""
    if "AMD" in field("vendor_id") or "AMD" in name:
        if family == 25:
            arch = "Zen 4" if 0x10 <= model <= 0x1F or 0x60 <= model <= 0x7F or 0xA0 <= model <= 0xAF else "Zen 3"
        elif family == 26:
            arch = "Zen 5"
        elif family == 23:
            arch = "Zen 2" if model >= 0x30 else "Zen"
    simd = "AVX-512" if "avx512f" in flags else "AVX2" if "avx2" in flags else "SSE"
    cores = os.cpu_count()
    mem = round(int(re.search(r"MemTotal:\s+(\d+)", open("/proc/meminfo").read()).group(1)) / 1024**2)
    desc = f"{name}" + (f" ({arch}, family {family} model {model})" if arch else f" (family {family} model {model})")
    return f"{desc}, {simd}, {cores} cores, {mem} GB, {platform.system()} {platform.release()}"


# ---------------------------------------------------------------------------------------------
# 1. Reduction


def reduction(a, sizes, repeats):
    mtx = os.path.join(a.work, "mtx")
    os.makedirs(mtx, exist_ok=True)
    eigsh = os.path.join(a.root, "crates/reduction/benches/scipy_eigsh.py")
    # ARPACK's tolerance: 1e-8, and 0 (its default, machine precision). With 1e-8 and the default
    # 41 Lanczos vectors it can miss the second copy of a repeated eigenvalue (the blocks' square
    # sections have pairs of equal bending frequencies): the eigenvalue column shows it.
    tols = ["1e-8", "0"]
    ours = {s: [] for s in sizes}
    theirs = {(s, t): [] for s in sizes for t in tols}
    loads = []
    for r in range(repeats):
        for size in sizes:
            env = {"REDUCTION_CB_SIZES": size}
            if r == 0:  # the first run also writes K_ii, M_ii and its eigenvalues
                env.update({"REDUCTION_CB_MTX_DIR": mtx, "REDUCTION_CB_EIGEN_ONLY": "0"})
            loads.append(load())
            f = result_fields(run([a.bench, "--bench"], env))
            ours[size].append(f)
            log(f"reduction {size} flexmbs run {r + 1}: {f['reduce_s']} s, {f['peak_mib']} MiB, factorisation {f['factor_s']} s (load {loads[-1]})")
            if r == 0:  # read the text once into the .npz cache, outside the timed runs
                run([sys.executable, "-c", f"import sys; sys.path.insert(0, {os.path.dirname(eigsh)!r}); import scipy_eigsh as s; "
                     f"s.read({mtx!r}, 'K_{size}'); s.read({mtx!r}, 'M_{size}')"])
            for tol in tols:
                loads.append(load())
                f = result_fields(run([sys.executable, eigsh, "--solver", "pardiso", "--tol", tol, mtx, size]))
                theirs[(size, tol)].append(f)
                log(f"reduction {size} PARDISO eigsh tol {tol} run {r + 1}: {f['eigsh_s']} s, {f['peak_mib']} MiB, Cholesky {f['factor_s']} s,"
                    f" LU {f['factor_lu_s']} s, eigenvalue difference {f['difference']} (load {loads[-1]})")
    for name in os.listdir(mtx):  # the matrices take GBs at 200k dofs
        if name.endswith((".mtx", ".npz")):
            os.remove(os.path.join(mtx, name))
    med = lambda rows, k: statistics.median(float(x[k]) for x in rows)
    lines = [
        "| block | dofs | run | wall [s] | CPU [s] | peak RSS [MiB] | factorisation [s] | eigenvalues: largest relative difference to flexmbs | wall time / flexmbs | memory / flexmbs |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for size in sizes:
        o = ours[size]
        t_o, m_o = med(o, "reduce_s"), med(o, "peak_mib")
        lines.append(f"| {size} | {o[0]['dofs']} | flexmbs, whole reduction | {t_o:.2f} | {med(o, 'reduce_cpu_s'):.2f} | {m_o:.0f} | {med(o, 'factor_s'):.2f} | | 1 | 1 |")
        for tol in tols:
            t = theirs[(size, tol)]
            diff = max(float(x["difference"]) for x in t)
            lines.append(
                f"| | | eigsh + PARDISO, tol {tol} | {med(t, 'eigsh_s'):.2f} | {med(t, 'eigsh_cpu_s'):.2f} | {med(t, 'peak_mib'):.0f} | {med(t, 'factor_s'):.2f} |"
                f" {diff:.1e}{' (modes missed)' if diff > 1e-6 else ''} | {med(t, 'eigsh_s') / t_o:.2f}x | {med(t, 'peak_mib') / m_o:.2f}x |"
            )
        lu = [x for tol in tols for x in theirs[(size, tol)]]
        lines.append(f"| | | PARDISO LU alone (pypardiso's default, matrix type 11) | | | | {med(lu, 'factor_lu_s'):.2f} | | | |")
    return lines, loads


# ---------------------------------------------------------------------------------------------
# 2. The C2 rod


class Rod:
    def __init__(self, a):
        self.a = a
        self.dir = os.path.join(a.work, "rod")
        os.makedirs(self.dir, exist_ok=True)
        self.params = os.path.join(a.work, "rod_mesh", "params.txt")
        self.exudyn = [sys.executable, os.path.join(a.root, "benchmarks/exudyn/slider_crank_beam.py"), "--params", self.params]
        self.flexmbs = [os.path.join(a.bin, "slider_crank"), "--rod", "round"]
        self.cache = {}

    def command(self, cfg, h, csv):
        common = ["--h", repr(h), "--t-end", repr(T_END), "--csv", csv]
        if cfg["program"] == "flexmbs":
            args = ["--segments", str(cfg["segments"]), "--modes", str(cfg["modes"]), "--beam-elements", str(cfg["beam_elements"])]
            if cfg.get("stiffening"):
                args.append("--geometric-stiffening")
            if cfg.get("modified"):
                args += ["--newton", "modified"]
            if cfg.get("planar"):
                args.append("--planar")
            return self.flexmbs + args + common
        args = ["--model", cfg["model"], "--elements", str(cfg["elements"])]
        if cfg.get("sparse"):
            args.append("--sparse")
        if cfg.get("modified"):
            args.append("--modified-newton")
        return self.exudyn + args + common

    def once(self, cfg, h, tag="", may_fail=False):
        """One run: its RESULT fields, iterations per step and the CSV path (cached by config and h);
        None if it failed and `may_fail`."""
        key = (cfg["name"], h, tag)
        if tag == "" and key in self.cache:
            return self.cache[key]
        csv = os.path.join(self.dir, re.sub(r"[^A-Za-z0-9]+", "_", f"{cfg['name']}_{h:.4e}{tag}") + ".csv")
        cmd = self.command(cfg, h, csv)
        l0 = load()
        out = run(cmd, env=EXUDYN_FAST if cfg["program"] == "exudyn" else None, may_fail=may_fail)
        if out is None:
            return None
        f = result_fields(out)
        it = re.search(r"([0-9.]+) iterations/step|iterations per step ([0-9.]+)", out)
        f["iterations"] = float(next(g for g in it.groups() if g)) if it else float("nan")
        f["csv"], f["cmd"], f["load"] = csv, cmd, l0
        if tag == "":
            self.cache[key] = f
        return f


def rod(a, repeats):
    r = Rod(a)
    report = []

    # The reference: Exudyn's ANCF cable refined until the extrema change < REFERENCE_TOL.
    ancf = lambda n: {"name": f"ref ANCF {n}", "program": "exudyn", "model": "ancf", "elements": n, "sparse": n >= 32}
    steps, n, h_ref = converge(lambda n, h: r.once(ancf(n), h)["csv"], PERIOD, a.quick, log)
    ref = r.once(ancf(n), h_ref)
    ref_csv, ref_e = ref["csv"], extrema(ref["csv"])
    log(f"reference: {n} elements, h = T/{PERIOD / h_ref:.0f}: extrema {ref_e[0] * 1e3:.5f} / {ref_e[1] * 1e3:.5f} mm")
    report.append(("reference", steps, n, h_ref, ref_e))

    # The configurations, each at the largest step of the ladder that reaches TARGET.
    ladder = [PERIOD / (400 * 2**k) for k in range(4 if a.quick else 6)]
    # Each program's modified Newton (the factorised iteration matrix kept across iterations and
    # steps) is a row of its own: it is the fastest choice on both sides.
    modified = lambda mod: ", modified Newton" if mod else ""
    flex = lambda s, m, st=True, mod=False, planar=False: {
        "name": f"flexmbs, {s}{' planar' if planar else ''} beam superelement{'s' if s > 1 else ''}, {m} mode{'s' if m != 1 else ''}{', geometric stiffening' if st else ''}{modified(mod)}",
        "program": "flexmbs", "segments": s, "modes": m, "beam_elements": 8, "stiffening": st, "modified": mod, "planar": planar,
    }
    exu = lambda model, n, sparse=False, mod=False: {
        "name": f"Exudyn {'ObjectANCFCable2D' if model == 'ancf' else 'ObjectBeamGeometricallyExact'}, {n} elements{modified(mod)}",
        "program": "exudyn", "model": model, "elements": n, "sparse": sparse, "modified": mod,
    }
    # The planar rows evaluate the rod in the plane of the mechanism (`--planar`: in-plane modes
    # only, 3 coordinates per interface); the spatial rows' 2 modes of the round rod are one
    # in-plane and one out-of-plane bending mode, so 2 spatial segments with 2 modes are the
    # planar ones with 1 mode.
    configs = [flex(1, 2), flex(1, 4), flex(2, 2), flex(2, 2, mod=True), flex(2, 4), flex(2, 4, mod=True), flex(1, 4, False),
               flex(1, 3, planar=True, mod=True), flex(1, 4, planar=True, mod=True),
               flex(2, 1, planar=True), flex(2, 1, planar=True, mod=True),
               exu("ancf", 4), exu("ancf", 4, mod=True)]
    # Exudyn's models: the smallest element count that can reach TARGET.
    families = [("ancf", [4, 8, 16, 32]), ("beam3d", [32, 64] if a.quick else [32, 64, 128])]

    def scan(cfg, first=0):
        """(h, error, run): the largest step of the ladder whose extrema error, and that of half the
        step, are within TARGET (so that a lucky cancellation of time and space errors does not
        choose the step); else the finest step within TARGET; else the smallest error. The ladder
        stops early when halving the step no longer reduces an error above TARGET (the space
        error dominates)."""
        tried = []
        for h in ladder[first:]:
            f = r.once(cfg, h, may_fail=True)
            err = extrema_change(extrema(f["csv"]), ref_e) if f is not None else math.inf
            log(f"  {cfg['name']}, h = T/{PERIOD / h:.0f}: extrema error {err:.2e}")
            tried.append((h, err, f))
            if len(tried) >= 2:
                (h0, e0, f0), e1 = tried[-2], err
                if e0 <= TARGET and e1 <= TARGET:
                    return tried[-2]
                if e0 > TARGET and e1 > TARGET and e1 > 0.7 * e0:
                    break
                if e0 <= TARGET and not math.isfinite(e1):  # a finer step failed: keep the coarser
                    break
        ok = [x for x in tried if x[1] <= TARGET]
        return ok[-1] if ok else min(tried, key=lambda x: x[1])  # (h, inf, None) if every step failed

    chosen = {}
    for cfg in configs:
        chosen[cfg["name"]] = (cfg,) + scan(cfg)
    for model, counts in families:
        for n in counts:
            cfg = exu(model, n, sparse=n >= 32)
            if cfg["name"] in chosen:
                res = chosen[cfg["name"]][1:]
            else:
                # The 3D beam's Newton iterations crawl or fail at T/400 and T/800: it starts at T/1600.
                res = scan(cfg, first=2 if model == "beam3d" else 0)
                chosen[cfg["name"]] = (cfg,) + res
            if res[1] <= TARGET:
                break
    # Our own converged beam model (32 superelements) against Exudyn's reference.
    ours_ref = {"name": "flexmbs, 32 beam superelements, 2 modes", "program": "flexmbs",
                "segments": 32, "modes": 2, "beam_elements": 4, "stiffening": False}
    f32 = r.once(ours_ref, ladder[-2])
    ours_ref_err = extrema_change(extrema(f32["csv"]), ref_e)
    log(f"{ours_ref['name']}, h = T/{PERIOD / ladder[-2]:.0f}: extrema error {ours_ref_err:.2e}")

    # Timed runs, alternating.
    failed = [name for name, c in chosen.items() if c[3] is None]
    for name in failed:
        log(f"{name}: failed at every step tried")
    rows = {name: {"cfg": c[0], "h": c[1], "err": c[2], "hist": history_error(c[3]["csv"], ref_csv), "runs": []}
            for name, c in chosen.items() if c[3] is not None}
    for k in range(repeats):
        for name, row in rows.items():
            f = r.once(row["cfg"], row["h"], tag=f"_timed{k}")
            row["runs"].append(f)
            log(f"timed {name} run {k + 1}: {float(f['s_per_step']) * 1e6:.1f} us/step wall, {float(f['cpu_per_step']) * 1e6:.1f} CPU (load {f['load']})")
    return report, rows, (ours_ref, ladder[-2], ours_ref_err, history_error(f32["csv"], ref_csv)), failed


def rod_tables(report, rows, ours_ref, repeats):
    _, steps, n_ref, h_ref, ref_e = report[0]
    lines = table(steps, n_ref, h_ref, ref_e, PERIOD, T_END, "round rod, Euler-Bernoulli, as C2 defines it") + [
        "",
        "Rows: every configuration at the largest step of h = T/400, T/800, ... (T/400 = 1.05e-4 s) whose extrema are within"
        f" {TARGET * 100:.2f} % of the reference (or the finest step tried, its error in bold). Per step: the time loop over its steps"
        f" (set-up and reduction excluded on both sides), medians of {repeats} runs, the programs alternating run by run;"
        " 4 revolutions: the per-step time times the steps, the time to the same answer."
        " Ratio: CPU time for the 4 revolutions of the fastest Exudyn row within the accuracy over this row's.",
        "",
        "| configuration | h | steps | Newton iterations/step | wall µs/step | CPU µs/step | CPU s for 4 revolutions | extrema error | max abs(w - w_ref) / max abs(w_ref) | fastest accurate Exudyn / this (CPU, 4 revolutions) |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    med = lambda row, k: statistics.median(float(f[k]) for f in row["runs"])
    total = lambda row: med(row, "cpu_per_step") * int(round(T_END / row["h"]))
    accurate_exudyn = [row for row in rows.values() if row["cfg"]["program"] == "exudyn" and row["err"] <= TARGET]
    fastest = min(accurate_exudyn, key=total) if accurate_exudyn else None
    for name, row in rows.items():
        err = f"{row['err'] * 100:.3f} %"
        err = err if row["err"] <= TARGET else f"**{err}**"
        ratio = f"{total(fastest) / total(row):.3g}x" if fastest is not None and row["err"] <= TARGET else "-"
        lines.append(
            f"| {name} | T/{PERIOD / row['h']:.0f} | {int(round(T_END / row['h']))} | {med(row, 'iterations'):.2f} | {med(row, 's_per_step') * 1e6:.1f} | "
            f"{med(row, 'cpu_per_step') * 1e6:.1f} | {total(row):.3f} | {err} | {row['hist'] * 100:.3f} % | {ratio} |"
        )
    cfg, h, err, hist = ours_ref
    lines += [
        "",
        f"Our own converged model against Exudyn's reference: {cfg['name']}, h = T/{PERIOD / h:.0f}: extrema {err * 100:.4f} % off, history {hist * 100:.4f} %.",
    ]
    if fastest is not None:
        lines.append(f"Fastest Exudyn row within {TARGET * 100:.2f} %: {[n for n, r in rows.items() if r is fastest][0]}.")
    return lines


def commands(rows, work, root, bin_dir):
    out = ["```sh"]
    for name, row in rows.items():
        cmd = " ".join(row["runs"][0]["cmd"]).replace(work, "$WORK").replace(bin_dir, "target/release").replace(root + "/", "")
        cmd = re.sub(r"\S*/python\S* ", "", cmd)
        cmd = cmd.replace("benchmarks/exudyn/slider_crank_beam.py", "EXUDYN_MODULE=fast benchmarks/exudyn/run.sh slider_crank_beam.py")
        out += [f"# {name}", re.sub(r"--csv \S+", "--csv $WORK/run.csv", cmd)]
    return out + ["```"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--root", required=True)
    ap.add_argument("--bin", required=True, help="folder of the release binaries (slider_crank)")
    ap.add_argument("--bench", required=True, help="the craig_bampton bench executable")
    ap.add_argument("--work", required=True)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", default="reduction,rod")
    ap.add_argument("--command", default="benchmarks/compare_all.sh")
    a = ap.parse_args()
    import exudyn, scipy  # noqa: E401  (versions for the record)

    versions = (
        f"{sh('rustc --version')}; Python {platform.python_version()}, exudyn {exudyn.__version__},"
        f" scipy {scipy.__version__}, numpy {np.__version__}, pypardiso {sh(sys.executable + ' -m pip show pypardiso | sed -n s/^Version:.//p')},"
        f" mkl {sh(sys.executable + ' -m pip show mkl | sed -n s/^Version:.//p')}"
    )
    for part in a.only.split(","):
        start, load_start = time.time(), open("/proc/loadavg").read().split()[:3]
        if part == "reduction":
            sizes = ["10k"] if a.quick else ["50k", "200k"]
            lines, loads = reduction(a, sizes, a.repeats)
            body = [
                "# Reduction against scipy eigsh with MKL PARDISO",
                "",
                "Hex8 steel blocks of the craig_bampton bench (2:1:1 bricks; RBE2 interfaces on both end faces), 20 fixed-interface modes."
                " flexmbs: the whole `reduction::reduce` (assembly, ordering and factorisation of K_ii, 12 constraint modes, Lanczos, projections,"
                " inertia invariants), one process per run. eigsh + PARDISO: scipy's `eigsh(K_ii, M=M_ii, sigma=0, k=20, tol=...)` with MKL"
                " PARDISO's Cholesky factor of K_ii (`pypardiso`, matrix type 2, METIS ordering) as the shift-invert operator on the same"
                " K_ii, M_ii (only the eigenproblem inside the reduction), at ARPACK tolerance 1e-8 and at its default 0 (machine"
                " precision); its peak RSS includes the matrices read. Factorisation: flexmbs's ordering and factorisation stage; PARDISO's"
                " Cholesky factorisation of the same K_ii inside the eigsh run, and pypardiso's default LU alone. Eigenvalues: the"
                " reduction's 20 fixed-interface eigenvalues against eigsh's, largest relative difference over the runs (above 1e-6: eigsh"
                " returned a wrong set, missing the second copy of a repeated eigenvalue).",
                "",
            ] + lines
        elif part == "rod":
            report, rows, ours_ref, failed = rod(a, a.repeats)
            loads = [float(f["load"]) for row in rows.values() for f in row["runs"]]
            body = [
                "# Slider-crank C2 rod: beam superelements against Exudyn's beam elements",
                "",
                "Validation problem C2 (rigid crank 0.15 m at 150 rad/s from the dead centre, round steel rod d = 6 mm, l = 0.30 m,"
                " slider of half the rod's mass, no gravity) over 4 revolutions (T = 2π/150 s), generalized-α with ρ∞ = 0.9 and full Newton"
                " on both sides, or each program's own modified Newton where the row says so (flexmbs: `--newton modified`, the"
                " factorised iteration matrix kept across iterations and steps and rebuilt when a correction contracts the residual"
                " by less than 0.01; Exudyn: `newton.useModifiedNewton`, its Jacobian kept across steps and rebuilt when the"
                " iteration slows). Exudyn runs its fast module (`EXUDYN_MODULE=fast`: exudynCPPfast, no range checks, AVX2;"
                " the same results). Output: the rod's midpoint deflection w from its chord; extrema error: the largest difference of max w and"
                " min w over the run from the reference's, over the reference's largest |w|. flexmbs: the rod as Euler-Bernoulli beam"
                " superelements (`slider_crank --rod round`, 8 beam elements reduced per superelement). Exudyn 2D: `ObjectANCFCable2D`"
                " with a 2D rigid crank and mass-point slider, its default dense solver up to 16 elements and its sparse one beyond."
                " Exudyn 3D: `ObjectBeamGeometricallyExact` (shear deformable, `NodeRigidBodyRxyz`, sparse solver, shear stiffness k G A)"
                " with 3D rigid crank and slider and generic joints.",
                "",
            ] + rod_tables(report, rows, ours_ref, a.repeats)
            if failed:
                body += ["", "Failed at every step tried (Newton did not converge): " + "; ".join(failed) + "."]
            body += ["", "The runs ($WORK is the script's temporary folder, `$WORK/rod_mesh` written by `export_rod --out $WORK/rod_mesh`):", ""]
            body += commands(rows, a.work, a.root, a.bin)
        else:
            sys.exit(f"--only: unknown part '{part}' (reduction, rod)")
        load_end = open("/proc/loadavg").read().split()[:3]
        head = [
            body[0],
            "",
            f"Machine: {machine()}; {versions}.",
            f"Load average (1, 5, 15 min) at the start {' '.join(load_start)}, at the end {' '.join(load_end)}; at the starts of the runs"
            f" {min(loads):.1f} to {max(loads):.1f}, median {statistics.median(loads):.1f}"
            + (" (above 2, other work shared the 2 cores: wall times are inflated, CPU times less so)." if max(loads) > 2 else "."),
            f"Command: `{a.command}` ({a.repeats} repetitions{', --quick' if a.quick else ''}; this part {(time.time() - start) / 60:.0f} min).",
        ]
        text = "\n".join(head + body[1:]) + "\n"
        path = os.path.join(a.root, f"benchmarks/results/compare_all_{part}.md")
        open(path, "w").write(text)
        print(text, flush=True)
        subprocess.run([sys.executable, os.path.join(a.root, "benchmarks/scripts/write_section.py"), f"compare_all_{part}", path,
                        os.path.join(a.root, "BENCHMARKS.md")], check=True)


if __name__ == "__main__":
    main()
