//! Every tangent against central differences of its residual (one helper,
//! `superelement::testing::check_jacobian`, reporting the worst entry).
//!
//! States are deformed (2% of the body size, 0.02 rad, modal amplitudes alike), rotated by
//! 30, 120 and 170 degrees about a skew axis and moving (3 rad/s, nonzero accelerations);
//! rotations are perturbed through the exponential map, spatially.
//!
//! Tolerance: central differences with steps of 1e-6 (times the body size for positions)
//! have truncation errors ~1e-12 and round-off ~1e-16 |r| / (1e-6 |K|), about 1e-9 of an
//! entry's row or column scale here; a missing or wrong term of the tangent shows up at
//! 1e-4 or more. 1e-6 separates the two with margin on both sides.

use super::common::*;
use faer::Mat;
use nalgebra::{Matrix3, Vector3};
use reduction::ReducedBody;
use superelement::local_coordinates::{elastic_rotation, interface_displacement};
use superelement::so3;
use superelement::testing::{
    check_jacobian, coordinate_scales, perturb_state, perturb_velocity, test_state, FdReport, StateSpec,
};
use superelement::{BodyState, Damping, Frame, MassVariant, Superelement};

const TOL: f64 = 1e-6;
const ANGLES: [f64; 3] = [30.0, 120.0, 170.0];

/// Finite-difference steps for the superelement's coordinates: 1e-6 of the body size for
/// positions, 1e-6 rad, and 1e-6 of the modal amplitude scale for eta.
pub(super) fn steps(se: &Superelement) -> Vec<f64> {
    coordinate_scales(se, 1e-6)
}

pub(super) fn assert_ok(rep: FdReport, what: &str) {
    if std::env::var_os("SUPERELEMENT_FD_VERBOSE").is_some() {
        eprintln!("{what}: {rep}");
    }
    assert!(rep.worst <= TOL, "{what}\n{rep}");
}

/// K_t, C_t and M of `se` at `state` against central differences of the residual.
pub(super) fn check_tangents(se: &Superelement, state: &BodyState, acc: &[f64], g: &Vector3<f64>, what: &str) {
    let ev = se.evaluate(state, acc, g).unwrap();
    let mut base = state.clone();
    base.frame = ev.frame;
    let h = steps(se);
    let rep = check_jacobian("K_t", ev.stiffness.as_ref(), &h, |d| {
        se.evaluate(&perturb_state(&base, d), acc, g).unwrap().residual
    });
    assert_ok(rep, what);
    // The residual is exactly quadratic in the velocities and linear in the accelerations,
    // so central differences are exact there for any step: unit steps keep the round-off of
    // the (large) elastic part of the residual out of these two checks.
    let unit = vec![1.0; h.len()];
    let rep = check_jacobian("C_t", ev.damping.as_ref(), &unit, |d| {
        se.evaluate(&perturb_velocity(&base, d), acc, g).unwrap().residual
    });
    assert_ok(rep, what);
    let rep = check_jacobian("M", ev.mass.as_ref(), &unit, |d| {
        let a: Vec<f64> = acc.iter().zip(d).map(|(a, d)| a + d).collect();
        se.evaluate(&base, &a, g).unwrap().residual
    });
    assert_ok(rep, what);
}

fn with_stiffness_scaled(body: &ReducedBody, s: f64) -> ReducedBody {
    let mut b = body.clone();
    b.K_CB.data.iter_mut().for_each(|v| *v *= s);
    b
}

/// The full residual (inertia, elastic, gravity) of every fixture, frame choice, inertia
/// variant and angle.
#[test]
fn tangents_match_fd() {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            for mass in VARIANTS {
                let se = superelement(&fx.body, frame, mass);
                for (i, angle) in ANGLES.iter().enumerate() {
                    let (state, acc) = test_state(&se, &StateSpec::moving(*angle, 7 + i as u64));
                    check_tangents(
                        &se,
                        &state,
                        &acc,
                        &gravity(),
                        &format!("{} {frame} {mass:?} {angle} deg", fx.name),
                    );
                }
            }
        }
    }
}

/// Inertia alone (K_CB = 0, no gravity), fast rotation: the quadratic velocity terms and
/// the configuration dependence of the mass are not hidden behind the stiffness.
#[test]
fn inertia_tangents_match_fd() {
    for fx in [beam_dynamic(), l_frame(), beam_auxiliary(), solid_block()] {
        let body = with_stiffness_scaled(&fx.body, 0.0);
        for frame in frame_choices(&body) {
            for mass in VARIANTS {
                let se = superelement(&body, frame, mass);
                let mut spec = StateSpec::moving(120.0, 3);
                spec.spin = 20.0;
                spec.deformation = 0.05;
                let (state, acc) = test_state(&se, &spec);
                check_tangents(
                    &se,
                    &state,
                    &acc,
                    &Vector3::zeros(),
                    &format!("{} {frame} {mass:?} inertia only", fx.name),
                );
            }
        }
    }
}

