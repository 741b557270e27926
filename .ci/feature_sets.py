#!/usr/bin/env python3
"""Fails when two of the builds `.ci/run` makes would compile a shared crate with different
features. Cargo compiles a crate once per feature set, so one difference (say, serde's
derive under PyO3's macros) compiles everything above that crate a second time; the crate
`unify` asks for the union, and this check says which crate escaped it.

    python3 .ci/feature_sets.py
"""

import subprocess
import sys

# The cargo commands of .ci/run, by their package selection (features as they pass them).
BUILDS = {
    "cargo test --workspace": ["--workspace"],
    "cargo test -p flexmbs --features validate": ["-p", "flexmbs", "--features", "validate"],
    "cargo test --release -p mbs": ["-p", "mbs"],
    "cargo test --release -p study": ["-p", "study"],
    "cargo run --release -p flexmbs": ["-p", "flexmbs"],
    "cargo build --release -p flexmbs-fmu": ["-p", "flexmbs-fmu"],
    "pip install ./crates/python": ["-p", "flexmbs-python", "--features", "extension-module"],
}
# Packages whose features differ by design: the two faces (their own features) and PyO3,
# which only the Python package uses (its extension-module feature is maturin's).
BY_DESIGN = {"flexmbs", "flexmbs-python", "pyo3", "pyo3-ffi", "pyo3-build-config"}


def feature_sets(selection):
    out = subprocess.run(
        ["cargo", "tree", *selection, "-e", "features,normal,build,dev", "--prefix", "none",
         "-f", "{p}|{f}"],
        check=True, capture_output=True, text=True,
    ).stdout
    sets = {}
    for line in out.splitlines():
        if "|" not in line:
            continue
        package, features = line.split("|", 1)
        name = package.split()[0]
        if name in BY_DESIGN:
            continue
        features = features.replace("(*)", "").replace("(proc-macro)", "").strip()
        sets.setdefault(" ".join(package.split()[:2]), set()).add(features)
    return sets


def main():
    graphs = {build: feature_sets(sel) for build, sel in BUILDS.items()}
    first, reference = next(iter(graphs.items()))
    problems = []
    for build, sets in graphs.items():
        for package in sorted(set(sets) & set(reference)):
            if sets[package] != reference[package]:
                problems.append(
                    f"{package}: '{build}' asks for {sorted(sets[package])}, "
                    f"'{first}' for {sorted(reference[package])}"
                )
    if problems:
        print("shared crates compiled with different features (add the union to crates/unify):")
        print("\n".join("  " + p for p in problems))
        sys.exit(1)
    print(f"one feature set per shared crate across {len(graphs)} builds")


if __name__ == "__main__":
    main()
