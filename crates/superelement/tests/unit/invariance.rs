//! Rigid motions of all interfaces: zero elastic force, the frame moves with the body, and the
//! centre-of-mass frame sits at the centre of mass.

use super::common::*;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use superelement::testing::{test_state, StateSpec};
use superelement::{BodyState, Frame, FrameChoice, MassVariant};

/// The placement `(Q, t)` of the FE model: interface k at `t + Q x_k^FE`, oriented `Q`.
fn placed(se: &superelement::Superelement, Q: UnitQuaternion<f64>, t: Vector3<f64>) -> BodyState {
    // The superelement's x_k are measured from the frame origin P_j (FE coordinates `origin`).
    let origin = se.frame_origin();
    se.undeformed_state(Frame::new(t + Q * origin, Q))
}

fn rotations() -> Vec<UnitQuaternion<f64>> {
    [
        (30.0, Vector3::new(1.0, 2.0, -0.5)),
        (120.0, Vector3::new(-0.3, 0.1, 1.0)),
        (179.9, Vector3::new(0.6, -0.8, 0.2)),
    ]
    .iter()
    .map(|(a, ax)| UnitQuaternion::from_axis_angle(&Unit::new_normalize(*ax), f64::to_radians(*a)))
    .collect()
}

/// Round-off: local coordinates of a rigidly placed body are differences of O(L + |t|)
/// numbers, so they vanish to ~1e-15 (|t| ~ 10 L here); the elastic force is K_CB times
/// them: 1e-13 of K_CB's scale per unit length is far below any real deformation.
#[test]
fn rigid_motion_gives_zero_elastic_force_and_carries_the_frame() {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            for mass in VARIANTS {
                let se = superelement(&fx.body, frame, mass);
                let n = se.n_coordinates();
                let kmax = (0..n)
                    .flat_map(|i| (0..n).map(move |j| (i, j)))
                    .map(|(i, j)| se.k_cb()[(i, j)].abs())
                    .fold(0.0, f64::max);
                for Q in rotations() {
                    let t = Vector3::new(3.0, -7.0, 5.0);
                    let mut state = placed(&se, Q, t);
                    // Cold start: the frame must be found from the identity.
                    state.frame = Frame::identity();
                    let ev = se.evaluate(&state, &vec![0.0; n], &Vector3::zeros()).unwrap();
                    let qmax = ev.q_jj.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                    assert!(qmax < 1e-13, "{} {frame}: q_jj = {qmax:e} for a rigid motion", fx.name);
                    let fmax = ev.f_elastic.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                    assert!(fmax < 1e-13 * kmax, "{} {frame}: elastic force {fmax:e}", fx.name);
                    // The frame is the FE frame origin carried by the rigid motion.
                    let expected = Frame::new(t + Q * se.frame_origin(), Q);
                    assert!(
                        (ev.frame.r - expected.r).norm() < 1e-13,
                        "{} {frame}: frame at {}",
                        fx.name,
                        ev.frame.r
                    );
                    assert!(ev.frame.R.angle_to(&expected.R) < 1e-13, "{} {frame}", fx.name);
                }
            }
        }
    }
}

/// The centre-of-mass frame of a rigidly placed body is at the placed centre of mass.
#[test]
fn center_of_mass_frame_stays_at_the_center_of_mass() {
    for fx in all_fixtures() {
        let se = superelement(&fx.body, FrameChoice::CenterOfMass, MassVariant::Exact);
        let com = Vector3::from(fx.body.inertia.center_of_mass);
        assert!((se.frame_origin() - com).norm() == 0.0);
        for Q in rotations() {
            let t = Vector3::new(-1.0, 0.5, 2.0);
            let mut state = placed(&se, Q, t);
            state.frame = Frame::identity();
            let (f, _) = se.solve_frame(&state).unwrap();
            assert!(
                (f.r - (t + Q * com)).norm() < 1e-13,
                "{}: {} vs {}",
                fx.name,
                f.r,
                t + Q * com
            );
        }
    }
}

/// A rigid motion applied to a deformed state: the CB coordinates do not change, the frame
/// moves rigidly, and the elastic force turns with the body (objectivity).
#[test]
fn rigid_motion_of_a_deformed_state_is_objective() {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            let se = superelement(&fx.body, frame, MassVariant::Exact);
            let (state, _) = test_state(&se, &StateSpec::moving(30.0, 21));
            let n = se.n_coordinates();
            let ev = se.evaluate(&state, &vec![0.0; n], &Vector3::zeros()).unwrap();
            for Q in rotations() {
                let t = Vector3::new(0.4, 2.0, -3.0);
                let moved = rigidly_moved(&state, &ev.frame, &Q, &t);
                let ev2 = se.evaluate(&moved, &vec![0.0; n], &Vector3::zeros()).unwrap();
                let dq = ev
                    .q_jj
                    .iter()
                    .zip(&ev2.q_jj)
                    .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
                assert!(dq < 1e-13, "{} {frame}: q_jj changed by {dq:e}", fx.name);
                let scale = ev.f_elastic.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                for b in 0..2 * se.n_interfaces() {
                    let f = Vector3::new(ev.f_elastic[3 * b], ev.f_elastic[3 * b + 1], ev.f_elastic[3 * b + 2]);
                    let f2 = Vector3::new(ev2.f_elastic[3 * b], ev2.f_elastic[3 * b + 1], ev2.f_elastic[3 * b + 2]);
                    assert!((Q * f - f2).norm() < 1e-11 * scale, "{} {frame}: block {b}", fx.name);
                }
                // A free body in equilibrium of its elastic forces: they balance (sum of forces
                // and moments about the origin vanish) in any placement.
                let (F, Mo) = resultant(&ev2.f_elastic, &moved.r[..se.n_interfaces()]);
                assert!(
                    F.norm() < 1e-10 * scale && Mo.norm() < 1e-9 * scale,
                    "{} {frame}: resultant {F} {Mo}",
                    fx.name
                );
            }
        }
    }
}
