#!/usr/bin/env python3
"""Cost of a communication step of the slider-crank FMU (examples/slider_crank.toml, h =
0.1 ms) in FMPy against the library's step stepped from Python.

    python benchmarks/scripts/fmu_do_step.py [--repeats 5] [--library target/release/libflexmbs_fmu.so]

Needs a Python with `flexmbs` and `fmpy` installed (`pip install "./crates/python[test]"`)
and the FMU library (`cargo build --release -p flexmbs-fmu`). Every figure is CPU time of
the process per analysis step, the smallest of `--repeats` repetitions, over the steps from
t = 0.0126 to 0.0252 (126 steps; the first 126 steps warm the caches and the allocator):

- library: `Simulation.step()` then `sensors()` (every sensor read), one step at a time;
- library, nothing read: `Simulation.step()` alone;
- FMU, step = dt: `fmi2DoStep(dt)` then `fmi2GetReal` of every output (what a master does
  at every communication point);
- FMU, nothing read: `fmi2DoStep(dt)` alone;
- FMU, step = 10 dt: `fmi2DoStep(10 dt)` and every output read, per analysis step.

Prints the table that BENCHMARKS.md ("The FMU's communication step") quotes.
"""

import argparse
import tempfile
import time
from pathlib import Path

import flexmbs
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parents[2]
DT = 1e-4
WARM, STEPS = 126, 126


def library_steps(study, read):
    sim = study.simulation()
    for _ in range(WARM):
        sim.step()
    t0 = time.process_time()
    for _ in range(STEPS):
        sim.step()
        if read:
            sim.sensors()
    return (time.process_time() - t0) / STEPS


def fmu_steps(fmu, folder, n, read):
    # A fresh folder each time: a library stays mapped after it is freed (its thread-local
    # destructors keep it loaded), and extracting over a mapped file would fault.
    folder.mkdir(exist_ok=True)
    folder = Path(tempfile.mkdtemp(dir=folder))
    md = read_model_description(str(fmu))
    outputs = [v.valueReference for v in md.modelVariables if v.causality == "output"]
    s = FMU2Slave(
        guid=md.guid,
        unzipDirectory=extract(str(fmu), str(folder)),
        modelIdentifier=md.coSimulation.modelIdentifier,
        instanceName="bench",
    )
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    t = 0.0
    for _ in range(WARM // n):
        s.doStep(currentCommunicationPoint=t, communicationStepSize=n * DT)
        t += n * DT
    t0 = time.process_time()
    for _ in range(STEPS // n):
        s.doStep(currentCommunicationPoint=t, communicationStepSize=n * DT)
        t += n * DT
        if read:
            s.getReal(outputs)
    spent = (time.process_time() - t0) / (STEPS // n * n)
    s.terminate()
    s.freeInstance()
    return spent


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--library", type=Path, default=ROOT / "target" / "release" / "libflexmbs_fmu.so")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        study = flexmbs.Study.load(ROOT / "examples" / "slider_crank.toml")
        fmu = tmp / "slider_crank.fmu"
        study.export_fmu(fmu, library=args.library)
        rows = {
            "library: `step()` + `sensors()`": lambda: library_steps(study, True),
            "library: `step()`, nothing read": lambda: library_steps(study, False),
            "FMU: `fmi2DoStep(dt)` + every output": lambda: fmu_steps(fmu, tmp / "a", 1, True),
            "FMU: `fmi2DoStep(dt)`, nothing read": lambda: fmu_steps(fmu, tmp / "b", 1, False),
            "FMU: `fmi2DoStep(10 dt)` + every output, per step": lambda: fmu_steps(fmu, tmp / "c", 10, True),
        }
        best = {k: min(f() for _ in range(args.repeats)) for k, f in rows.items()}
    base = best["library: `step()` + `sensors()`"]
    print("| stepping | µs per analysis step | relative to the library's step + sensors |")
    print("|---|---:|---:|")
    for k, v in best.items():
        print(f"| {k} | {v * 1e6:.1f} | {v / base:.3f} |")


if __name__ == "__main__":
    main()
