//! Results body by body: modal coordinates through `System::modal_coordinates`, the deformed
//! FE mesh through `System::deformed_mesh`, and points welded into nodes (`weld_points`).

use crate::fixtures::{square_beam, MeshShapes};
use mbs::merge::Point;
use mbs::{solve_static, weld_points, BodyId, Model, SensorKind, StaticSettings, Support, System};
use nalgebra::{Isometry3, Vector3};
use reduction::ModeSelection;
use superelement::{FrameChoice, MassVariant};

/// A cantilever along x of one beam superelement (mesh shapes kept), a small tip force along
/// y: small enough that the response is linear to 1e-8.
fn loaded_cantilever(L: f64, side: f64, E: f64, P: f64) -> (System, mbs::State, Vec<f64>) {
    let mut model = Model::new("cantilever");
    let a = model.add_node("root", Vector3::zeros());
    let b = model.add_node("tip", Vector3::new(L, 0.0, 0.0));
    let body = square_beam(
        "beam",
        (Vector3::zeros(), Vector3::new(L, 0.0, 0.0)),
        8,
        [side, E, 7800.0],
        ModeSelection::Count(2),
        MeshShapes::Keep,
    );
    model.add_flexible_body(
        body,
        vec![a, b],
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    model.add_support(Support::clamp(a));
    model.add_dead_force(b, Vector3::new(0.0, P, 0.0));
    model.add_sensor("eta", SensorKind::ModalCoordinates { body: BodyId(0) });
    let sys = System::new(&model).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap();
    let eta = sol.sensors.rows.last().unwrap().clone();
    (sys, sol.state, eta)
}

#[test]
fn modal_coordinates_are_the_modal_sensor() {
    let (sys, state, sensor) = loaded_cantilever(1.0, 0.02, 2.1e11, 1.0);
    let (eta, eta_dot) = sys.modal_coordinates(&state, BodyId(0));
    assert_eq!(eta.len(), 2);
    assert_eq!(eta, sensor);
    // A static solution is at rest.
    assert_eq!(eta_dot, vec![0.0; 2]);
    // A body id that is not in the model has no modal coordinates.
    assert!(sys.modal_coordinates(&state, BodyId(7)).0.is_empty());
}

/// The recovered mesh of the loaded cantilever against Euler-Bernoulli, $w(x) = P x^2 (3L -
/// x) / (6EI)$: cubic beam elements are exact at their nodes for a tip load, and the constraint
/// modes hold the static response to interface loads exactly.
#[test]
fn deformed_mesh_of_a_cantilever_is_the_beam_deflection() {
    let (L, side, E, P): (f64, f64, f64, f64) = (1.0, 0.02, 2.1e11, 1.0);
    let I = side.powi(4) / 12.0;
    let (sys, state, _) = loaded_cantilever(L, side, E, P);
    let reference = sys.deformed_mesh(&sys.initial_state(), BodyId(0)).unwrap().unwrap();
    let deformed = sys.deformed_mesh(&state, BodyId(0)).unwrap().unwrap();
    assert_eq!(reference.len(), 9);
    let tip_w = P * L.powi(3) / (3.0 * E * I);
    for (x0, x) in reference.iter().zip(&deformed) {
        let s = x0.x;
        let w = P * s * s * (3.0 * L - s) / (6.0 * E * I);
        // 1e-5 of the tip deflection: the geometric nonlinearity at w/L = 2e-4 is 1e-8 and the
        // floating frame converges to round-off; the rest is the static solver's tolerance.
        assert!((x.y - w).abs() <= 1e-5 * tip_w, "at x = {s}: {} against {w}", x.y);
        assert!(x.z.abs() <= 1e-9 * tip_w, "out of plane at x = {s}: {}", x.z);
    }
    // The undeformed mesh is the beam's nodes on the x axis, every L/8 (in any order), to the
    // round-off of coordinates of order 1.
    let mut xs: Vec<f64> = reference.iter().map(|x0| x0.x).collect();
    xs.sort_by(f64::total_cmp);
    for (k, (x, x0)) in xs.iter().zip(&reference).enumerate() {
        assert!((x - L * k as f64 / 8.0).abs() < 1e-12, "{x}");
        assert!(x0.y.abs() < 1e-12 && x0.z.abs() < 1e-12, "{x0}");
    }
    // A rigid body or an unknown id has no mesh.
    assert!(sys.deformed_mesh(&state, BodyId(3)).unwrap().is_none());
}

fn point(name: &str, x: f64) -> Point {
    Point {
        name: name.into(),
        position: Vector3::new(x, 0.0, 0.0),
    }
}

#[test]
fn welded_points_share_one_node_named_after_them() {
    let points = [
        point("a.1", 0.0),
        point("b.1", 1.0),
        point("c.1", 1.0),
        point("d.1", 2.0),
    ];
    let mut model = Model::new("weld");
    // b-c welded, then c-b again (a repeated weld changes nothing).
    let nodes = weld_points(&mut model, &points, &[(1, 2), (2, 1)]).unwrap();
    assert_eq!(model.nodes.len(), 3);
    assert_eq!(nodes[1], nodes[2]);
    assert_ne!(nodes[0], nodes[1]);
    assert_eq!(model.nodes[nodes[1].index()].name, "b.1=c.1");
    assert_eq!(model.nodes[nodes[3].index()].name, "d.1");
    // Nodes in the order of their first point.
    assert_eq!(nodes.iter().map(|n| n.index()).collect::<Vec<_>>(), vec![0, 1, 1, 2]);
}

#[test]
fn welded_points_apart_are_refused_with_the_weld() {
    // 2 m model: the tolerance is 2e-6 m; 1e-5 m apart is refused, 1e-7 m accepted.
    let points = [
        point("a", 0.0),
        point("b", 2.0),
        point("c", 2.0 + 1e-5),
        point("d", 2.0 + 1e-7),
    ];
    let mut model = Model::new("weld");
    let e = weld_points(&mut model, &points, &[(1, 3), (1, 2)]).unwrap_err();
    assert_eq!(e.weld, 1);
    assert_eq!((e.a.as_str(), e.b.as_str()), ("b", "c"));
    assert!((e.distance - 1e-5).abs() < 1e-9);
    assert!(e.to_string().contains("must coincide"), "{e}");
}
