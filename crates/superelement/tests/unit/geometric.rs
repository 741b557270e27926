//! Geometric stiffening: the strain energy gains $U_3 = \tfrac12\sum_k q_k\,\mathbf q^T\mathbf G_k\mathbf q$
//! and $U_4 = \tfrac12\mathbf b^T\mathbf K_{CB}^+\mathbf b$ (`superelement::GeometricStiffness`). With a synthetic $\mathbf G$ (random symmetric
//! matrices whose tangent is about as large as $\mathbf K_{CB}$ at the test deformations, so
//! that a wrong term cannot hide) on every fixture, and with the $\mathbf G$ of the reduction
//! when it provides one:
//!
//! * the elastic force is the gradient of `strain_energy` (central differences through exp);
//! * $\mathbf K_t$, $\mathbf C_t$, $\mathbf M$ match central differences of the residual on deformed, rotated,
//!   moving states (`fd_tangent::check_tangents`, the one FD check of the residual);
//! * a rigid motion of a deformed body leaves $\mathbf q^{jj}$ and the body-axis elastic force
//!   unchanged, and the elastic forces stay self-equilibrated;
//! * a body without $\mathbf G$ and one with $\mathbf G = \mathbf 0$ give bit-identical evaluations (the
//!   geometric path adds exact zeros; the path without $\mathbf G$ is the former code).

use super::common::*;
use super::fd_tangent::check_tangents;
use faer::Mat;
use nalgebra::Point3;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use reduction::{CbSettings, DenseMatrix, ModeSelection, ReducedBody};
use std::sync::OnceLock;
use superelement::compressed::{clean, coordinate_weights};
use superelement::testing::fixtures;
use superelement::testing::{
    check_jacobian, compression, coordinate_scales, perturb_state, synthetic_geometric_stiffness, test_state, StateSpec,
};
use superelement::{Damping, MassVariant, Superelement, SuperelementError};

/// Relative deformation of the test states (as `StateSpec::moving`).
const DEFORMATION: f64 = 0.02;

/// `body` with a synthetic geometric stiffness whose tangent is about `gamma` K_CB at the
/// deformation of the test states of `frame`'s superelement.
fn with_synthetic_g(body: &ReducedBody, frame: superelement::FrameChoice, gamma: f64, seed: u64) -> ReducedBody {
    let se = superelement(body, frame, MassVariant::Exact);
    let mut b = body.clone();
    b.geometric_stiffness = Some(synthetic_geometric_stiffness(
        body,
        &coordinate_scales(&se, DEFORMATION),
        gamma,
        seed,
    ));
    b
}

/// The bodies with a geometric stiffness to test: every fixture with a synthetic one whose
/// tangent is about `gamma` K_CB at the test deformation (`DEFORMATION`), and a beam and a
/// hex8 block with the geometric stiffness of their reduction.
fn synthetic_cases(gamma: f64) -> Vec<(&'static str, ReducedBody, superelement::FrameChoice)> {
    let mut cases = Vec::new();
    for (i, fx) in all_fixtures().into_iter().enumerate() {
        for frame in frame_choices(&fx.body) {
            cases.push((fx.name, with_synthetic_g(&fx.body, frame, gamma, 100 + i as u64), frame));
        }
    }
    for (name, body) in real_bodies() {
        for frame in frame_choices(body) {
            cases.push((name, body.clone(), frame));
        }
    }
    cases
}

