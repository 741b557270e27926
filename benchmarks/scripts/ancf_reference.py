#!/usr/bin/env python3
"""A converged reference for the slider-crank rod (validation problem C2) that is not our model:
Exudyn's planar ANCF cable (`ObjectANCFCable2D`, Euler-Bernoulli with axial strain), refined in
elements and time step until the rod's midpoint-deflection extrema change by less than
REFERENCE_TOL relative. compare_all.py uses it for the round rod; run_comparison.sh runs this
file for the solid rod's square section (with the venv's Python, which has Exudyn):

    ancf_reference.py --params DIR/params.txt --section round|square --t-end T --work DIR
        --csv reference.csv --markdown reference.md [--quick]

It writes the reference run's CSV (t, w, slider_x, as both programs' --reference reads it) and
a Markdown paragraph with the refinement table and how the reference converged.
"""

import argparse
import math
import os
import subprocess
import sys

import numpy as np

REFERENCE_TOL = 1e-5  # the reference's convergence: extrema change under refinement


def history(path):
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    return d[:, 0], d[:, 1]


def extrema(path):
    _, w = history(path)
    return np.array([w.max(), w.min()])


def extrema_change(e, ref):
    """Largest change of the extrema (max w, min w) relative to the reference's largest |w|."""
    return float(np.max(np.abs(e - ref)) / np.max(np.abs(ref)))


def history_error(path, ref_path):
    t, w = history(path)
    tr, wr = history(ref_path)
    return float(np.max(np.abs(w - np.interp(t, tr, wr))) / np.max(np.abs(wr)))


def converge(csv_of, period, quick, log=print):
    """Refines the ANCF cable from 8 elements at h = T/1600: at each level, the extrema change
    when the step is halved (dh) and when the elements are doubled (dn); refines what changed by
    REFERENCE_TOL or more, within a budget ((2 n_max) elements at h_min, n_max at h_min / 2).
    `csv_of(n, h)` runs n elements at step h and returns its CSV. Returns the levels
    [(n, h, dh, dn)], and the elements and step of the reference: the last level with the step
    halved (its time-step error about a third of dh for a second-order integrator, its element
    error about dn)."""
    n, h = 8, period / 1600
    n_max, h_min = (16, period / 6400) if quick else (32, period / 25600)
    steps = []
    while True:
        base = extrema(csv_of(n, h))
        dh = extrema_change(extrema(csv_of(n, h / 2)), base)
        dn = extrema_change(extrema(csv_of(2 * n, h)), base)
        steps.append((n, h, dh, dn))
        log(f"reference: {n} ANCF elements, h = T/{period / h:.0f}: halving h changes the extrema by {dh:.1e}, doubling the elements by {dn:.1e}")
        if max(dh, dn) < REFERENCE_TOL:
            break
        refine_h, refine_n = dh >= REFERENCE_TOL and h / 2 >= h_min, dn >= REFERENCE_TOL and 2 * n <= n_max
        if not (refine_h or refine_n):
            log("reference: refinement budget reached")
            break
        h, n = (h / 2 if refine_h else h), (2 * n if refine_n else n)
    return steps, n, h / 2


def table(steps, n_ref, h_ref, ref_e, period, t_end, rod):
    """The Markdown paragraph: how the reference converged (`rod` names the rod modelled)."""
    lines = [
        f"**Reference.** Exudyn's `ObjectANCFCable2D` ({rod}), refined from 8 elements at h = T/1600:",
        "",
        "| elements | h | extrema change, h halved | extrema change, elements doubled |",
        "|---:|---|---:|---:|",
    ]
    for n, h, dh, dn in steps:
        lines.append(f"| {n} | T/{period / h:.0f} = {h:.3e} s | {dh:.1e} | {dn:.1e} |")
    ok = max(steps[-1][2], steps[-1][3]) < REFERENCE_TOL
    lines += [
        "",
        f"The reference is the run with {n_ref} elements at h = T/{period / h_ref:.0f} = {h_ref:.3e} s ({int(round(t_end / h_ref))} steps): "
        f"midpoint deflection extrema {ref_e[0] * 1e3:.5f} mm and {ref_e[1] * 1e3:.5f} mm; "
        + (f"from the last row's level, halving the step and doubling the elements changed the extrema by less than {REFERENCE_TOL:.0e} relative."
           if ok else f"**not converged to {REFERENCE_TOL:.0e}**: the refinement budget ended with the changes in the last row."),
    ]
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--params", required=True, help="params.txt written by export_rod")
    ap.add_argument("--section", choices=["round", "square"], default="round")
    ap.add_argument("--t-end", type=float, required=True)
    ap.add_argument("--work", required=True, help="folder for the refinement runs")
    ap.add_argument("--csv", required=True, help="the reference run's CSV, written")
    ap.add_argument("--markdown", required=True, help="the paragraph on its convergence, written")
    ap.add_argument("--quick", action="store_true", help="a smaller refinement budget")
    a = ap.parse_args()
    params = dict(line.split() for line in open(a.params))
    period = 2 * math.pi / float(params["speed"])
    os.makedirs(a.work, exist_ok=True)
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "exudyn", "slider_crank_beam.py")

    def csv_of(n, h):
        csv = os.path.join(a.work, f"ancf_{n}_{period / h:.0f}.csv")
        if not os.path.exists(csv):
            cmd = [sys.executable, script, "--params", a.params, "--model", "ancf", "--section", a.section, "--elements", str(n),
                   "--h", repr(h), "--t-end", repr(a.t_end), "--csv", csv] + (["--sparse"] if n >= 32 else [])
            p = subprocess.run(cmd, capture_output=True, text=True)
            if p.returncode != 0:
                sys.exit(f"failed ({p.returncode}): {' '.join(cmd)}\n{p.stdout[-2000:]}\n{p.stderr[-2000:]}")
        return csv

    steps, n_ref, h_ref = converge(csv_of, period, a.quick, log=lambda s: print(s, flush=True))
    ref = csv_of(n_ref, h_ref)
    ref_e = extrema(ref)
    with open(a.csv, "w") as out:
        out.write(open(ref).read())
    rod = {"round": "round rod, Euler-Bernoulli, as C2 defines it",
           "square": f"Euler-Bernoulli with the solid rod's square section, side {float(params['side']) * 1e3:.4f} mm: its EA, EI and mass per length"}
    text = "\n".join(table(steps, n_ref, h_ref, ref_e, period, a.t_end, rod[a.section])) + "\n"
    open(a.markdown, "w").write(text)
    print(text, flush=True)


if __name__ == "__main__":
    main()
