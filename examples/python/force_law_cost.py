"""The cost of a force law in Python per call: the flexible double pendulum of
crates/study/tests/studies/flexible_double_pendulum.toml run with its elbow damper as the
study's PID and as a flexmbs.ForceLaw (the same motion), timed; the extra time over the calls
the law took, each run the best of `repeats`. Usage: python force_law_cost.py [repeats]."""

import shutil
import sys
import tempfile
import time
from pathlib import Path

import flexmbs

STUDY = Path(__file__).resolve().parents[2] / "crates" / "study" / "tests" / "studies" / "flexible_double_pendulum.toml"


def main(repeats=3):
    tmp = Path(tempfile.mkdtemp())
    shutil.copy(STUDY, tmp)
    study = flexmbs.Study.load(tmp / STUDY.name)
    study["analyses.swing.t_end"] = 5.0  # 5000 steps: long enough to time on a busy machine
    calls = [0]

    def damper(t, q, qd):
        calls[0] += 1
        return {"elbow-damper": -1.0 * qd["elbow"]}

    study.run(results_dir=tmp / "warm")  # reduces the links into the cache
    for differences in ("central", "forward"):
        law = flexmbs.ForceLaw(damper, outputs=["elbow-damper"], reads=["elbow"], differences=differences)
        best_pid, best_law = float("inf"), float("inf")
        for _ in range(repeats):
            t0 = time.perf_counter()
            study.run(results_dir=tmp / "pid")
            best_pid = min(best_pid, time.perf_counter() - t0)
            calls[0] = 0
            t0 = time.perf_counter()
            study.run(results_dir=tmp / "law", forces=law)
            best_law = min(best_law, time.perf_counter() - t0)
        n = calls[0]
        print(
            f"{differences}: PID run {best_pid:.3f} s, law run {best_law:.3f} s, {n} calls: "
            f"{1e6 * (best_law - best_pid) / n:.1f} us per call"
        )
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
