"""Studies from Python: values by key path with the program's validation and located errors,
runs whose results equal the program's to round-off, results folders and the cache."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

import flexmbs


def read_csv(path):
    """A sensor CSV of a results folder: header, then rows of numbers."""
    with open(path) as f:
        header = f.readline().strip().split(",")
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def untimed(value):
    """A summary without its timings (keys with "seconds" in their name), which differ by run,
    and without `from_cache`."""
    if isinstance(value, dict):
        return {k: untimed(v) for k, v in value.items() if "seconds" not in k and k != "from_cache"}
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return value


def test_get_and_set_values_by_key_path(examples):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    assert study["sections.rod.d"] == 0.006
    assert study["parts.segment.reduction.modes"] == 2
    assert study.get("materials[0].E") == 200e9
    assert study["drivers.crank-speed.function"] == {"type": "constant-speed", "speed": 150.0}
    study["parts.segment.reduction.modes"] = 3
    study["sections.rod.d"] = np.float64(0.005)
    study.set("drivers.crank-speed.function.speed", 120)
    assert study["parts.segment.reduction.modes"] == 3
    assert study["sections.rod.d"] == 0.005
    assert study["drivers.crank-speed.function.speed"] == 120
    # The text keeps its comments and shows the new values.
    assert "# Planar flexible slider-crank" in study.text
    assert "d = 0.005" in study.text
    assert study.analyses == ["run-up"]
    assert study.parts == ["segment"]


def test_a_refused_value_is_located_and_not_kept(examples):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    with pytest.raises(flexmbs.StudyError) as e:
        study["materials.steel.E"] = -1.0
    err = e.value
    assert isinstance(err, flexmbs.FlexmbsError)
    assert err.file.endswith("slider_crank.toml")
    assert err.key == "materials[0].E"
    # The line and column of the value in the study text as it would be.
    line = [i + 1 for i, l in enumerate(study.text.splitlines()) if l.startswith("E = ")][0]
    assert err.line == line and err.column == 5
    assert len(err.errors) >= 1 and err.errors[0]["message"]
    assert "E" in str(err)
    # Not kept: the study still has its own value and is valid.
    assert study["materials.steel.E"] == 200e9
    study.validate()
    # Several values that are only valid together; a failure keeps none of them.
    with pytest.raises(flexmbs.StudyError):
        study.update({"parts.segment.reduction.modes": 4, "sections.rod.d": -0.006})
    assert study["parts.segment.reduction.modes"] == 2
    study.update({"parts.segment.reduction.modes": 4, "sections.rod.d": 0.007})
    assert study["sections.rod.d"] == 0.007


def test_key_paths_that_lead_nowhere(examples):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    with pytest.raises(flexmbs.KeyPathError) as e:
        study["sections.nope.d"]
    assert e.value.path == "sections.nope.d"
    with pytest.raises(flexmbs.KeyPathError):
        study["parts[7].reduction"]
    with pytest.raises(TypeError):
        study["sections.rod.d"] = object()


def test_invalid_files_and_texts_raise_located_errors(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[study]\ntitle = "x"\n\n[[materials]]\nname = "steel"\nE = "stiff"\nnu = 0.3\nrho = 7850.0\n')
    with pytest.raises(flexmbs.StudyError) as e:
        flexmbs.Study.load(bad)
    assert e.value.file == str(bad) and e.value.line == 6
    with pytest.raises(flexmbs.StudyError) as e:
        flexmbs.Study.from_toml("[study\n", base_dir=tmp_path, name="typed.toml")
    assert e.value.file.endswith("typed.toml") and e.value.line == 1


def test_run_equals_the_program_to_round_off(examples, cli, tmp_path):
    # The slider-crank over 0.01 s (100 steps): the program and Python on the same study file.
    study_file = examples / "slider_crank.toml"
    cli("run", study_file, "--t-end", "0.01", "--out", tmp_path / "cli", cwd=examples)
    study = flexmbs.Study.load(study_file)
    res = study.run(t_end=0.01, results_dir=tmp_path / "py")
    a = res["run-up"]
    assert a.kind == "dynamic"
    for name in ["rod-mid", "slider", "crank-angle", "drive-torque", "energy"]:
        s = a.sensor(name)
        header, table = read_csv(tmp_path / "cli" / "run-up" / f"{name}.csv")
        assert header == ["t [s]", *s.labels]
        # The same computation in the same library: equal to the last bit, which the CSV's
        # shortest round-trip numbers keep.
        np.testing.assert_array_equal(s.time, table[:, 0])
        np.testing.assert_array_equal(s.values, table[:, 1:])
        # The Python run wrote the same folder.
        _, own = read_csv(tmp_path / "py" / "run-up" / f"{name}.csv")
        np.testing.assert_array_equal(own, table)
    s = a.sensor("rod-mid")
    assert s.units == ["m"] and len(s.time) == 101
    assert res.summary["status"] == "complete"
    cli_summary = json.loads((tmp_path / "cli" / "summary.json").read_text())
    assert [x["name"] for x in res.summary["analyses"]] == [x["name"] for x in cli_summary["analyses"]]
    # The same results in both summaries, but for the timings and where the rod came from:
    # the program reduced it, Python found it in the cache the program filled.
    assert untimed(a.summary["results"]) == untimed(cli_summary["analyses"][0]["results"])
    assert a.summary["results"]["model"]["reductions"][0]["from_cache"] is True
    assert cli_summary["analyses"][0]["results"]["model"]["reductions"][0]["from_cache"] is False


def test_linearized_frequencies_and_mode_labels(examples, cli, tmp_path):
    study_file = examples / "four_bar.toml"
    study = flexmbs.Study.load(study_file)
    name = [a for a in study.analyses if a.startswith("linearized")][0]
    # The linearised analysis starts from the equilibrium before it, which runs first.
    res = study.run(analysis=name, results_dir=tmp_path / "py")
    a = res[name]
    f = a.frequencies
    labels = a.mode_labels
    assert f is not None and len(f) >= 1 and np.all(np.diff(f) >= 0)
    assert len(labels) == len(f)
    cli("run", study_file, "--out", tmp_path / "cli", cwd=examples)
    header, table = read_csv(tmp_path / "cli" / name / "frequencies.csv")
    col = [i for i, h in enumerate(header) if "[Hz]" in h][0]
    np.testing.assert_allclose(f, table[:, col], rtol=1e-14)


def test_the_cache_is_shared_with_the_program(examples, cli, tmp_path):
    study_file = examples / "slider_crank.toml"
    cli("reduce", study_file, cwd=examples)
    cached = sorted((examples / ".flexmbs-cache").glob("*.rbody"))
    assert len(cached) == 1
    stamp = cached[0].stat().st_mtime_ns
    res = flexmbs.Study.load(study_file).run(t_end=0.001, results_dir=tmp_path / "py")
    assert any("cache" in m for m in res.messages), res.messages
    assert sorted((examples / ".flexmbs-cache").glob("*.rbody")) == cached
    assert cached[0].stat().st_mtime_ns == stamp
    # A changed reduction setting is a new cache entry.
    study = flexmbs.Study.load(study_file)
    study["parts.segment.reduction.modes"] = 3
    study.run(t_end=0.001, results_dir=tmp_path / "py3")
    assert len(list((examples / ".flexmbs-cache").glob("*.rbody"))) == 2


def test_study_from_text_takes_relative_paths_from_base_dir(examples, tmp_path):
    text = (examples / "slider_crank.toml").read_text()
    study = flexmbs.Study.from_toml(text, base_dir=examples, name="copy.toml")
    assert study.path.endswith("copy.toml")
    res = study.run(t_end=0.001)
    assert res.results_dir.startswith(str(examples))
    assert math.isfinite(res.sensor("rod-mid").values[-1, 0])
    # A sensor or an analysis the results do not hold: one exception class, a KeyError too,
    # with the close names.
    for lookup in (lambda: res.sensor("rod-mdi"), lambda: res.sensor("rod-mdi", analysis="run-up")):
        with pytest.raises(flexmbs.UnknownNameError) as e:
            lookup()
        assert isinstance(e.value, KeyError) and isinstance(e.value, flexmbs.FlexmbsError)
        assert "did you mean 'rod-mid'?" in str(e.value), str(e.value)
        assert e.value.name == "rod-mdi" and e.value.what == "sensor" and e.value.matches == ["rod-mid"]
    with pytest.raises(flexmbs.UnknownNameError) as e:
        res.sensor("rod-mid", analysis="run-pu")
    assert e.value.what == "analysis" and "did you mean 'run-up'?" in str(e.value)


def test_an_unknown_analysis_is_one_exception_with_the_close_names(examples):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    for call in (lambda: study.run(analysis="run-pu"), lambda: study.simulation(analysis="run-pu")):
        with pytest.raises(flexmbs.UnknownNameError) as e:
            call()
        err = e.value
        assert isinstance(err, KeyError) and isinstance(err, flexmbs.FlexmbsError)
        assert str(err).startswith("unknown analysis 'run-pu'; did you mean 'run-up'?"), str(err)
        assert err.name == "run-pu" and err.what == "analysis"
        assert err.matches == ["run-up"] and err.defined == study.analyses
    # A Simulation's sensors alike.
    sim = study.simulation()
    with pytest.raises(flexmbs.UnknownNameError) as e:
        sim.sensor("slidr")
    assert e.value.matches == ["slider"] and "did you mean 'slider'?" in str(e.value)


def test_keys_are_removed_and_tables_replaced(examples):
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    # An optional key removed; the default acts.
    del study["analyses.run-up.rho_inf"]
    with pytest.raises(flexmbs.KeyPathError):
        study["analyses.run-up.rho_inf"]
    # A key the study needs: refused at its table, located, and kept.
    with pytest.raises(flexmbs.StudyError) as e:
        del study["sections.rod.d"]
    assert e.value.file.endswith("slider_crank.toml") and e.value.key.startswith("sections[0]")
    assert study["sections.rod.d"] == 0.006
    # A path that leads nowhere.
    with pytest.raises(flexmbs.KeyPathError) as e:
        del study["sections.rdo"]
    assert "did you mean 'rod'" in str(e.value)
    # A dict replaces the whole table: the section given by `d` switched to one given by values
    # (key by key, `d` and `A` together would be refused).
    values = {"name": "rod", "shape": "values", "A": 2.8e-5, "Iy": 6.4e-11, "Iz": 6.4e-11, "J": 1.3e-10}
    study["sections.rod"] = values
    assert study["sections.rod"] == values
    # Re-validated like any set: a refused table is located and not kept.
    with pytest.raises(flexmbs.StudyError) as e:
        study["sections.rod"] = {"name": "rod", "shape": "circle", "d": -1.0}
    assert e.value.key == "sections[0].d", e.value.key
    assert study["sections.rod"] == values


def test_an_equilibrium_that_stops_says_the_load_factor(examples, tmp_path):
    # The elastica under a tip load 1e10 times its own: Newton's first correction bends the
    # clamped segment so far that its floating frame is lost, and load stepping gives up
    # (under a million times its load the equilibrium converges, stretched 24-fold).
    # An equilibrium says where in its own terms: a load factor, no time.
    study = flexmbs.Study.load(examples / "elastica.toml")
    study["loads.P.force"] = [0.0, 3.0e10, 0.0]
    with pytest.raises(flexmbs.SolveError) as e:
        study.run(results_dir=tmp_path / "res")
    err = e.value
    assert err.time is None
    assert err.load_factor is not None and 0.0 < err.load_factor < 1.0
    assert err.step is not None and err.step >= 1
    assert f"at load factor {err.load_factor:.6f} (step {err.step})" in str(err)
    assert "t = " not in str(err)
    # Located at the body whose frame was lost.
    assert err.key.startswith("bodies[") and err.line is not None



def test_study_keys_are_the_declarations_the_validator_and_the_docs_use(examples):
    """`study_keys()` lists the keys the study crate declares once: the keys it gives a
    circular section are the ones the validator names when it refuses another key there, and
    the docs' key table of the sections names every key it lists."""
    keys = flexmbs.study_keys("sections")
    assert all(k["table"] == "sections" for k in keys)
    assert len(flexmbs.study_keys()) > len(keys)
    d = next(k for k in keys if k["name"] == "d")
    assert d["unit"] == "m" and d["kinds"] == ["circle"] and d["required"] and d["doc"]
    circle = [k["name"] for k in keys if not k["kinds"] or "circle" in k["kinds"]]

    # A key of the table that a circle does not take is refused with the circle's keys; a
    # key the table does not have at all, with every key of the table.
    text = (examples / "slider_crank.toml").read_text()
    with pytest.raises(flexmbs.StudyError) as refused:
        flexmbs.Study.from_toml(text.replace("d = 0.006", "d = 0.006\nb = 0.01", 1), base_dir=examples)
    assert "key `b` does not apply to a circle section" in str(refused.value)
    assert f"(its keys: {', '.join(circle)})" in str(refused.value)
    with pytest.raises(flexmbs.StudyError) as unknown:
        flexmbs.Study.from_toml(text.replace("d = 0.006", "d = 0.006\ndiameter = 0.006", 1), base_dir=examples)
    assert "diameter" in str(unknown.value)
    for k in keys:
        assert f"`{k['name']}`" in str(unknown.value)

    docs = (Path(__file__).resolve().parents[3] / "docs" / "study-file.md").read_text()
    table = docs.split("<!-- keys:sections begin -->")[1].split("<!-- keys:sections end -->")[0]
    for k in keys:
        assert f"| `{k['name']}` |" in table
