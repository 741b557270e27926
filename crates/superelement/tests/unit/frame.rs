//! The frame solve (4.4).

use super::common::*;
use nalgebra::Vector3;
use superelement::testing::{perturb_state, test_state, Rng, StateSpec};
use superelement::{Damping, Frame, FrameChoice, FrameSettings, MassVariant, Superelement, SuperelementError};

/// Warm-started from the previous step's frame, Newton needs few iterations ([AIC-FFR] §4), and
/// the converged frame satisfies (4.4) to the tolerance.
#[test]
fn warm_start_converges_in_a_few_iterations() {
    for fx in [l_frame(), beam_dynamic()] {
        let se = superelement(&fx.body, FrameChoice::CenterOfMass, MassVariant::Exact);
        let (state, _) = test_state(&se, &StateSpec::moving(120.0, 1));
        let (f0, _) = se.solve_frame(&state).unwrap();
        // A "time step": every coordinate moves by 1e-3 of its scale.
        let mut rng = Rng::new(5);
        let dq: Vec<f64> = (0..se.n_coordinates()).map(|_| 1e-3 * rng.uniform()).collect();
        let mut next = perturb_state(&state, &dq);
        next.frame = f0;
        let kin = se.kinematics(&next).unwrap();
        assert!(
            kin.frame_iterations <= 3,
            "{}: {} iterations",
            fx.name,
            kin.frame_iterations
        );
        let g: Vec<f64> = (0..6)
            .map(|a| (0..se.n_coordinates()).map(|c| se.phi_j()[(a, c)] * kin.q_jj[c]).sum())
            .collect();
        assert!(g.iter().all(|x| x.abs() < 1e-12), "{}: residual {g:?}", fx.name);
    }
}

/// From a cold start (identity frame) a body turned by 170 degrees is still found: the
/// solver starts from interface 0 when the warm start is more than 1 rad away.
#[test]
fn cold_start_far_away_converges() {
    let fx = l_frame();
    let se = superelement(&fx.body, FrameChoice::CenterOfMass, MassVariant::Exact);
    let (mut state, _) = test_state(&se, &StateSpec::moving(170.0, 3));
    let (reference, _) = se.solve_frame(&state).unwrap();
    state.frame = Frame::new(Vector3::new(50.0, 0.0, 0.0), Default::default());
    let (f, _) = se.solve_frame(&state).unwrap();
    assert!((f.r - reference.r).norm() < 1e-12 && f.R.angle_to(&reference.R) < 1e-12);
}

/// Too few iterations give the error with the iteration count and the residual.
#[test]
fn non_convergence_is_reported() {
    let fx = l_frame();
    let se = superelement(&fx.body, FrameChoice::CenterOfMass, MassVariant::Exact).with_frame_settings(FrameSettings {
        tolerance: 1e-12,
        max_iterations: 1,
    });
    let (mut state, _) = test_state(
        &se,
        &StateSpec {
            deformation: 0.05,
            ..StateSpec::moving(30.0, 3)
        },
    );
    state.frame.r += Vector3::new(0.3, 0.0, 0.0);
    match se.solve_frame(&state) {
        Err(
            e @ SuperelementError::FrameNotConverged {
                iterations: 1,
                residual,
                tolerance,
            },
        ) => {
            assert!(residual > tolerance);
            let msg = e.to_string();
            // The message speaks of what the user can change, not of equation numbers.
            assert!(msg.contains("floating frame could not be found"), "{msg}");
            assert!(msg.contains("no convergence in 1 iterations"), "{msg}");
            assert!(msg.contains("smaller") && msg.contains("split the member"), "{msg}");
            assert!(
                !msg.contains("(4.4)") && !msg.contains("(2.6)") && !msg.contains("Phi"),
                "{msg}"
            );
        }
        other => panic!("expected FrameNotConverged, got {other:?}"),
    }
}

/// Frames at an interface (and the auxiliary interface) are explicit: R_j = R_k, r_j = r_k,
/// and that interface's CB coordinates vanish.
#[test]
fn interface_frames_are_explicit() {
    for fx in [beam_auxiliary(), l_frame()] {
        let mut choices = vec![FrameChoice::InterfaceNode(1)];
        if let Some(a) = fx.body.auxiliary_interface {
            choices.push(FrameChoice::AuxiliaryNode);
            assert_eq!(a, fx.body.interfaces.len() - 1);
        }
        for choice in choices {
            let se = superelement(&fx.body, choice, MassVariant::Lumped);
            let k = match choice {
                FrameChoice::InterfaceNode(k) => k,
                _ => fx.body.auxiliary_interface.unwrap(),
            };
            let (state, _) = test_state(&se, &StateSpec::moving(120.0, 8));
            let kin = se.kinematics(&state).unwrap();
            assert_eq!(kin.frame_iterations, 0);
            assert_eq!(kin.frame.r, state.r[k]);
            assert_eq!(kin.frame.R, state.R[k]);
            assert!(
                kin.q_jj[6 * k..6 * k + 6].iter().all(|x| x.abs() < 1e-15),
                "{:?}",
                &kin.q_jj[6 * k..6 * k + 6]
            );
            // T_j has zero rows for that interface: its modes are dropped.
            let T = kin.T().expect("complete kinematics");
            for i in 6 * k..6 * k + 6 {
                assert!((0..se.n_coordinates()).all(|j| T[(i, j)].abs() < 1e-14));
            }
        }
    }
}