/// The skew beam of `beam_dynamic` (8 elements, 4 modes; and 2 modes with the inertia
/// correction) and the hex8 block (2 modes) reduced with `geometric_stiffening`.
fn real_bodies() -> &'static [(&'static str, ReducedBody)] {
    static B: OnceLock<Vec<(&'static str, ReducedBody)>> = OnceLock::new();
    B.get_or_init(|| {
        let settings = |m| CbSettings {
            geometric_stiffening: true,
            ..CbSettings::new(ModeSelection::Count(m))
        };
        let (_, _, beam) = fixtures::straight_beam_with(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.45),
            8,
            settings(4),
            false,
        );
        let (_, _, block) = fixtures::solid_block_with(settings(2));
        // Two modes and the static correction for the interfaces' inertia (the configuration
        // that converges monotonically in the modes): G over 24 coordinates, 12 of them
        // correction vectors with their own axial stress.
        let (_, _, corrected) = fixtures::straight_beam_with(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.45),
            8,
            CbSettings {
                inertia_correction: true,
                ..settings(2)
            },
            false,
        );
        assert!(beam.geometric_stiffness.is_some() && block.geometric_stiffness.is_some());
        assert!(corrected.attachment_modes > 0);
        vec![
            ("beam-with-G", beam),
            ("block-with-G", block),
            ("beam-with-G-inertia-corrected", corrected),
        ]
    })
}

/// F = K_CB^+ of the real bodies: K F K = K and F K F = F (the pseudo-inverse on the
/// complement of the rigid modes).
#[test]
fn compliance_is_the_pseudo_inverse_of_k_cb() {
    for (name, body) in real_bodies() {
        let se = superelement(body, superelement::FrameChoice::CenterOfMass, MassVariant::Exact);
        let K = se.k_cb();
        let F = se.geometric_stiffness().unwrap().compliance();
        let KFK = K * F * K;
        let FKF = F * K * F;
        let n = se.n_coordinates();
        let big = |A: &Mat<f64>| {
            (0..n)
                .flat_map(|j| (0..n).map(move |i| (i, j)))
                .map(|(i, j)| A[(i, j)].abs())
                .fold(0.0, f64::max)
        };
        let dK = big(&Mat::from_fn(n, n, |i, j| KFK[(i, j)] - K[(i, j)]));
        let dF = big(&Mat::from_fn(n, n, |i, j| FKF[(i, j)] - F[(i, j)]));
        assert!(
            dK < 1e-9 * big(K) && dF < 1e-9 * big(F),
            "{name}: K F K - K {dK:e}, F K F - F {dF:e}"
        );
    }
}

/// U_3 + U_4 straight from the reduced body's matrices (independent of the superelement's
/// storage): U_3 = 1/2 sum_k q_k q^T G_k q, U_4 = 1/2 b^T F b with b_m = 1/2 q^T G_m q and
/// F = K_CB^+ as the superelement holds it; and the sum of the magnitudes of their terms, the
/// scale of their round-off (the terms cancel where stiff coordinates, such as static
/// correction vectors, carry large stresses).
fn geometric_energy_reference(G: &[DenseMatrix], F: &Mat<f64>, q: &[f64]) -> (f64, f64, f64) {
    let n = q.len();
    let (b, b_abs): (Vec<f64>, Vec<f64>) = G
        .iter()
        .map(|Gm| {
            let (mut s, mut a) = (0.0, 0.0);
            for i in 0..n {
                for j in 0..n {
                    let t = 0.5 * q[i] * Gm.data[i + n * j] * q[j];
                    s += t;
                    a += t.abs();
                }
            }
            (s, a)
        })
        .unzip();
    let U3: f64 = (0..n).map(|k| q[k] * b[k]).sum();
    let mut scale: f64 = (0..n).map(|k| (q[k] * b_abs[k]).abs()).sum();
    let mut U4 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let t = 0.5 * b[i] * F[(i, j)] * b[j];
            U4 += t;
            scale += (0.5 * b_abs[i] * F[(i, j)] * b_abs[j]).abs();
        }
    }
    (U3, U4, scale)
}

