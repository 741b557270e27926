"""Parameter sweeps on a local Dask cluster of 2 workers: 9 slider-crank cases (rod diameter x
crank speed, and one invalid diameter), a failing case recorded in its row, reduced bodies
shared through the cache."""

import math

import numpy as np
import pytest

import flexmbs

pytest.importorskip("dask.distributed")


def variants():
    cases = flexmbs.grid(**{"sections.rod.d": [0.004, 0.005, 0.006, 0.007], "drivers.crank-speed.function.speed": [120.0, 150.0]})
    cases.append({"sections.rod.d": -0.006, "drivers.crank-speed.function.speed": 150.0})
    for c in cases:
        # One revolution at 150 rad/s: 420 steps a case.
        c["analyses.run-up.t_end"] = 0.042
    return cases


def test_grid():
    g = flexmbs.grid(**{"a.b": [1, 2], "c": ["x", "y", "z"]})
    assert len(g) == 6 and g[0] == {"a.b": 1, "c": "x"} and g[-1] == {"a.b": 2, "c": "z"}
    with pytest.raises(TypeError):
        flexmbs.grid(a=3)


def test_sweep_on_a_local_cluster(examples, tmp_path):
    table = flexmbs.sweep(
        examples / "slider_crank.toml",
        variants(),
        {"peak_deflection": flexmbs.peak_abs("rod-mid"), "final_angle": flexmbs.final("crank-angle")},
        client="local",
        n_workers=2,
        results_dir=tmp_path / "sweep",
        cache=tmp_path / "cache",
    )
    assert len(table) == 9
    assert list(table["case"]) == list(range(9))
    errors = list(table["error"])
    # The invalid diameter fails in its row, with the validation's located message; the other
    # eight ran.
    assert all(e is None for e in errors[:8]), errors
    assert "sections[0].d" in errors[8] or "d" in errors[8]
    assert math.isnan(table["peak_deflection"][8])
    peaks = np.array(table["peak_deflection"][:8], dtype=float)
    assert np.all(np.isfinite(peaks)) and np.all(peaks > 0)
    # A thinner rod bends more (at both speeds), and a faster crank bends it more.
    by_d = peaks.reshape(4, 2)
    assert np.all(np.diff(by_d[:, 1]) < 0) and np.all(np.diff(by_d[:, 0]) < 0)
    assert np.all(by_d[:, 1] > by_d[:, 0])
    np.testing.assert_allclose(table["final_angle"][:8], [0.042 * s for s in [120.0, 150.0] * 4], rtol=1e-9)
    # Four diameters: four reductions in the shared cache, each used by the two speeds.
    assert len(list((tmp_path / "cache").glob("*.rbody"))) == 4
    # Each case wrote its own results folder.
    assert (tmp_path / "sweep" / "case-0000" / "run-up" / "rod-mid.csv").is_file()


def test_serial_sweep_gives_the_same_rows(examples, tmp_path):
    cases = variants()[:2] + variants()[-1:]
    table = flexmbs.sweep(
        examples / "slider_crank.toml",
        cases,
        {"peak_deflection": flexmbs.peak_abs("rod-mid")},
        client=None,
        results_dir=tmp_path / "serial",
        cache=tmp_path / "cache",
        as_pandas=False,
    )
    assert isinstance(table, dict)
    assert table["error"][0] is None and table["error"][2] is not None
    # The same case in the distributed sweep of the previous test gives the same number; here,
    # compared with a run of the same variant through Study.
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    study.update(cases[0])
    peak = np.max(np.abs(study.run(results_dir=tmp_path / "one", cache=tmp_path / "cache").sensor("rod-mid").values))
    assert table["peak_deflection"][0] == peak
