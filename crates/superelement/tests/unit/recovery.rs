//! Recovery of the deformed mesh from the state.

use super::common::*;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use superelement::testing::{test_state, StateSpec};
use superelement::{BodyState, Frame, FrameChoice, Kinematics, MassVariant, Superelement};

/// Interface nodes land exactly on the interface coordinates (their CB shapes are unit
/// vectors), for every frame choice.
#[test]
fn interface_nodes_follow_the_interfaces() {
    each_moving_body(0.1, (120.0, 4), |fx, frame, se, state, kin| {
        let mesh = se.recover_mesh(kin).expect("fixtures keep the mesh shapes");
        for (k, node) in fx.interfaces.iter().enumerate() {
            // Round-off of r_j + R_j (x_k + u_k) against r_k: ~1e-15 of the coordinates.
            assert!(
                (mesh.positions[node.index()] - state.r[k]).norm() < 1e-13,
                "{} {frame}: interface {k}",
                fx.name
            );
            assert!(mesh.orientations[node.index()].angle_to(&state.R[k]) < 1e-13);
        }
    });
}

/// Runs `check` on every fixture body with every frame choice it allows (exact inertia), in a
/// test state deformed by `deformation` and moving as `StateSpec::moving(speed, seed)`, with
/// its kinematics.
fn each_moving_body(
    deformation: f64,
    (speed, seed): (f64, u64),
    mut check: impl FnMut(&Fixture, FrameChoice, &Superelement, &BodyState, &Kinematics),
) {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            let se = superelement(&fx.body, frame, MassVariant::Exact);
            let (state, _) = test_state(
                &se,
                &StateSpec {
                    deformation,
                    ..StateSpec::moving(speed, seed)
                },
            );
            let kin = se.kinematics(&state).unwrap();
            check(fx, frame, &se, &state, &kin);
        }
    }
}

/// A rigid placement moves every node rigidly: p = t + Q x.
#[test]
fn rigid_placement_moves_the_mesh_rigidly() {
    let fx = l_frame();
    let se = superelement(&fx.body, superelement::FrameChoice::CenterOfMass, MassVariant::Lumped);
    let Q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(1.0, -2.0, 0.5)), 2.5);
    let t = Vector3::new(4.0, 5.0, -6.0);
    let state = se.undeformed_state(Frame::new(t + Q * se.frame_origin(), Q));
    let kin = se.kinematics(&state).unwrap();
    let mesh = se.recover_mesh(&kin).unwrap();
    for (i, x) in fx.model.mesh.nodes.iter().enumerate() {
        assert!((mesh.positions[i] - (t + Q * x.coords)).norm() < 1e-13);
        assert!(mesh.elastic[i].norm() < 1e-13);
    }
}

/// Mesh node velocities are the time derivatives of the recovered positions: central
/// differences of positions along the state's own motion (interfaces moved by their
/// velocities, eta by eta_dot, the frame re-solved) on a deformed, rotated, moving body.
#[test]
fn mesh_velocities_are_the_derivatives_of_the_positions() {
    each_moving_body(0.05, (60.0, 7), |fx, frame, se, state, kin| {
        let v = se
            .recover_mesh_velocities(kin, state)
            .expect("fixtures keep the mesh shapes");
        let qd = state.velocity_vector();
        let at = |h: f64| {
            let dq: Vec<f64> = qd.iter().map(|x| x * h).collect();
            let s = superelement::testing::perturb_state(state, &dq);
            se.recover_mesh(&se.kinematics(&s).unwrap()).unwrap().positions
        };
        let h = 1e-6;
        let (plus, minus) = (at(h), at(-h));
        let scale = v.iter().fold(0.0f64, |m, x| m.max(x.norm()));
        for i in 0..v.len() {
            let fd = (plus[i] - minus[i]) / (2.0 * h);
            // Central differences: O(h^2) truncation (1e-12 here) and round-off of about
            // 1e-16 |p| / h = 1e-10; 1e-6 of the largest speed leaves a wide margin.
            assert!(
                (fd - v[i]).norm() < 1e-6 * scale.max(1.0),
                "{} {frame}: node {i}: {v:?} against {fd:?}",
                fx.name,
                v = v[i]
            );
        }
    });
}

/// The hex8 block with stress shapes.
fn block_with_stress() -> (fe_model::FeModel, reduction::ReducedBody) {
    let mut settings = reduction::CbSettings::new(reduction::ModeSelection::Count(3));
    settings.stress_shapes = true;
    let (model, _, body) = superelement::testing::fixtures::solid_block_with(settings);
    (model, body)
}

/// A rigid placement adds no stress, for every frame choice.
#[test]
fn rigid_placement_gives_no_stress() {
    let (_, body) = block_with_stress();
    for frame in frame_choices(&body) {
        let se = superelement(&body, frame, MassVariant::Exact);
        let Q = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vector3::new(0.3, 1.0, -0.5)), 1.9);
        let state = se.undeformed_state(Frame::new(Vector3::new(1.0, -2.0, 3.0) + Q * se.frame_origin(), Q));
        let kin = se.kinematics(&state).unwrap();
        let stress = se.recover_stress(&kin.q_jj).expect("stress shapes kept");
        let largest = stress
            .nodal
            .iter()
            .flatten()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        // Round-off of the local coordinates (~1e-16 m) times E / size (~1e11 Pa/m).
        assert!(largest < 1e-3, "{frame}: rigid placement gives {largest:e} Pa");
    }
}

/// In a deformed, moving state the recovered stress is the FE stress of the elastic field
/// $\mathbf S\mathbf q^{jj}$ computed element by element (`fe_model::stress`), not through the
/// stored shapes.
#[test]
fn recovered_stress_is_the_fe_stress_of_the_elastic_field() {
    let (model, body) = block_with_stress();
    for frame in frame_choices(&body) {
        let se = superelement(&body, frame, MassVariant::Exact);
        let (state, _) = test_state(
            &se,
            &StateSpec {
                deformation: 0.01,
                ..StateSpec::moving(80.0, 7)
            },
        );
        let kin = se.kinematics(&state).unwrap();
        let stress = se.recover_stress(&kin.q_jj).unwrap();
        let mesh = se.recover_mesh(&kin).unwrap();
        let u: Vec<[f64; 6]> = mesh.elastic.iter().map(|e| [e.x, e.y, e.z, 0.0, 0.0, 0.0]).collect();
        let direct = fe_model::stress::nodal_stresses(&model, &u).unwrap();
        let scale = direct.iter().flatten().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(scale > 1e3, "{frame}: the state must strain the block ({scale:e} Pa)");
        for (i, (a, b)) in stress.nodal.iter().zip(&direct).enumerate() {
            // The interface nodes of the spiders carry no solid element, hence no stress.
            assert_eq!(a.is_some(), b.is_some(), "{frame}: node {i}");
            let (Some(a), Some(b)) = (a, b) else { continue };
            for c in 0..6 {
                // Two summation orders of the same linear map: round-off of the sums.
                assert!(
                    (a[c] - b[c]).abs() < 1e-9 * scale,
                    "{frame}: node {i} component {c}: {} vs {}",
                    a[c],
                    b[c]
                );
            }
        }
    }
}
