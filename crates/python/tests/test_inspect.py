"""`flexmbs.inspect`: what a reduced body holds and its physical checks, the report of
`flexmbs inspect` (one library function behind both), for .rbody files and for matrices from
another code (Matrix Market) reduced with the keys of a study's [bodies.matrices]."""

import re

import pytest

import flexmbs


@pytest.fixture
def beam(examples):
    """examples/cantilever.toml's beam (steel, 2 m, 20 elements), 4 fixed-interface modes."""
    study = flexmbs.Study.load(examples / "cantilever.toml")
    return dict(study.reduce())["beam"]


def matrix_market(path, A):
    n = A.shape[0]
    entries = [(i, j, float(A[i, j])) for j in range(n) for i in range(n) if A[i, j] != 0.0]
    lines = ["%%MatrixMarket matrix coordinate real general", f"{n} {n} {len(entries)}"]
    lines += [f"{i + 1} {j + 1} {v!r}" for i, j, v in entries]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def matrices(examples, tmp_path):
    """The beam condensed to its two end nodes (no modes) as matrices from another code: K.mtx,
    M.mtx (12 x 12, six dofs per node) and the node table, in tmp_path."""
    study = flexmbs.Study.load(examples / "cantilever.toml")
    study["parts.beam.reduction.modes"] = 0
    body = dict(study.reduce())["beam"]
    matrix_market(tmp_path / "K.mtx", body.K_CB)
    matrix_market(tmp_path / "M.mtx", body.M_CB)
    (tmp_path / "nodes.txt").write_text("0 0 0\n2 0 0\n")
    return tmp_path, body


def test_the_report_is_the_one_flexmbs_inspect_prints(beam, cli, tmp_path):
    path = tmp_path / "beam.rbody"
    beam.save(path)
    found = flexmbs.inspect(path, excitation_hz=20.0)
    assert found.report == cli("inspect", path, "--excitation-hz", "20").stdout
    assert str(found) == found.report and found.passed and found.failed_checks == 0
    assert "CB coordinates: 16 = 6 x 2 interfaces + 4 fixed-interface modes" in found.report
    # The first bending mode (26.6 Hz) is below sqrt(2) times the excitation: a warning.
    assert "modes near or below the excitation 2.0000e1 Hz" in found.report
    assert "physical checks: passed" in found.report


def test_matrices_from_another_code_are_reduced_with_the_study_keys(matrices, cli):
    folder, body = matrices
    keys = dict(mass=folder / "M.mtx", nodes=folder / "nodes.txt", dofs_per_node=6, interfaces={"root": 0, "tip": 1}, modes=0)
    found = flexmbs.inspect(folder / "K.mtx", **keys)
    printed = cli(
        "inspect", "K.mtx", "--mass", "M.mtx", "--nodes", "nodes.txt", "--dofs-per-node", "6",
        "--interface", "root=0", "--interface", "tip=1", "--modes", "0", cwd=folder,
    ).stdout
    # The same report but for the paths, given here as absolute ones.
    assert found.report.replace(f"{folder}/", "") == printed
    mass = float(re.search(r"\n  mass +(\S+) kg", found.report).group(1))
    # The report prints 7 significant digits.
    assert found.passed and mass == pytest.approx(body.mass, rel=1e-6)


def test_a_body_failing_its_checks_is_reported_not_raised(matrices):
    folder, body = matrices
    M = body.M_CB.copy()
    M[0, 0] = -M[0, 0]
    matrix_market(folder / "M.mtx", M)
    found = flexmbs.inspect(folder / "K.mtx", mass=folder / "M.mtx", nodes=folder / "nodes.txt", dofs_per_node=6, interfaces={"root": 0, "tip": 1}, modes=0)
    assert not found.passed and found.failed_checks > 0
    assert "physical checks: FAILED, studies refuse this body" in found.report


def test_wrong_input_raises_with_the_file_or_the_keyword(beam, matrices, tmp_path):
    with pytest.raises(flexmbs.ReducedBodyFileError) as e:
        flexmbs.inspect(tmp_path / "missing.rbody")
    assert e.value.path.endswith("missing.rbody")
    beam.save(tmp_path / "beam.rbody")
    with pytest.raises(ValueError, match="mass= is for a Matrix Market stiffness"):
        flexmbs.inspect(tmp_path / "beam.rbody", mass="M.mtx")
    with pytest.raises(ValueError, match="needs a positive frequency"):
        flexmbs.inspect(tmp_path / "beam.rbody", excitation_hz=0.0)
    folder, _ = matrices
    with pytest.raises(ValueError, match="needs mass="):
        flexmbs.inspect(folder / "K.mtx", nodes=folder / "nodes.txt")
    # A matrix with a bad value: the file and line.
    (folder / "M.mtx").write_text("%%MatrixMarket matrix coordinate real general\n12 12 1\n1 1 nan\n")
    with pytest.raises(flexmbs.ReducedBodyFileError, match="M.mtx, line 3"):
        flexmbs.inspect(folder / "K.mtx", mass=folder / "M.mtx", nodes=folder / "nodes.txt", dofs_per_node=6, interfaces={"root": 0, "tip": 1}, modes=0)
