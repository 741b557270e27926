//! The momentum map and its projection (`mbs::momentum`) on models with every kind of
//! coordinate: the rigid velocity fields move every node rigidly, and a free chain of
//! superelements joined by revolute joints keeps its momenta to round-off.

use crate::fixtures::beam_body;
use crate::free_body::{run_drifts, second_path_momentum};
use mbs::{JointKind, Model, MomentumProjection, NodeId, PointMass, RigidBody, System};
use nalgebra::{Isometry3, Matrix3, UnitQuaternion, Vector3};
use reduction::ModeSelection;
use superelement::{FrameChoice, MassVariant};

/// A beam superelement between two nodes of `m` (1 m class, soft, 2 modes).
fn add_beam(m: &mut Model, a: NodeId, b: NodeId, mass: MassVariant) {
    let (pa, pb) = (m.nodes[a.index()].position, m.nodes[b.index()].position);
    let name = format!("beam {}-{}", m.nodes[a.index()].name, m.nodes[b.index()].name);
    let body = beam_body(&name, pa, pb, 4, 0.05, 7e7, 2700.0, ModeSelection::Count(2));
    m.add_flexible_body(body, vec![a, b], Isometry3::identity(), FrameChoice::CenterOfMass, mass);
}

#[test]
fn rigid_velocities_move_every_node_rigidly() {
    // Every coordinate kind: independent flexible nodes (translations and SO(3)), a revolute
    // joint (relative angle), a spherical joint (absolute SO(3) of the child), a rigid body with
    // a further node (offset), modal coordinates, a point mass.
    let mut m = Model::new("every coordinate");
    let n0 = m.add_node("n0", Vector3::new(0.2, -0.1, 0.3));
    let n1 = m.add_node("n1", Vector3::new(1.2, -0.1, 0.3));
    let n2 = m.add_node("n2", Vector3::new(1.2, -0.1, 0.3));
    let n3 = m.add_node("n3", Vector3::new(1.2, 0.9, 0.3));
    let n4 = m.add_node("n4", Vector3::new(1.2, 0.9, 0.3));
    let n5 = m.add_node("n5", Vector3::new(1.2, 0.9, 0.8));
    add_beam(&mut m, n0, n1, MassVariant::Exact);
    m.add_joint("hinge", n1, n2, JointKind::Revolute { axis: Vector3::z() });
    add_beam(&mut m, n2, n3, MassVariant::Lumped);
    m.add_joint("ball", n3, n4, JointKind::Spherical);
    m.add_rigid_body(RigidBody {
        name: "block".into(),
        reference: n4,
        nodes: vec![n5],
        mass: 2.0,
        center_of_mass: Vector3::new(0.0, 0.0, 0.25),
        inertia: Matrix3::from_diagonal(&Vector3::new(0.05, 0.06, 0.02)),
    });
    m.point_masses.push(PointMass {
        name: String::new(),
        node: n1,
        mass: 0.5,
    });
    let sys = System::new(&m).unwrap();
    assert_eq!(sys.rigid_invariance(), Ok(()));
    // A deformed, turned configuration: every coordinate away from zero.
    let mut s = sys.initial_state();
    sys.set_node_pose(
        &mut s,
        n1,
        Vector3::new(1.21, -0.08, 0.27),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.1, -0.2, 0.3)),
    );
    sys.set_node_pose(
        &mut s,
        n3,
        Vector3::new(1.3, 0.95, 0.2),
        UnitQuaternion::from_scaled_axis(Vector3::new(-0.3, 0.1, 0.5)),
    );
    sys.set_joint(&mut s, mbs::JointId(0), 0, 0.4, 0.0);
    sys.reset_frames(&mut s);
    let T = sys.rigid_velocities(&s);
    let nodes0 = sys.node_motions(&s);
    for k in 0..6 {
        let mut sk = s.clone();
        for (i, v) in sk.velocity_mut().iter_mut().enumerate() {
            *v = T[(i, k)];
        }
        let e = Vector3::ith(k % 3, 1.0);
        let (v0, w) = if k < 3 {
            (e, Vector3::zeros())
        } else {
            (Vector3::zeros(), e)
        };
        for (c, node) in sys.node_motions(&sk).iter().enumerate() {
            let v = v0 + w.cross(&nodes0[c].r);
            let err = (node.v - v).norm() + (node.omega - w).norm();
            // Exact maps: round-off of a few products of unit-size numbers.
            assert!(
                err < 1e-14,
                "field {k}, node {}: v {} (want {v}), w {}",
                m.nodes[c].name,
                node.v,
                node.omega
            );
        }
    }
}

/// Three beam superelements in a free chain joined by two revolute joints (axes z and x),
/// spinning, deformed and flapping.
fn free_chain() -> (System, mbs::State) {
    let mut m = Model::new("free chain");
    let p = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(1.8, 0.5, 0.0),
        Vector3::new(1.8, 0.5, 0.0),
        Vector3::new(2.6, 0.5, 0.3),
    ];
    let n: Vec<NodeId> = p
        .iter()
        .enumerate()
        .map(|(i, x)| m.add_node(&format!("n{i}"), *x))
        .collect();
    add_beam(&mut m, n[0], n[1], MassVariant::Exact);
    m.add_joint("j1", n[1], n[2], JointKind::Revolute { axis: Vector3::z() });
    add_beam(&mut m, n[2], n[3], MassVariant::Exact);
    m.add_joint("j2", n[3], n[4], JointKind::Revolute { axis: Vector3::x() });
    add_beam(&mut m, n[4], n[5], MassVariant::Exact);
    let sys = System::new(&m).unwrap();
    let mut s = sys.initial_state();
    sys.set_node_pose(
        &mut s,
        n[5],
        Vector3::new(2.6, 0.51, 0.29),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.01, -0.01, 0.02)),
    );
    sys.reset_frames(&mut s);
    let w = Vector3::new(0.4, -0.6, 2.0);
    let v0 = Vector3::new(0.1, 0.2, -0.1);
    let nodes = sys.node_motions(&s);
    for &k in &[0, 1, 3, 5] {
        sys.set_node_velocity(&mut s, n[k], v0 + w.cross(&nodes[k].r), w);
    }
    let th = sys.joint_value(&s, mbs::JointId(0), 0);
    sys.set_joint(&mut s, mbs::JointId(0), 0, th, 1.5);
    sys.set_joint(&mut s, mbs::JointId(1), 0, 0.2, -1.0);
    (sys, s)
}

#[test]
fn a_free_chain_with_revolute_joints_keeps_its_momenta_to_round_off() {
    let (sys, s) = free_chain();
    assert_eq!(sys.rigid_invariance(), Ok(()));
    let (L, H) = sys.momentum(&s).unwrap();
    let (Lb, Hb) = second_path_momentum(&sys, &s);
    assert!((L - Lb).norm() < 1e-13 * L.norm() && (H - Hb).norm() < 1e-13 * H.norm());
    let (d, _) = run_drifts(&sys, s.clone(), 2e-3, 100, MomentumProjection::Auto, 0.9);
    eprintln!("free chain, projected: {d}");
    for (x, what) in [
        (d.L, "L"),
        (d.H, "H"),
        (d.L2, "L, second path"),
        (d.H2, "H, second path"),
    ] {
        assert!(x < 1e-13, "{what} drift {x:e}");
    }
    let (d, _) = run_drifts(&sys, s, 2e-3, 100, MomentumProjection::Off, 0.9);
    eprintln!("free chain, plain: {d}");
    assert!(d.L2 > 1e-7 && d.H2 > 1e-7, "{d}");
}
