//! Recovery of the deformed mesh from the state.

use super::common::*;
use nalgebra::{Unit, UnitQuaternion, Vector3};
use superelement::testing::{test_state, StateSpec};
use superelement::{Frame, MassVariant};

/// Interface nodes land exactly on the interface coordinates (their CB shapes are unit
/// vectors), for every frame choice.
#[test]
fn interface_nodes_follow_the_interfaces() {
    for fx in all_fixtures() {
        for frame in frame_choices(&fx.body) {
            let se = superelement(&fx.body, frame, MassVariant::Exact);
            let (state, _) = test_state(
                &se,
                &StateSpec {
                    deformation: 0.1,
                    ..StateSpec::moving(120.0, 4)
                },
            );
            let kin = se.kinematics(&state).unwrap();
            let mesh = se.recover_mesh(&kin).expect("fixtures keep the mesh shapes");
            for (k, node) in fx.interfaces.iter().enumerate() {
                // Round-off of r_j + R_j (x_k + u_k) against r_k: ~1e-15 of the coordinates.
                assert!(
                    (mesh.positions[node.index()] - state.r[k]).norm() < 1e-13,
                    "{} {frame}: interface {k}",
                    fx.name
                );
                assert!(mesh.orientations[node.index()].angle_to(&state.R[k]) < 1e-13);
            }
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
