//! Small motions about the undeformed state reproduce the linear FE model: statics exactly
//! (constraint modes are exact for interface loads), frequencies to the accuracy of the
//! fixed-interface modes kept. Plus Newton on the full nonlinear residual.

use super::common::*;
use fe_model::{modal_dense, solve_static, DofMask, NodalLoad};
use nalgebra::{DMatrix, DVector, Unit, UnitQuaternion, Vector3};
use superelement::so3;
use superelement::{BodyState, Frame, FrameChoice, MassVariant, Superelement};

/// The body placed with the FE model's axes turned by `Q` about the FE origin.
fn placed(se: &Superelement, Q: UnitQuaternion<f64>) -> BodyState {
    se.undeformed_state(Frame::new(Q * se.frame_origin(), Q))
}

/// Free coordinates when interface 0 is clamped: interfaces 1.. and eta.
fn free(se: &Superelement) -> Vec<usize> {
    (6..se.n_coordinates()).collect()
}

fn sub(A: &faer::Mat<f64>, idx: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(idx.len(), idx.len(), |i, j| A[(idx[i], idx[j])])
}

/// Interface loads (force, moment) in FE axes, one per interface after the clamped one.
fn loads(n_loaded: usize, scale: f64) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    (0..n_loaded)
        .map(|i| {
            let s = scale * (1.0 + i as f64);
            (Vector3::new(1.0, -0.5, 0.8) * s, Vector3::new(-0.2, 0.3, 0.1) * s)
        })
        .collect()
}

/// Linear statics with the superelement tangent at the undeformed state, at a placement
/// turned by 120 degrees, against fe-model's sparse static solution of the clamped FE model.
/// Round-off only: the condensation is exact, so the two agree to ~1e-12 relative
/// (condition number of the clamped stiffness ~1e6 times 1e-16, with margin).
#[test]
fn statics_match_fe_exactly() {
    for fx in all_fixtures() {
        let mut model = fx.model.clone();
        model.add_support(fx.interfaces[0], DofMask::ALL);
        let ld = loads(fx.interfaces.len() - 1, 1.0);
        let nodal: Vec<NodalLoad> = fx.interfaces[1..]
            .iter()
            .zip(&ld)
            .map(|(node, (f, m))| NodalLoad {
                node: *node,
                force: *f,
                moment: *m,
            })
            .collect();
        let fe = solve_static(&model, &nodal).unwrap();
        let Q =
            UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(0.3, -0.5, 0.8)), 120f64.to_radians());
        for frame in frame_choices(&fx.body) {
            for mass in VARIANTS {
                let se = superelement(&fx.body, frame, mass);
                let n = se.n_coordinates();
                let ev = se.evaluate(&placed(&se, Q), &vec![0.0; n], &Vector3::zeros()).unwrap();
                let idx = free(&se);
                let K = sub(&ev.stiffness, &idx);
                let mut F = DVector::zeros(idx.len());
                for (i, (f, m)) in ld.iter().enumerate() {
                    F.fixed_rows_mut::<3>(6 * i).copy_from(&(Q * f));
                    F.fixed_rows_mut::<3>(6 * i + 3).copy_from(&(Q * m));
                }
                let d = K.clone().lu().solve(&F).unwrap();
                for (i, node) in fx.interfaces[1..].iter().enumerate() {
                    let u_fe = fe.displacements[node.index()];
                    let u = Q.inverse() * Vector3::from(d.fixed_rows::<3>(6 * i).into_owned());
                    let th = Q.inverse() * Vector3::from(d.fixed_rows::<3>(6 * i + 3).into_owned());
                    let (u_ref, th_ref) = (
                        Vector3::new(u_fe[0], u_fe[1], u_fe[2]),
                        Vector3::new(u_fe[3], u_fe[4], u_fe[5]),
                    );
                    let scale = u_ref.norm() + th_ref.norm() * 1.0;
                    assert!(
                        (u - u_ref).norm() + (th - th_ref).norm() < 1e-10 * scale,
                        "{} {frame} {mass:?} interface {}: {u} {th} vs FE {u_ref} {th_ref}",
                        fx.name,
                        i + 1
                    );
                }
                // Static interface loads do not excite the fixed-interface modes.
                for i in 6 * (se.n_interfaces() - 1)..idx.len() {
                    assert!(d[i].abs() < 1e-10 * d.amax(), "{}: eta = {}", fx.name, d[i]);
                }
            }
        }
    }
}