#[test]
fn bad_frame_choices_and_states_are_refused() {
    let body = &beam_static().body;
    let e = Superelement::new(body, FrameChoice::InterfaceNode(2), MassVariant::Exact, Damping::none()).unwrap_err();
    assert!(matches!(e, SuperelementError::InvalidFrameChoice { .. }), "{e}");
    let e = Superelement::new(body, FrameChoice::AuxiliaryNode, MassVariant::Exact, Damping::none()).unwrap_err();
    assert!(e.to_string().contains("without an auxiliary interface"), "{e}");
    let e = Superelement::new(
        body,
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
        Damping {
            alpha: 0.0,
            beta: 0.0,
            modal_ratios: vec![0.1],
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("modal damping ratios"), "{e}");
    let mut broken = body.clone();
    broken.M_CB.nrows -= 1;
    let e = Superelement::new(&broken, FrameChoice::CenterOfMass, MassVariant::Exact, Damping::none()).unwrap_err();
    assert!(e.to_string().contains("M_CB"), "{e}");
    let se = superelement(body, FrameChoice::CenterOfMass, MassVariant::Exact);
    let mut state = se.undeformed_state(Frame::identity());
    state.eta.push(0.0);
    assert!(matches!(
        se.solve_frame(&state),
        Err(SuperelementError::InvalidState { .. })
    ));
    let mut state = se.undeformed_state(Frame::identity());
    state.r[0].x = f64::NAN;
    assert!(matches!(
        se.solve_frame(&state),
        Err(SuperelementError::InvalidState { .. })
    ));
}

/// The frame velocity (5.4) and the elastic velocity (5.5) of the state's velocities are the
/// time derivatives of the solved frame and of q_jj along the motion (central differences in
/// time, step 1e-6 s: truncation ~1e-12 relative; 1e-7 leaves room for the round-off of
/// differencing positions of size ~1).
#[test]
fn frame_and_elastic_velocities_are_time_derivatives() {
    for fx in all_fixtures() {
        for choice in frame_choices(&fx.body) {
            let se = superelement(&fx.body, choice, MassVariant::Exact);
            let (state, _) = test_state(
                &se,
                &StateSpec {
                    deformation: 0.1,
                    ..StateSpec::moving(120.0, 6)
                },
            );
            let kin = se.kinematics(&state).unwrap();
            let (v_j, w_j) = se.frame_velocity(&kin, &state);
            let qd_jj = se.local_velocity(&kin, &state);
            let h = 1e-6;
            let at = |t: f64| {
                let mut s = state.clone();
                for k in 0..se.n_interfaces() {
                    s.r[k] += state.v[k] * t;
                    s.R[k] = superelement::so3::exp(&(state.omega[k] * t)) * state.R[k];
                }
                for i in 0..se.n_modes() {
                    s.eta[i] += state.eta_dot[i] * t;
                }
                s.frame = kin.frame;
                se.kinematics(&s).unwrap()
            };
            let (kp, km) = (at(h), at(-h));
            let v_fd = (kp.frame.r - km.frame.r) / (2.0 * h);
            let w_fd = superelement::so3::log(&(kp.frame.R * km.frame.R.inverse())) / (2.0 * h);
            let scale = v_j.norm() + w_j.norm();
            assert!(
                (v_fd - v_j).norm() + (w_fd - w_j).norm() < 1e-7 * scale,
                "{} {choice}: {v_j} {w_j} vs {v_fd} {w_fd}",
                fx.name
            );
            let qscale = qd_jj.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            for i in 0..se.n_coordinates() {
                let fd = (kp.q_jj[i] - km.q_jj[i]) / (2.0 * h);
                assert!(
                    (fd - qd_jj[i]).abs() < 1e-6 * qscale,
                    "{} {choice}: qdot_jj[{i}] = {} vs {fd}",
                    fx.name,
                    qd_jj[i]
                );
            }
        }
    }
}

/// A frame that the interfaces cannot fix is reported in the user's terms: what is wrong with
/// the body and what to change, without symbols or equation numbers.
#[test]
fn singular_frame_message_says_what_to_do() {
    let msg = SuperelementError::SingularFrame { rcond: 1e-17 }.to_string();
    assert!(msg.contains("floating frame is undetermined"), "{msg}");
    assert!(
        msg.contains("split the member") && msg.contains("loads and units"),
        "{msg}"
    );
    assert!(!msg.contains("Phi") && !msg.contains("(2.6)"), "{msg}");
}

/// `evaluate_into` with a reused workspace starts the frame solve with chord steps on the
/// last evaluation's inverse Jacobian: after a small "time step" it finds the frame of a fresh
/// solve to the solve's tolerance, and from an unrelated configuration (a large deformation
/// and rotation since the last evaluation), where the chord steps do not contract, it changes
/// to Newton and still converges.
#[test]
fn chord_steps_from_the_last_evaluation_find_the_same_frame() {
    let g = Vector3::new(0.0, 0.0, -9.81);
    for fx in [l_frame(), beam_dynamic()] {
        let se = superelement(&fx.body, FrameChoice::CenterOfMass, MassVariant::Exact);
        let (state, acc) = test_state(&se, &StateSpec::moving(120.0, 1));
        let mut ws = se.workspace();
        let mut out = superelement::Evaluation::zeros(se.n_coordinates());
        se.evaluate_into(&state, &acc, &g, &mut ws, &mut out).unwrap();
        let mut rng = Rng::new(11);
        for scale in [1e-3, 0.3] {
            let dq: Vec<f64> = (0..se.n_coordinates()).map(|_| scale * rng.uniform()).collect();
            let mut next = perturb_state(&state, &dq);
            next.frame = out.frame;
            let (fresh, _) = se.solve_frame(&next).unwrap();
            se.evaluate_into(&next, &acc, &g, &mut ws, &mut out).unwrap();
            // Both stop at residual 1e-12 (relative to the body size for the position);
            // a Newton-converged frame is far closer than that to the root, so the two
            // agree to about the tolerance times the body size (about 1 m here).
            let (dr, dR) = ((out.frame.r - fresh.r).norm(), out.frame.R.angle_to(&fresh.R));
            assert!(
                dr < 1e-11 && dR < 1e-11,
                "{} step {scale}: {dr:e} m, {dR:e} rad",
                fx.name
            );
            assert!(out.frame_iterations <= 30, "{}: {}", fx.name, out.frame_iterations);
        }
    }
}

/// A forces-only evaluation leaves T_j and B out of the workspace's kinematics: the accessors
/// say so (`None`) instead of handing out stale rows, the elastic velocity of those kinematics
/// is still right, and completing them forms the same rows as a full kinematics.
#[test]
fn forces_only_kinematics_say_what_they_lack_and_complete_to_the_full_rows() {
    for fx in all_fixtures() {
        let se = superelement(&fx.body, FrameChoice::CenterOfMass, MassVariant::Exact);
        let (state, acc) = test_state(&se, &StateSpec::moving(120.0, 6));
        let full = se.kinematics(&state).unwrap();
        let expected = se.local_velocity(&full, &state);
        let mut ws = se.workspace();
        let mut out = superelement::Evaluation::zeros(se.n_coordinates());
        se.residual_into(&state, &acc, &Vector3::zeros(), &mut ws, &mut out)
            .unwrap();
        let kin = ws.kinematics();
        assert!(
            !kin.is_complete() && kin.T().is_none() && kin.B().is_none(),
            "{}",
            fx.name
        );
        let qd = se.local_velocity(kin, &state);
        // The same formulas on the same frame and q_jj, but the rows of a forces-only update
        // then completed, against a full update: round-off of sums of a few dozen products.
        let scale = expected.iter().fold(f64::MIN_POSITIVE, |m, x| m.max(x.abs()));
        for (a, b) in qd.iter().zip(&expected) {
            assert!((a - b).abs() <= 1e-12 * scale, "{}: {a} vs {b}", fx.name);
        }
        let kin = ws.complete_kinematics();
        assert!(kin.is_complete(), "{}", fx.name);
        for (A, B) in [
            (kin.T().unwrap(), full.T().unwrap()),
            (kin.B().unwrap(), full.B().unwrap()),
        ] {
            for j in 0..A.ncols() {
                for i in 0..A.nrows() {
                    assert!(
                        (A[(i, j)] - B[(i, j)]).abs() <= 1e-12 * (1.0 + B[(i, j)].abs()),
                        "{}: ({i}, {j}) {} vs {}",
                        fx.name,
                        A[(i, j)],
                        B[(i, j)]
                    );
                }
            }
        }
    }
}
