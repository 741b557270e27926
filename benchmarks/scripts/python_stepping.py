#!/usr/bin/env python3
"""Cost per time step of the slider-crank (examples/slider_crank.toml, 4 superelements, 2
modes each, h = 0.1 ms) stepped from Python against the same run in the `flexmbs` program.

    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install ./crates/python
    cargo build --release -p flexmbs
    /tmp/venv/bin/python benchmarks/scripts/python_stepping.py [--repeats 5]

Writes benchmarks/results/python_stepping.md and its table into BENCHMARKS.md
(benchmarks/scripts/write_section.py). Every figure is CPU time (user + system) per step, the
smallest of `--repeats` runs (other processes on the machine only ever add to it):

- program: `flexmbs run --t-end T` at two end times (126 and 1260 steps), the difference
  divided by the 1134 steps in between, so that start-up, the reduction (from the cache) and
  the plots at the end cancel; each step writes its sensor row to the CSV files, and every 20th
  the deformed mesh (the study's `[output]`).
- Python `step()`: `Simulation.step()` 1260 times in a loop, nothing read.
- Python `step()` + `sensors()`: every sensor read into numpy arrays after each step, the
  work a controller or a co-simulation does.
- Python `Study.run`: the program's path in-process (results folder and all), by the same two
  end times.
"""

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STEPS = (126, 1260)
DT = 1e-4


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def own_cpu():
    return time.process_time()


def program_run(cli, study, t_end, out, cache):
    before = child_cpu()
    subprocess.run(
        [str(cli), "run", str(study), "--t-end", repr(t_end), "--out", str(out), "--cache", str(cache)],
        check=True,
        capture_output=True,
    )
    return child_cpu() - before


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=str(ROOT / "target" / "release" / "flexmbs"))
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--no-write", action="store_true", help="print the table only")
    args = ap.parse_args()
    import flexmbs

    work = Path(tempfile.mkdtemp(prefix="python_stepping."))
    shutil.copytree(ROOT / "examples", work / "examples")
    study_file = work / "examples" / "slider_crank.toml"
    cache = work / "cache"
    # Warm the cache (the reduction is not what is measured) and the file system.
    program_run(args.cli, study_file, STEPS[0] * DT, work / "warm", cache)

    def per_step(costs):
        return (costs[1] - costs[0]) / (STEPS[1] - STEPS[0])

    program, steps_only, steps_read, study_run = [], [], [], []
    load_before = open("/proc/loadavg").read().split()[:3]
    for r in range(args.repeats):
        program.append(
            per_step([program_run(args.cli, study_file, n * DT, work / f"cli-{r}-{n}", cache) for n in STEPS])
        )
        study = flexmbs.Study.load(study_file)
        costs = []
        for n in STEPS:
            t0 = own_cpu()
            study.run(t_end=n * DT, results_dir=work / f"py-{r}-{n}", cache=cache)
            costs.append(own_cpu() - t0)
        study_run.append(per_step(costs))
        for read, into in ((False, steps_only), (True, steps_read)):
            sim = study.simulation(cache=cache)
            t0 = own_cpu()
            for _ in range(STEPS[1]):
                sim.step()
                if read:
                    sim.sensors()
            into.append((own_cpu() - t0) / STEPS[1])
    load_after = open("/proc/loadavg").read().split()[:3]
    best = {
        "program (`flexmbs run`)": min(program),
        "Python `Simulation.step()`": min(steps_only),
        "Python `step()` + `sensors()`": min(steps_read),
        "Python `Study.run`": min(study_run),
    }
    base = best["program (`flexmbs run`)"]
    lines = [
        "# Slider-crank stepped from Python against the program",
        "",
        f"`benchmarks/scripts/python_stepping.py`, {args.repeats} repeats, smallest CPU time per step "
        f"(user + system); examples/slider_crank.toml, h = 0.1 ms. Load average before and after: "
        f"{' '.join(load_before)} / {' '.join(load_after)}; {os.cpu_count()} cores; "
        f"flexmbs {flexmbs.__version__}, Python {sys.version.split()[0]}.",
        "",
        "| run | µs per step | relative to the program |",
        "|---|---:|---:|",
    ]
    for name, v in best.items():
        lines.append(f"| {name} | {v * 1e6:.1f} | {v / base:.3f} |")
    lines.append("")
    lines.append(
        "All runs per repeat [µs/step]: program "
        + ", ".join(f"{x * 1e6:.0f}" for x in program)
        + "; step() "
        + ", ".join(f"{x * 1e6:.0f}" for x in steps_only)
        + "; step() + sensors() "
        + ", ".join(f"{x * 1e6:.0f}" for x in steps_read)
        + "; Study.run "
        + ", ".join(f"{x * 1e6:.0f}" for x in study_run)
        + "."
    )
    text = "\n".join(lines) + "\n"
    print(text)
    if not args.no_write:
        out = ROOT / "benchmarks" / "results" / "python_stepping.md"
        out.write_text(text)
        subprocess.run(
            [sys.executable, str(ROOT / "benchmarks" / "scripts" / "write_section.py"), "python_stepping", str(out), str(ROOT / "BENCHMARKS.md")],
            check=True,
        )
    shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