/// Elastic force alone (at rest, no gravity), with large elastic rotations (0.3 rad) so
/// that the Lambda terms matter.
#[test]
fn elastic_tangent_matches_fd() {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            let se = superelement(&fx.body, frame, MassVariant::Lumped);
            let mut spec = StateSpec::moving(170.0, 11);
            spec.spin = 0.0;
            spec.deformation = 0.3;
            let (state, acc) = test_state(&se, &spec);
            check_tangents(
                &se,
                &state,
                &acc,
                &Vector3::zeros(),
                &format!("{} {frame} elastic only", fx.name),
            );
        }
    }
}

/// Gravity alone (no stiffness, at rest).
#[test]
fn gravity_tangent_matches_fd() {
    for fx in [beam_dynamic(), l_frame()] {
        let body = with_stiffness_scaled(&fx.body, 0.0);
        for frame in frame_choices(&body) {
            let se = superelement(&body, frame, MassVariant::Exact);
            let mut spec = StateSpec::moving(30.0, 5);
            spec.spin = 0.0;
            spec.deformation = 0.1;
            let (state, acc) = test_state(&se, &spec);
            check_tangents(
                &se,
                &state,
                &acc,
                &gravity(),
                &format!("{} {frame} gravity only", fx.name),
            );
        }
    }
}

/// Rayleigh and modal damping (no stiffness, so that the damping forces dominate).
#[test]
fn damping_tangents_match_fd() {
    for fx in [beam_dynamic(), l_frame()] {
        let body = with_stiffness_scaled(&fx.body, 0.0);
        let m = body.n_modes;
        let damping = Damping {
            alpha: 3.0,
            beta: 0.0,
            modal_ratios: (0..m).map(|i| 0.02 * (i + 1) as f64).collect(),
        };
        let mut stiff = fx.body.clone();
        stiff.M_CB = body.M_CB.clone();
        for frame in frame_choices(&body) {
            for mass in VARIANTS {
                let se = Superelement::new(&body, frame, mass, damping.clone()).unwrap();
                let (state, acc) = test_state(&se, &StateSpec::moving(120.0, 9));
                check_tangents(
                    &se,
                    &state,
                    &acc,
                    &Vector3::zeros(),
                    &format!("{} {frame} {mass:?} damped", fx.name),
                );
                // Stiffness-proportional damping on the real body.
                let se = Superelement::new(&fx.body, frame, mass, Damping::rayleigh(0.0, 1e-4)).unwrap();
                let (state, acc) = test_state(&se, &StateSpec::moving(170.0, 10));
                check_tangents(
                    &se,
                    &state,
                    &acc,
                    &gravity(),
                    &format!("{} {frame} {mass:?} beta-damped", fx.name),
                );
            }
        }
    }
}

