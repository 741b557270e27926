"""Shared fixtures: copies of the repository's example studies in a temporary folder (runs
write results folders and caches beside their study), and the `flexmbs` program to compare
with."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
EXAMPLES = REPO / "examples"
# Test studies read by both the Rust tests of the study crate and these.
STUDIES = REPO / "crates" / "study" / "tests" / "studies"


@pytest.fixture
def examples(tmp_path):
    """A copy of examples/ (studies and meshes) in a fresh temporary folder."""
    dst = tmp_path / "examples"
    # Without caches and results a developer's runs may have left there.
    shutil.copytree(EXAMPLES, dst, ignore=shutil.ignore_patterns(".flexmbs-cache", "*-results", "__pycache__"))
    return dst


def cli_path():
    """The `flexmbs` program: $FLEXMBS_CLI, else the workspace's release, else debug build."""
    env = os.environ.get("FLEXMBS_CLI")
    if env:
        return Path(env)
    for profile in ("release", "debug"):
        p = REPO / "target" / profile / "flexmbs"
        if p.is_file():
            return p
    return None


@pytest.fixture
def cli():
    """Runs the `flexmbs` program; the comparison tests need it (CI builds it before pytest)."""
    path = cli_path()
    if path is None or not path.is_file():
        pytest.fail("the flexmbs program is not built: cargo build --release -p flexmbs, or set FLEXMBS_CLI")

    def run(*args, cwd=None):
        done = subprocess.run([str(path), *map(str, args)], cwd=cwd, capture_output=True, text=True)
        if done.returncode != 0:
            raise AssertionError(f"flexmbs {' '.join(map(str, args))} failed:\n{done.stdout}\n{done.stderr}")
        return done

    return run
