//! Loads at load points inside a body (`superelement::point_load`): the residual share against
//! the virtual work of the load on the recovered point, and its tangent against central
//! differences on deformed, rotated, moving states, dead and follower, solid and beam bodies.

use super::common::*;
use super::fd_tangent::{assert_ok, steps};
use fe_model::NodeId;
use nalgebra::{Point3, Vector3};
use reduction::{CbSettings, ModeSelection, ReducedBody};
use std::sync::OnceLock;
use superelement::testing::{check_jacobian, fixtures, perturb_state, test_state, StateSpec};
use superelement::{FrameChoice, MassVariant, PointLoad, Superelement};

/// The hex8 block with a load point at the node (0.6, 0.2, 0.15), inside the body between its
/// two spider faces, and 2 modes (3 attachment modes are appended).
fn solid_with_load_point() -> &'static ReducedBody {
    static B: OnceLock<ReducedBody> = OnceLock::new();
    B.get_or_init(|| {
        let mut settings = CbSettings::new(ModeSelection::Count(2));
        // The fixture's mesh: 5 x 1 x 2 hex8 over 1 x 0.2 x 0.3 m; node numbering is the
        // generator's, so the node is found by position.
        let mesh = fe_model::box_mesh::box_mesh(fe_model::CellKind::Hex8, [1.0, 0.2, 0.3], [5, 1, 2]).unwrap();
        let target = Point3::new(0.6, 0.2, 0.15);
        let node = (0..mesh.nodes.len())
            .find(|&i| (mesh.nodes[i] - target).norm() < 1e-12)
            .expect("a node at the load point");
        settings.load_points = vec![("p".to_string(), NodeId(node as u32))];
        fixtures::solid_block_with(settings).2
    })
}

/// The skew beam (8 elements, 2 modes) with a load point at its node 3 (6 attachment modes).
fn beam_with_load_point() -> &'static ReducedBody {
    static B: OnceLock<ReducedBody> = OnceLock::new();
    B.get_or_init(|| {
        let mut settings = CbSettings::new(ModeSelection::Count(2));
        // `straight_beam` numbers the nodes from 0 along the beam in an empty model.
        settings.load_points = vec![("p".to_string(), NodeId(3))];
        fixtures::straight_beam_with(
            Point3::new(0.1, -0.2, 0.05),
            Point3::new(1.0, 0.3, 0.45),
            8,
            settings,
            false,
        )
        .2
    })
}

fn load(follower: bool) -> PointLoad {
    PointLoad {
        point: 0,
        force: Vector3::new(120.0, -340.0, 75.0),
        moment: Vector3::new(-20.0, 15.0, 40.0),
        follower,
    }
}

fn residual(
    se: &Superelement,
    state: &superelement::BodyState,
    l: &PointLoad,
    tangents: bool,
) -> (Vec<f64>, faer::Mat<f64>) {
    let kin = se.kinematics(state).unwrap();
    let mut ws = se.point_load_workspace();
    if tangents {
        se.point_load_into(&kin, l, &mut ws).unwrap();
    } else {
        se.point_load_residual_into(&kin, l, &mut ws).unwrap();
    }
    (ws.residual, ws.stiffness)
}

#[test]
fn point_load_tangents_match_fd() {
    for (name, body) in [("solid", solid_with_load_point()), ("beam", beam_with_load_point())] {
        assert_eq!(body.load_points.len(), 1);
        for frame in [FrameChoice::CenterOfMass, FrameChoice::InterfaceNode(1)] {
            let se = superelement(body, frame, MassVariant::Exact);
            for follower in [false, true] {
                for (i, angle) in [30.0, 170.0].iter().enumerate() {
                    let mut spec = StateSpec::moving(*angle, 21 + i as u64);
                    // 5 % deformation: large enough that the q_jj dependence of the lever arm
                    // and of P is exercised.
                    spec.deformation = 0.05;
                    let (state, _) = test_state(&se, &spec);
                    let kin = se.kinematics(&state).unwrap();
                    let mut base = state.clone();
                    base.frame = kin.frame;
                    let l = load(follower);
                    let (_, K) = residual(&se, &base, &l, true);
                    let rep = check_jacobian("K_load", K.as_ref(), &steps(&se), |d| {
                        residual(&se, &perturb_state(&base, d), &l, false).0
                    });
                    assert_ok(rep, &format!("{name} {frame} follower {follower} {angle} deg"));
                }
            }
        }
    }
}

/// The residual share is minus the virtual work of the load on the point's motion: with the
/// point at p(q) (recovered through the mesh shapes) and turning by the frame's rotation plus
/// the linear elastic rotation, -dW/dq from central differences of p and of the rotation.
#[test]
fn point_load_does_the_work_of_the_load_on_the_recovered_point() {
    let body = solid_with_load_point();
    let se = superelement(body, FrameChoice::CenterOfMass, MassVariant::Exact);
    let node = body.load_points[0].node as usize;
    let (state, _) = test_state(&se, &StateSpec::moving(120.0, 5));
    let kin = se.kinematics(&state).unwrap();
    let mut base = state.clone();
    base.frame = kin.frame;
    let mut l = load(false);
    // A solid node has no rotation slots: a moment does no work there (the shape rows are zero).
    l.moment = Vector3::zeros();
    let (r, _) = residual(&se, &base, &l, false);
    let h = steps(&se);
    let position = |d: &[f64]| {
        let s = perturb_state(&base, d);
        se.recover_mesh(&se.kinematics(&s).unwrap()).unwrap().positions[node]
    };
    for (j, hj) in h.iter().enumerate() {
        let mut d = vec![0.0; h.len()];
        d[j] = *hj;
        let plus = position(&d);
        d[j] = -hj;
        let minus = position(&d);
        let work = l.force.dot(&(plus - minus)) / (2.0 * hj);
        // Central differences of positions of size 1: O(h^2) truncation, round-off 1e-16 / 1e-6
        // of the force scale (~400 N): 1e-6 relative to the force is ample.
        assert!(
            (r[j] + work).abs() <= 1e-6 * l.force.norm(),
            "coordinate {j}: residual {} against -dW/dq {}",
            r[j],
            -work
        );
    }
}