/// Newton on the full nonlinear static residual r(q) = f (clamped interface 0), with the
/// tangent K_t: a small load converges to the linear FE solution (difference of the order of
/// the load, the geometric nonlinearity), and a large one (deflection ~20% of the length, in
/// 10 load steps) converges quadratically: the error ratio e_{k+1} / e_k^2 stays bounded.
#[test]
fn newton_on_the_nonlinear_residual() {
    let fx = beam_dynamic();
    let mut model = fx.model.clone();
    model.add_support(fx.interfaces[0], DofMask::ALL);
    for frame in [
        FrameChoice::CenterOfMass,
        FrameChoice::InterfaceNode(0),
        FrameChoice::InterfaceNode(1),
    ] {
        let se = superelement(&fx.body, frame, MassVariant::Exact);
        let n = se.n_coordinates();
        let solve = |scale: f64, steps: usize| -> (BodyState, Vec<Vec<f64>>) {
            let mut state = placed(&se, UnitQuaternion::identity());
            let mut history = Vec::new();
            for step in 1..=steps {
                let (f, m) = loads(1, scale * step as f64 / steps as f64)[0];
                let mut norms = Vec::new();
                for _ in 0..25 {
                    let ev = se.evaluate(&state, &vec![0.0; n], &Vector3::zeros()).unwrap();
                    state.frame = ev.frame;
                    let mut res = DVector::from_fn(n - 6, |i, _| ev.residual[6 + i]);
                    for i in 0..3 {
                        res[i] -= f[i];
                        res[3 + i] -= m[i];
                    }
                    norms.push(res.norm());
                    // Converged at 1e-8 of the load: the elastic forces carry a round-off of
                    // ~1e-9 of it here (K_CB ~ 1e9 N/m times 1e-16 m, times the load's scale).
                    if res.norm() < 1e-8 * (f.norm() + m.norm()) {
                        break;
                    }
                    let K = sub(&ev.stiffness, &free(&se));
                    let d = K.lu().solve(&(-res)).unwrap();
                    let mut dq = vec![0.0; n];
                    dq[6..].copy_from_slice(d.as_slice());
                    state = superelement::testing::perturb_state(&state, &dq);
                }
                history.push(norms);
            }
            (state, history)
        };
        // Small load: linear.
        let (state, history) = solve(1.0, 1);
        assert!(history[0].len() <= 4, "{frame}: {:?}", history[0]);
        let (f, m) = loads(1, 1.0)[0];
        let fe = solve_static(
            &model,
            &[NodalLoad {
                node: fx.interfaces[1],
                force: f,
                moment: m,
            }],
        )
        .unwrap();
        let u_fe = fe.displacements[fx.interfaces[1].index()];
        let u = state.r[1] - placed(&se, UnitQuaternion::identity()).r[1];
        let th = so3::log(&state.R[1]);
        let (u_ref, th_ref) = (
            Vector3::new(u_fe[0], u_fe[1], u_fe[2]),
            Vector3::new(u_fe[3], u_fe[4], u_fe[5]),
        );
        let rel = ((u - u_ref).norm() + (th - th_ref).norm()) / (u_ref.norm() + th_ref.norm());
        // Tip rotations here are ~1e-5 rad: geometric nonlinearity of that relative order.
        assert!(rel < 1e-4, "{frame}: nonlinear vs linear FE differ by {rel:e}");
        // Large load in 10 steps: every step converges quadratically. Residuals are measured
        // relative to the step's load; once below 1e-4, e_{k+1} <= 1e4 e_k^2 (C ~ 1e3 is
        // seen for the frame at the loaded tip; a Newton with an approximate tangent converges
        // linearly and misses this by orders of magnitude in the last iterations).
        let (state, history) = solve(2e4, 10);
        let tip = (state.r[1] - placed(&se, UnitQuaternion::identity()).r[1]).norm();
        assert!(tip > 0.1, "{frame}: tip moved only {tip}");
        for (step, norms) in history.iter().enumerate() {
            let (f, m) = loads(1, 2e4 * (step + 1) as f64 / 10.0)[0];
            let e: Vec<f64> = norms.iter().map(|r| r / (f.norm() + m.norm())).collect();
            assert!(e.len() <= 8, "{frame}: step {step}: {e:?}");
            for w in e.windows(2) {
                if w[0] < 1e-4 && w[1] > 1e-12 {
                    assert!(w[1] <= 1e4 * w[0] * w[0], "{frame}: step {step} not quadratic: {e:?}");
                }
            }
        }
    }
}

