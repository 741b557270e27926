"""Reduced bodies from Python: reduction through a study, .rbody files, matrices, mass data,
fixed-interface modes."""

import math

import numpy as np
import pytest

import flexmbs


@pytest.fixture
def segment(examples):
    """The slider-crank's rod segment (steel, d = 6 mm, 75 mm, 4 Euler-Bernoulli elements, 2
    fixed-interface modes), reduced from Python."""
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    bodies = dict(study.reduce())
    return bodies["segment"]


def test_reduce_and_read_the_body(segment):
    b = segment
    assert b.name == "segment"
    assert b.interface_names == ["a", "b"]
    assert [i["node"] for i in b.interfaces] == [0, 1]
    # A generated mesh has no file numbers.
    assert [i["node_label"] for i in b.interfaces] == [None, None]
    np.testing.assert_array_equal(b.interfaces[1]["position"], [0.075, 0.0, 0.0])
    assert b.n_modes == 2 and b.n_coordinates == 14
    K, M = b.K_CB, b.M_CB
    assert K.shape == (14, 14) and M.shape == (14, 14)
    # Symmetric to round-off of the products V^T K V (1e-12 of the largest entry).
    assert np.abs(K - K.T).max() <= 1e-12 * np.abs(K).max()
    assert np.abs(M - M.T).max() <= 1e-12 * np.abs(M).max()
    # Mass data against the section: rho A L (the consistent mass integrates it exactly).
    d, L, rho = 0.006, 0.075, 7870.0
    assert b.mass == pytest.approx(rho * math.pi * d**2 / 4 * L, rel=1e-12)
    np.testing.assert_allclose(b.center_of_mass, [L / 2, 0, 0], atol=1e-15)
    # Transverse inertia about the centre of mass: m L^2 / 12 plus the rotary inertia of the
    # section, m d^2 / 16 (the elements' consistent mass integrates both exactly).
    m = b.mass
    assert b.inertia[1, 1] == pytest.approx(m * L**2 / 12 + m * d**2 / 16, rel=1e-9)


def test_fixed_interface_modes_against_the_clamped_beam(segment):
    b = segment
    w = b.fixed_interface_omega
    f = b.fixed_interface_frequencies
    np.testing.assert_allclose(f, w / (2 * math.pi), rtol=1e-15)
    # The modal block of the CB matrices: mass-normalised modes, K_CB = diag(omega^2) there.
    K, M = b.K_CB[12:, 12:], b.M_CB[12:, 12:]
    np.testing.assert_allclose(M, np.eye(2), atol=1e-10)
    np.testing.assert_allclose(np.diag(K), w**2, rtol=1e-10)
    # The first fixed-interface mode is the clamped-clamped beam's (a pair: y and z bending of
    # the round section): omega = 4.7300^2 sqrt(EI / (rho A)) / L^2. Four cubic elements are
    # within 0.5 % of it (the discretisation error of the first mode).
    E, d, L, rho = 200e9, 0.006, 0.075, 7870.0
    A, I = math.pi * d**2 / 4, math.pi * d**4 / 64
    exact = 4.730041**2 * math.sqrt(E * I / (rho * A)) / L**2
    assert w[0] == pytest.approx(exact, rel=5e-3)
    assert w[1] == pytest.approx(w[0], rel=1e-9)
    # Mode shapes on the mesh: nodes x 6 dof slots x modes, the last columns of the CB basis.
    shapes = b.mode_shapes
    assert shapes.shape == (5, 6, 2)
    basis = b.cb_basis
    np.testing.assert_array_equal(shapes[:, :, 0].reshape(-1), basis[:, 12])
    # Fixed interfaces: the modes vanish at the interface nodes (both ends), not inside.
    for i in b.interfaces:
        assert np.abs(shapes[i["node"]]).max() == 0.0
    assert np.abs(shapes).max() > 0.0
    nodes = b.mesh_nodes
    np.testing.assert_allclose(np.sort(nodes[:, 0]), np.linspace(0, L, 5), atol=1e-15)
    inv = b.invariants
    assert inv["S_t"].shape == (3, 14) and inv["S_bar"].shape == (9, 14, 14) and inv["Phi_com"].shape == (6, 14)
    assert b.geometric_stiffness is None