/// f_elastic = dU/dq with U = strain_energy (linear part plus U_3), by central differences
/// with exponential-map perturbations, on deformed rotated states; and U_3 itself against the
/// direct sum.
#[test]
fn elastic_force_is_the_gradient_of_the_strain_energy() {
    for (name, body, frame) in synthetic_cases(1.0) {
        let se = superelement(&body, frame, MassVariant::Exact);
        let linear = superelement(
            &ReducedBody {
                geometric_stiffness: None,
                ..body.clone()
            },
            frame,
            MassVariant::Exact,
        );
        let mut spec = StateSpec::moving(170.0, 13);
        spec.spin = 0.0;
        let (state, acc) = test_state(&se, &spec);
        let ev = se.evaluate(&state, &acc, &Vector3::zeros()).unwrap();
        let n = se.n_coordinates();
        let mut base = state.clone();
        base.frame = ev.frame;
        let kin = se.kinematics(&base).unwrap();
        let U_G = se.strain_energy(&kin) - linear.strain_energy(&kin);
        let F = se.geometric_stiffness().unwrap().compliance();
        // The G the superelement holds: the reduction's, without its round-off zeros when it
        // stores them compressed (`superelement::compressed`).
        let mut G: Vec<DenseMatrix> = body.geometric_stiffness.clone().unwrap();
        if compression(&se).geometric == Some(true) {
            let n = body.n_coordinates();
            let mut mats: Vec<Mat<f64>> = G
                .iter()
                .map(|Gk| Mat::from_fn(n, n, |i, j| Gk.data[i + n * j]))
                .collect();
            let c = coordinate_weights(&body);
            clean(&mut mats.iter_mut().collect::<Vec<_>>(), |k, i, j| c[i] * c[j] * c[k]);
            for (Gk, A) in G.iter_mut().zip(&mats) {
                for j in 0..n {
                    for i in 0..n {
                        Gk.data[i + n * j] = A[(i, j)];
                    }
                }
            }
        }
        let (U3, U4, scale) = geometric_energy_reference(&G, F, &kin.q_jj);
        assert!(
            (U_G - U3 - U4).abs() < 1e-12 * (scale + linear.strain_energy(&kin)),
            "{name} {frame}: U_3 + U_4 = {U_G:e}, direct sums {U3:e} + {U4:e} (terms up to {scale:e})"
        );
        // Both terms must matter at this deformation, or the test would not see them.
        let U2 = linear.strain_energy(&kin);
        assert!(
            U3.abs() > 1e-3 * U2 && U4.abs() > 1e-4 * U2,
            "{name} {frame}: U_3 {U3:e}, U_4 {U4:e} against {U2:e}"
        );
        let A = Mat::from_fn(1, n, |_, j| ev.f_elastic[j]);
        let rep = check_jacobian("dU/dq", A.as_ref(), &vec![1e-6; n], |d| {
            let s = perturb_state(&base, d);
            vec![se.strain_energy(&se.kinematics(&s).unwrap())]
        });
        assert!(rep.worst < 1e-6, "{name} {frame}: {rep}");
    }
}

/// The strain energy from an evaluation's workspace (`strain_energy_in`, the energy sensor's
/// path) equals `strain_energy` of the same configuration, with and without G, on a deformed,
/// moving body. Tolerance: the two sum the same terms in a different order (round-off of
/// sums of about n^2 terms of the size of U).
#[test]
fn strain_energy_from_the_workspace_equals_the_direct_one() {
    for (name, body, frame) in synthetic_cases(1.0) {
        let linear_body = ReducedBody {
            geometric_stiffness: None,
            ..body.clone()
        };
        for se in [
            superelement(&body, frame, MassVariant::Exact),
            superelement(&linear_body, frame, MassVariant::Exact),
        ] {
            let (state, acc) = test_state(&se, &StateSpec::moving(170.0, 13));
            let mut ws = se.workspace();
            let mut ev = superelement::Evaluation::zeros(se.n_coordinates());
            for tangents in [false, true] {
                if tangents {
                    se.evaluate_into(&state, &acc, &Vector3::zeros(), &mut ws, &mut ev)
                } else {
                    se.forces_into(&state, &acc, &Vector3::zeros(), &mut ws, &mut ev)
                }
                .unwrap();
                let direct = se.strain_energy(ws.kinematics());
                let from_ws = se.strain_energy_in(&ws);
                assert!(
                    (from_ws - direct).abs() <= 1e-12 * direct.abs(),
                    "{name} {frame}: {from_ws:e} against {direct:e}"
                );
                assert!(direct > 0.0);
            }
        }
    }
}