/// d(local coordinates)/d(absolute coordinates) at a fixed frame: Lambda Rbar^T, and
/// d(local coordinates)/d(frame) = -Lambda Phi_rig (the exact (5.3)).
#[test]
fn local_coordinates_variation() {
    let fx = l_frame();
    let se = superelement(&fx.body, superelement::FrameChoice::CenterOfMass, MassVariant::Exact);
    let (state, _) = test_state(
        &se,
        &StateSpec {
            deformation: 0.2,
            ..StateSpec::moving(120.0, 2)
        },
    );
    let frame = se.solve_frame(&state).unwrap().0;
    let kin = se.kinematics_at(&state, frame, 0).unwrap();
    let n = se.n_coordinates();
    let N = se.n_interfaces();
    let R = kin.R_j;
    let local = |s: &BodyState, f: &Frame| se.kinematics_at(s, *f, 0).unwrap().q_jj;
    // Analytic Lambda Rbar^T.
    let mut A = Mat::<f64>::zeros(n, n);
    for k in 0..N {
        let blocks = [Matrix3::identity(), kin.Lambda[k]];
        for (b, L) in blocks.iter().enumerate() {
            let M = L * R.transpose();
            for i in 0..3 {
                for j in 0..3 {
                    A[(6 * k + 3 * b + i, 6 * k + 3 * b + j)] = M[(i, j)];
                }
            }
        }
    }
    for i in 6 * N..n {
        A[(i, i)] = 1.0;
    }
    let h = steps(&se);
    let rep = check_jacobian("dq_jj/dq (frame held)", A.as_ref(), &h, |d| {
        local(&perturb_state(&state, d), &frame)
    });
    assert_ok(rep, "local coordinates");
    // Frame variation in body axes: r_j + R_j d_t, R_j exp(d_r).
    let Phi_rig = kin.phi_rig();
    let mut A = Mat::<f64>::zeros(n, 6);
    for j in 0..6 {
        for k in 0..N {
            let t = Vector3::new(Phi_rig[(6 * k, j)], Phi_rig[(6 * k + 1, j)], Phi_rig[(6 * k + 2, j)]);
            let r = kin.Lambda[k]
                * Vector3::new(
                    Phi_rig[(6 * k + 3, j)],
                    Phi_rig[(6 * k + 4, j)],
                    Phi_rig[(6 * k + 5, j)],
                );
            for i in 0..3 {
                A[(6 * k + i, j)] = -t[i];
                A[(6 * k + 3 + i, j)] = -r[i];
            }
        }
    }
    let rep = check_jacobian("dq_jj/dframe", A.as_ref(), &[1e-6; 6], |d| {
        let f = Frame::new(
            frame.r + frame.R * Vector3::new(d[0], d[1], d[2]),
            frame.R * so3::exp(&Vector3::new(d[3], d[4], d[5])),
        );
        local(&state, &f)
    });
    assert_ok(rep, "local coordinates vs frame");
    // The single-interface functions agree with the vector form.
    let u = interface_displacement(&frame, &state.r[1], &se.interface_positions()[1]);
    let th = elastic_rotation(&frame.R, &state.R[1]);
    assert!((u - Vector3::new(kin.q_jj[6], kin.q_jj[7], kin.q_jj[8])).norm() < 1e-15);
    assert!((th - Vector3::new(kin.q_jj[9], kin.q_jj[10], kin.q_jj[11])).norm() < 1e-15);
}

/// The frame Jacobian: d(Phi_j q_jj)/d(frame) = -Phi_j Lambda Phi_rig, and the frame's and
/// the local coordinates' response to the absolute coordinates (frame re-solved):
/// Z_j Lambda Rbar^T and T_j Lambda Rbar^T (5.4)-(5.5).
#[test]
fn frame_jacobian() {
    for fx in all_fixtures() {
        for frame_choice in frame_choices(&fx.body) {
            let se = superelement(&fx.body, frame_choice, MassVariant::Exact);
            let (state, _) = test_state(
                &se,
                &StateSpec {
                    deformation: 0.1,
                    ..StateSpec::moving(170.0, 4)
                },
            );
            let kin = se.kinematics(&state).unwrap();
            let frame = kin.frame;
            let n = se.n_coordinates();
            let Phi_j = se.phi_j();
            let G = kin.G_inv.try_inverse().unwrap();
            let A = Mat::from_fn(6, 6, |i, j| -G[(i, j)]);
            let rep = check_jacobian("d(Phi_j q_jj)/dframe", A.as_ref(), &[1e-6; 6], |d| {
                let f = Frame::new(
                    frame.r + frame.R * Vector3::new(d[0], d[1], d[2]),
                    frame.R * so3::exp(&Vector3::new(d[3], d[4], d[5])),
                );
                let q = se.kinematics_at(&state, f, 0).unwrap().q_jj;
                (0..6).map(|a| (0..n).map(|c| Phi_j[(a, c)] * q[c]).sum()).collect()
            });
            assert_ok(rep, &format!("{} {frame_choice}", fx.name));
            let mut base = state.clone();
            base.frame = frame;
            let h = steps(&se);
            // Frame response, in body axes of the unperturbed frame.
            let Yr = rotate_cols(kin.Y(), &kin);
            let rep = check_jacobian("d(frame)/dq", Yr.as_ref(), &h, |d| {
                let f = se.solve_frame(&perturb_state(&base, d)).unwrap().0;
                let dt = frame.R.inverse() * (f.r - frame.r);
                let dr = so3::log(&(frame.R.inverse() * f.R));
                vec![dt.x, dt.y, dt.z, dr.x, dr.y, dr.z]
            });
            assert_ok(rep, &format!("{} {frame_choice}", fx.name));
            let Br = rotate_cols(kin.B().expect("complete kinematics"), &kin);
            let rep = check_jacobian("dq_jj/dq", Br.as_ref(), &h, |d| {
                se.kinematics(&perturb_state(&base, d)).unwrap().q_jj
            });
            assert_ok(rep, &format!("{} {frame_choice}", fx.name));
        }
    }
}