/// Generalised eigenvalues of (K, M) by Cholesky of M, ascending.
fn frequencies(K: &DMatrix<f64>, M: &DMatrix<f64>) -> Vec<f64> {
    let L = M.clone().cholesky().unwrap().l();
    let Li = L.clone().try_inverse().unwrap();
    let C = &Li * K * Li.transpose();
    let C = (&C + C.transpose()) * 0.5;
    let mut w: Vec<f64> = C
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .map(|l| l.max(0.0).sqrt())
        .collect();
    w.sort_by(|a, b| a.partial_cmp(b).unwrap());
    w
}

/// The small-motion eigenproblem of M and K_t about the undeformed state at rest, clamped at
/// interface 0, equals the CB problem (round-off) and approaches the FE frequencies of the
/// same clamped model as modes are added (here: 4 fixed-interface modes, 8 elements, lowest 4
/// frequencies within 0.2%; the static-modes-only body is worse, which the test also shows).
#[test]
fn frequencies_match_fe_to_the_modes_kept() {
    let fx = beam_dynamic();
    let mut model = fx.model.clone();
    model.add_support(fx.interfaces[0], DofMask::ALL);
    let fe = modal_dense(&model, 6).unwrap();
    let Q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, 1.0, 0.2)), 30f64.to_radians());
    for frame in frame_choices(&fx.body) {
        for mass in VARIANTS {
            let se = superelement(&fx.body, frame, mass);
            let n = se.n_coordinates();
            let ev = se.evaluate(&placed(&se, Q), &vec![0.0; n], &Vector3::zeros()).unwrap();
            let idx = free(&se);
            let w = frequencies(&sub(&ev.stiffness, &idx), &sub(&ev.mass, &idx));
            let w_cb = frequencies(&sub(se.k_cb(), &idx), &sub(se.m_cb(), &idx));
            for (a, b) in w.iter().zip(&w_cb) {
                assert!((a - b).abs() < 1e-9 * b, "{frame} {mass:?}: {a} vs CB {b}");
            }
            for i in 0..4 {
                let rel = (w[i] - fe.omega[i]) / fe.omega[i];
                assert!(
                    (-1e-9..2e-3).contains(&rel),
                    "{frame} {mass:?}: mode {i}: {} vs FE {} ({rel:e})",
                    w[i],
                    fe.omega[i]
                );
            }
        }
    }
    // Without fixed-interface modes the same beam is stiffer (Rayleigh-Ritz from above).
    let fs = beam_static();
    let se = superelement(&fs.body, FrameChoice::CenterOfMass, MassVariant::Exact);
    let idx = free(&se);
    let w = frequencies(&sub(se.k_cb(), &idx), &sub(se.m_cb(), &idx));
    let mut m2 = fs.model.clone();
    m2.add_support(fs.interfaces[0], DofMask::ALL);
    let fe2 = modal_dense(&m2, 2).unwrap();
    assert!(w[0] >= fe2.omega[0] * (1.0 - 1e-12));
}