def test_save_and_load_round_trip(segment, tmp_path):
    path = tmp_path / "segment.rbody"
    segment.save(path)
    again = flexmbs.ReducedBody.load(path)
    assert again == segment
    np.testing.assert_array_equal(again.K_CB, segment.K_CB)
    np.testing.assert_array_equal(again.mode_shapes, segment.mode_shapes)


def test_damaged_and_missing_files_raise_with_their_path(segment, tmp_path):
    path = tmp_path / "segment.rbody"
    segment.save(path)
    data = bytearray(path.read_bytes())
    data[-5] ^= 0xFF
    bad = tmp_path / "damaged.rbody"
    bad.write_bytes(bytes(data))
    with pytest.raises(flexmbs.ReducedBodyFileError) as e:
        flexmbs.ReducedBody.load(bad)
    assert e.value.path == str(bad)
    assert "checksum" in str(e.value)
    with pytest.raises(flexmbs.ReducedBodyFileError) as e:
        flexmbs.ReducedBody.load(tmp_path / "missing.rbody")
    assert isinstance(e.value, flexmbs.FlexmbsError)
    assert e.value.path.endswith("missing.rbody")


def test_the_body_equals_the_one_flexmbs_reduce_writes(examples, segment, cli):
    cli("reduce", examples / "slider_crank.toml", cwd=examples)
    written = flexmbs.ReducedBody.load(examples / "slider_crank-results" / "segment.rbody")
    assert written == segment


def test_the_inertia_correction_is_a_reduction_key(examples):
    """`inertia_correction = true` in a part's reduction (the static correction for the
    interfaces' inertia) appends 6 vectors per interface after the fixed-interface modes; the
    coordinates before them, and their matrices, are those of the body without it."""
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    plain = dict(study.reduce())["segment"]
    study["parts.segment.reduction.inertia_correction"] = True
    corrected = dict(study.reduce())["segment"]
    assert plain.n_coordinates == 14 and corrected.n_coordinates == 26
    # The same factor, modes and projections: the appended columns leave the leading block
    # untouched, bit for bit.
    for A, B in [(corrected.K_CB, plain.K_CB), (corrected.M_CB, plain.M_CB)]:
        np.testing.assert_array_equal(A[:14, :14], B)
    # The appended vectors carry mass and stiffness of their own.
    assert np.abs(corrected.M_CB[14:, 14:]).max() > 0.0 and np.abs(corrected.K_CB[14:, 14:]).max() > 0.0


def test_planar_is_a_reduction_key(examples):
    """`planar = true` in a part's reduction (the part reduced with the out-of-plane dofs of
    its interior supported): the same coordinates, every mode bends in the xy-plane, and the
    out-of-plane dofs of the interfaces do not couple to the in-plane ones or to the modes. The
    round rod's 3D reduction keeps one in-plane and one out-of-plane mode of equal frequency;
    the planar one the first two in-plane modes."""
    study = flexmbs.Study.load(examples / "slider_crank.toml")
    spatial = dict(study.reduce())["segment"]
    study["parts.segment.reduction.planar"] = True
    planar = dict(study.reduce())["segment"]
    assert planar.n_coordinates == spatial.n_coordinates == 14
    w3, w2 = spatial.fixed_interface_omega, planar.fixed_interface_omega
    assert abs(w3[1] - w3[0]) < 1e-6 * w3[0]
    assert abs(w2[0] - w3[0]) < 1e-9 * w3[0] and w2[1] > 2.5 * w2[0]
    out = [6 * k + d for k in range(2) for d in (2, 3, 4)]
    inside = [i for i in range(14) if i not in out]
    for A in (planar.K_CB, planar.M_CB):
        assert np.abs(A[np.ix_(out, inside)]).max() == 0.0
    # Mode shapes on the mesh: no out-of-plane component.
    shapes = planar.mode_shapes
    assert shapes is not None and np.abs(shapes[:, 2:5, :]).max() == 0.0