/// `A Rbar^T` for a matrix `A` with n columns (the body-axis maps applied to spatial variations).
fn rotate_cols(A: faer::MatRef<'_, f64>, kin: &superelement::Kinematics) -> Mat<f64> {
    let n = A.ncols();
    let N = kin.n_interfaces();
    let mut out = A.to_owned();
    for b in 0..2 * N {
        for i in 0..A.nrows() {
            let row = Vector3::new(A[(i, 3 * b)], A[(i, 3 * b + 1)], A[(i, 3 * b + 2)]);
            let v = kin.R_j * row;
            for c in 0..3 {
                out[(i, 3 * b + c)] = v[c];
            }
        }
    }
    let _ = n;
    out
}

/// The FFR inertia force's partials (`FfrInertia::force`) against central differences.
#[test]
fn ffr_partials() {
    let fx = l_frame();
    let se = superelement(
        &fx.body,
        superelement::FrameChoice::InterfaceNode(1),
        MassVariant::Exact,
    );
    let I = se.ffr_inertia();
    let n = se.n_coordinates();
    let mut rng = superelement::testing::Rng::new(17);
    let q: Vec<f64> = (0..n).map(|_| 0.05 * rng.uniform()).collect();
    let nu: Vec<f64> = (0..6 + n).map(|_| 3.0 * rng.uniform()).collect();
    let nud: Vec<f64> = (0..6 + n).map(|_| 9.0 * rng.uniform()).collect();
    let F = I.force_with_partials(&q, &nu, &nud);
    let h = vec![1e-6; n];
    let rep = check_jacobian("dF/dq", F.F_q.as_ref(), &h, |d| {
        let qq: Vec<f64> = q.iter().zip(d).map(|(a, b)| a + b).collect();
        I.force(&qq, &nu, &nud).F
    });
    assert_ok(rep, "ffr");
    let h = vec![1e-6; 6 + n];
    let rep = check_jacobian("dF/dnu", F.F_nu.as_ref(), &h, |d| {
        let v: Vec<f64> = nu.iter().zip(d).map(|(a, b)| a + b).collect();
        I.force(&q, &v, &nud).F
    });
    assert_ok(rep, "ffr");
    let rep = check_jacobian("dF/dnudot", F.M.as_ref(), &h, |d| {
        let v: Vec<f64> = nud.iter().zip(d).map(|(a, b)| a + b).collect();
        I.force(&q, &nu, &v).F
    });
    assert_ok(rep, "ffr");
    let M = I.mass_matrix(&q);
    let diff = (0..6 + n)
        .flat_map(|i| (0..6 + n).map(move |j| (i, j)))
        .map(|(i, j)| (M[(i, j)] - F.M[(i, j)]).abs())
        .fold(0.0, f64::max);
    assert!(diff == 0.0);
}

/// The force is linear in the accelerations with the mass matrix as factor: F(q, nu, nu_dot) -
/// F(q, nu, 0) = M_ffr(q) nu_dot, with M_ffr formed entry by entry from the invariants
/// (`FfrInertia::mass_matrix`) and the force by its column kernels (the packed invariant
/// products, the row updates of the transposed product), to round-off.
#[test]
fn ffr_force_is_linear_in_the_accelerations_with_the_mass_matrix() {
    let fx = l_frame();
    let se = superelement(&fx.body, superelement::FrameChoice::CenterOfMass, MassVariant::Exact);
    let I = se.ffr_inertia();
    let n = se.n_coordinates();
    let mut rng = superelement::testing::Rng::new(23);
    let q: Vec<f64> = (0..n).map(|_| 0.05 * rng.uniform()).collect();
    let nu: Vec<f64> = (0..6 + n).map(|_| 3.0 * rng.uniform()).collect();
    let nud: Vec<f64> = (0..6 + n).map(|_| 9.0 * rng.uniform()).collect();
    let F = I.force(&q, &nu, &nud).F;
    let F0 = I.force(&q, &nu, &vec![0.0; 6 + n]).F;
    let M = I.mass_matrix(&q);
    for i in 0..6 + n {
        let (mut lin, mut scale) = (0.0, F[i].abs() + F0[i].abs());
        for j in 0..6 + n {
            lin += M[(i, j)] * nud[j];
            scale += (M[(i, j)] * nud[j]).abs();
        }
        let gap = (F[i] - F0[i] - lin).abs();
        // Two summation orders of the same products (about 2(6 + n) terms a row): a few ulp
        // of the sum of their magnitudes, 1e-14 is about 45 ulp.
        assert!(gap <= 1e-14 * scale, "row {i}: {gap:e} of {scale:e}");
    }
}
