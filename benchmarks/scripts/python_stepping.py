#!/usr/bin/env python3
"""Cost per time step of the slider-crank (examples/slider_crank.toml, 4 superelements, 2
modes each, h = 0.1 ms) stepped from Python against the same run in the `flexmbs` program.

    python3 benchmarks/scripts/python_stepping.py [--repeats 7] [--venv DIR]

Set-up, as `.ci/run` does it: a virtual environment (`--venv`, default
`target/python-bench-venv`) where `pip install ./crates/python` builds the extension in
release and installs the package (its wall and CPU time are reported: what the extension adds
to CI), and `cargo build --release -p flexmbs` for the program. Then the script runs itself
again with the environment's Python. `--no-setup` measures with the Python that runs it, which
must have `flexmbs` installed.

Writes benchmarks/results/python_stepping.md and its table into BENCHMARKS.md
(benchmarks/scripts/write_section.py). Every figure is CPU time (user + system) per step, the
smallest of `--repeats` repetitions (other processes on the machine only ever add to it); the
repetitions interleave the program and Python, so a change of the machine's load falls on
both alike:

- program: `flexmbs run --t-end T` at two end times (126 and 1260 steps), the difference
  divided by the 1134 steps in between, so that start-up, the reduction (from the cache) and
  the plots at the end cancel; each step writes its sensor row to the CSV files, and every 20th
  the deformed mesh (the study's `[output]`).
- Python `step()` + `sensors()`: `Simulation.step()` one step at a time over the same steps,
  every sensor read into numpy arrays after each step: the work of a controller or a
  co-simulation partner. The same two step counts, differenced as for the program.
- Python `step()`: the same without reading the sensors.
- Python `Study.run`: the program's path (`study::run`, the same results folder) called
  in-process: the program minus its argument parsing and console.
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
COMMAND = "python3 benchmarks/scripts/python_stepping.py"


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def own_cpu():
    return time.process_time()


def loadavg():
    return " ".join(open("/proc/loadavg").read().split()[:3])


def cpu_model():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return "unknown CPU"
    fields = dict(line.split(":", 1) for line in out.splitlines() if ":" in line)
    model = fields.get("Model name", "unknown CPU").strip()
    cpus = fields.get("CPU(s)", "?").strip()
    return f"{model}, {cpus} CPUs (lscpu)"


def setup(venv: Path, argv):
    """The environment `.ci/run` makes, the program's release build, then this script again
    with the environment's Python."""
    if not (venv / "bin" / "python").is_file():
        subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    py = venv / "bin" / "python"
    wall, cpu = time.time(), child_cpu()
    subprocess.run([str(py), "-m", "pip", "install", "--quiet", str(ROOT / "crates" / "python")], check=True, cwd=ROOT)
    build = (time.time() - wall, child_cpu() - cpu)
    subprocess.run(["cargo", "build", "--release", "-p", "flexmbs"], check=True, cwd=ROOT)
    env = dict(os.environ, PYTHON_STEPPING_BUILD=f"{build[0]:.0f} {build[1]:.0f}")
    os.execve(str(py), [str(py), __file__, *argv, "--no-setup"], env)


def program_run(cli, study, t_end, out, cache):
    before = child_cpu()
    subprocess.run(
        [str(cli), "run", str(study), "--t-end", repr(t_end), "--out", str(out), "--cache", str(cache)],
        check=True,
        capture_output=True,
    )
    return child_cpu() - before


def stepping(flexmbs, study, cache, n, read):
    """CPU time of `n` steps of a fresh simulation, one `step()` at a time, every sensor read
    after each when `read`."""
    sim = study.simulation(cache=cache)
    step, sensors = sim.step, sim.sensors
    t0 = own_cpu()
    if read:
        for _ in range(n):
            step()
            sensors()
    else:
        for _ in range(n):
            step()
    return own_cpu() - t0