/// K_t, C_t, M of bodies with G against central differences: every fixture and frame choice,
/// both inertia variants, with gravity and Rayleigh damping (all force kinds at once), and
/// elastic only at a larger deformation (0.05, 2.5 times the one G is scaled for, with G 0.4
/// times as large: the geometric tangent is again about K_CB).
#[test]
fn tangents_match_fd() {
    let large = synthetic_cases(0.4);
    for (i, (name, body, frame)) in synthetic_cases(1.0).into_iter().enumerate() {
        let mass = VARIANTS[i % 2];
        let se = Superelement::new(&body, frame, mass, Damping::rayleigh(1.0, 1e-5)).unwrap();
        let (state, acc) = test_state(&se, &StateSpec::moving(120.0, 40 + i as u64));
        check_tangents(
            &se,
            &state,
            &acc,
            &gravity(),
            &format!("{name} {frame} {mass:?} with G"),
        );
        let se = superelement(&large[i].1, frame, MassVariant::Lumped);
        let mut spec = StateSpec::moving(30.0, 60 + i as u64);
        spec.spin = 0.0;
        spec.deformation = 0.05;
        let (state, acc) = test_state(&se, &spec);
        check_tangents(
            &se,
            &state,
            &acc,
            &Vector3::zeros(),
            &format!("{name} {frame} elastic only with G, deformation 0.05"),
        );
    }
}

/// A rigid motion (rotation Q, translation t) of a deformed body with G: q_jj and the body-axis
/// elastic force R_j^T f_el do not change, and the elastic forces balance (zero resultant force
/// and moment), since U depends on q_jj only.
#[test]
fn rigid_motion_leaves_the_local_elastic_force_unchanged() {
    let rotations = [
        (30.0, Vector3::new(1.0, 2.0, -0.5)),
        (120.0, Vector3::new(-0.3, 0.1, 1.0)),
        (179.9, Vector3::new(0.6, -0.8, 0.2)),
    ];
    for (name, body, frame) in synthetic_cases(1.0) {
        let se = superelement(&body, frame, MassVariant::Exact);
        let N = se.n_interfaces();
        let n = se.n_coordinates();
        let (state, _) = test_state(&se, &StateSpec::moving(30.0, 21));
        let ev = se.evaluate(&state, &vec![0.0; n], &Vector3::zeros()).unwrap();
        let local = |f: &[f64], R: &UnitQuaternion<f64>| -> Vec<Vector3<f64>> {
            (0..2 * N)
                .map(|b| R.inverse() * Vector3::new(f[3 * b], f[3 * b + 1], f[3 * b + 2]))
                .collect()
        };
        let f0 = local(&ev.f_elastic, &ev.frame.R);
        let scale = ev.f_elastic.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        for (angle, axis) in rotations {
            let Q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), f64::to_radians(angle));
            let t = Vector3::new(0.4, 2.0, -3.0);
            let moved = rigidly_moved(&state, &ev.frame, &Q, &t);
            let ev2 = se.evaluate(&moved, &vec![0.0; n], &Vector3::zeros()).unwrap();
            let dq = ev
                .q_jj
                .iter()
                .zip(&ev2.q_jj)
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
            assert!(dq < 1e-13, "{name} {frame}: q_jj changed by {dq:e}");
            let f2 = local(&ev2.f_elastic, &ev2.frame.R);
            for (b, (a, c)) in f0.iter().zip(&f2).enumerate() {
                assert!((a - c).norm() < 1e-11 * scale, "{name} {frame}: block {b}: {a} vs {c}");
            }
            let (F, Mo) = resultant(&ev2.f_elastic, &moved.r[..N]);
            assert!(
                F.norm() < 1e-10 * scale && Mo.norm() < 1e-9 * scale,
                "{name} {frame}: resultant {F} {Mo}"
            );
        }
    }
}