def per_step(costs):
    return (costs[1] - costs[0]) / (STEPS[1] - STEPS[0])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=str(ROOT / "target" / "release" / "flexmbs"))
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--venv", default=str(ROOT / "target" / "python-bench-venv"))
    ap.add_argument("--no-setup", action="store_true", help="use this Python's flexmbs and the built program as they are")
    ap.add_argument("--no-write", action="store_true", help="print the table only")
    args = ap.parse_args()
    if not args.no_setup:
        setup(Path(args.venv), [a for a in sys.argv[1:]])
    import flexmbs

    cli = Path(args.cli)
    have_cli = cli.is_file()
    if not have_cli:
        print(f"{cli} is not built: the program's path is measured in-process (Study.run)", file=sys.stderr)
    work = Path(tempfile.mkdtemp(prefix="python_stepping."))
    shutil.copytree(ROOT / "examples", work / "examples", ignore=shutil.ignore_patterns(".flexmbs-cache", "*-results"))
    study_file = work / "examples" / "slider_crank.toml"
    cache = work / "cache"
    study = flexmbs.Study.load(study_file)
    # Warm the cache (the reduction is not what is measured) and the file system.
    if have_cli:
        program_run(cli, study_file, STEPS[0] * DT, work / "warm", cache)
    else:
        study.run(t_end=STEPS[0] * DT, results_dir=work / "warm", cache=cache)

    runs = {"program": [], "read": [], "step": [], "run": []} if have_cli else {"run": [], "read": [], "step": []}
    load_before = loadavg()
    for r in range(args.repeats):
        # Interleaved: the program, Python stepping, the program's path in-process.
        if have_cli:
            runs["program"].append(
                per_step([program_run(cli, study_file, n * DT, work / f"cli-{r}-{n}", cache) for n in STEPS])
            )
        runs["read"].append(per_step([stepping(flexmbs, study, cache, n, True) for n in STEPS]))
        runs["step"].append(per_step([stepping(flexmbs, study, cache, n, False) for n in STEPS]))
        costs = []
        for n in STEPS:
            t0 = own_cpu()
            study.run(t_end=n * DT, results_dir=work / f"py-{r}-{n}", cache=cache)
            costs.append(own_cpu() - t0)
        runs["run"].append(per_step(costs))
        shutil.rmtree(work / f"cli-{r}-{STEPS[1]}", ignore_errors=True)
        shutil.rmtree(work / f"py-{r}-{STEPS[1]}", ignore_errors=True)
    load_after = loadavg()
    names = {
        "program": "program (`flexmbs run`, CSV rows every step, meshes every 20th)",
        "read": "Python, one `step()` at a time + `sensors()` after each",
        "step": "Python, one `step()` at a time, nothing read",
        "run": "Python `Study.run` (the program's path in-process)",
    }
    best = {k: min(v) for k, v in runs.items()}
    base = next(iter(best.values()))
    build = os.environ.get("PYTHON_STEPPING_BUILD")
    lines = [
        "# Slider-crank stepped from Python against the program",
        "",
        f"`{COMMAND} --repeats {args.repeats}`: examples/slider_crank.toml, h = 0.1 ms, "
        f"{STEPS[1] - STEPS[0]} steps (the difference of runs of {STEPS[0]} and {STEPS[1]} steps); "
        f"CPU time (user + system) per step, the smallest of {args.repeats} interleaved repetitions.",
        "",
        f"Machine: {cpu_model()}; load average before {load_before}, after {load_after} "
        f"(other builds ran meanwhile); flexmbs {flexmbs.__version__}, Python {sys.version.split()[0]}.",
        "",
        f"| run | µs per step | relative to the {'program' if have_cli else 'program path in-process'} |",
        "|---|---:|---:|",
    ]
    for k, v in best.items():
        lines.append(f"| {names[k]} | {v * 1e6:.1f} | {v / base:.3f} |")
    lines.append("")
    lines.append(
        "Every repetition [µs/step]: "
        + "; ".join(f"{k} " + ", ".join(f"{x * 1e6:.0f}" for x in v) for k, v in runs.items())
        + "."
    )
    if build:
        wall, cpu = build.split()
        lines.append("")
        lines.append(
            f"The set-up's `pip install ./crates/python` (the extension in release, with the "
            f"workspace's `target/` as it was): {wall} s wall, {cpu} s CPU."
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