/// G = 0 gives bit-identical forces and tangents to a body without G: the geometric path only
/// adds exact zeros, so the tests of the linear body (and its figures) stay valid for both.
#[test]
fn zero_g_is_bit_identical_to_no_g() {
    for fx in all_fixtures() {
        let n = fx.body.n_coordinates();
        let mut zero = fx.body.clone();
        zero.geometric_stiffness = Some(vec![DenseMatrix::zeros(n, n); n]);
        for frame in frame_choices(&fx.body) {
            for mass in VARIANTS {
                let damping = Damping::rayleigh(0.5, 1e-5);
                let a = Superelement::new(&fx.body, frame, mass, damping.clone()).unwrap();
                let b = Superelement::new(&zero, frame, mass, damping).unwrap();
                assert!(a.geometric_stiffness().is_none() && b.geometric_stiffness().is_some());
                let (state, acc) = test_state(&a, &StateSpec::moving(120.0, 5));
                let ea = a.evaluate(&state, &acc, &gravity()).unwrap();
                let eb = b.evaluate(&state, &acc, &gravity()).unwrap();
                let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let mbits = |m: &Mat<f64>| {
                    (0..n)
                        .flat_map(|j| (0..n).map(move |i| m[(i, j)].to_bits()))
                        .collect::<Vec<_>>()
                };
                let what = format!("{} {frame} {mass:?}", fx.name);
                assert_eq!(bits(&ea.residual), bits(&eb.residual), "{what}: residual");
                assert_eq!(bits(&ea.f_elastic), bits(&eb.f_elastic), "{what}: f_elastic");
                assert_eq!(mbits(&ea.stiffness), mbits(&eb.stiffness), "{what}: K_t");
                assert_eq!(mbits(&ea.damping), mbits(&eb.damping), "{what}: C_t");
                assert_eq!(mbits(&ea.mass), mbits(&eb.mass), "{what}: M");
                let kin = a.kinematics(&state).unwrap();
                assert_eq!(
                    a.strain_energy(&kin).to_bits(),
                    b.strain_energy(&kin).to_bits(),
                    "{what}: U"
                );
            }
        }
    }
}

/// Malformed geometric stiffness: a wrong count, a wrong shape, a non-finite entry and an
/// asymmetric matrix each give `InvalidBody` naming the matrix.
#[test]
fn malformed_g_is_refused_with_a_named_error() {
    let body = &beam_static().body;
    let n = body.n_coordinates();
    let frame = superelement::FrameChoice::CenterOfMass;
    let check = |G: Vec<DenseMatrix>, needle: &str| {
        let mut b = body.clone();
        b.geometric_stiffness = Some(G);
        match Superelement::new(&b, frame, MassVariant::Exact, Damping::none()) {
            Err(SuperelementError::InvalidBody { body, what }) => {
                assert_eq!(body, b.name);
                assert!(what.contains(needle), "'{what}' does not say '{needle}'");
            }
            other => panic!("expected InvalidBody ({needle}), got {other:?}"),
        }
    };
    check(vec![DenseMatrix::zeros(n, n); n - 1], "expected one per CB coordinate");
    let mut G = vec![DenseMatrix::zeros(n, n); n];
    G[3] = DenseMatrix::zeros(n, n + 1);
    check(G, "G[3] is");
    let mut G = vec![DenseMatrix::zeros(n, n); n];
    G[2].data[5] = f64::NAN;
    check(G, "G[2] has a non-finite entry");
    let mut G = vec![DenseMatrix::zeros(n, n); n];
    G[7].data[1] = 1.0; // (1, 0) without (0, 1)
    check(G, "G[7] is not symmetric");
}
