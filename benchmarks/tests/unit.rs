//! Checks of the slider-crank benchmark's model builder and midpoint measurement.
//! The binaries' numbers are compared against Exudyn and a beam reference by
//! `benchmarks/run_comparison.sh`; these tests pin the pieces those numbers rest on.

#![allow(non_snake_case)]

use fe_model::CellKind;
use flexmbs_benchmarks::{chord_distance, midpoint_from_mesh, rod_body, RodMesh, SliderCrank};
use mbs::SensorRecord;
use nalgebra::{UnitQuaternion, Vector3};
use reduction::ModeSelection;
use superelement::FrameChoice;

const MESH: RodMesh = RodMesh {
    kind: CellKind::Hex20,
    along: 8,
    across: 2,
};

/// A record of the sensors `midpoint_from_mesh` reads, one time, rod ends at `rA`, `rB` with
/// rotation vectors `qA`, `qB` and modal coordinates `eta`.
fn record(rA: Vector3<f64>, rB: Vector3<f64>, qA: Vector3<f64>, qB: Vector3<f64>, eta: Vec<f64>) -> SensorRecord {
    let m = eta.len();
    let mut row = Vec::new();
    for v in [rA, rB, qA, qB] {
        row.extend_from_slice(v.as_slice());
    }
    row.extend(eta);
    SensorRecord {
        names: ["A", "B", "rotA", "rotB", "eta0"].map(String::from).to_vec(),
        widths: vec![3, 3, 3, 3, m],
        times: vec![0.0],
        rows: vec![row],
    }
}

#[test]
fn square_section_has_the_round_rods_second_moment() {
    let p = SliderCrank::C2;
    let (a, d) = (p.side(), p.diameter);
    assert!((a.powi(4) / 12.0 - std::f64::consts::PI * d.powi(4) / 64.0).abs() < 1e-12 * d.powi(4));
}

#[test]
fn chord_distance_is_signed_along_ez_cross_chord() {
    let (a, b) = (Vector3::new(1.0, 1.0, 0.0), Vector3::new(3.0, 1.0, 0.0));
    assert!((chord_distance(&Vector3::new(2.0, 1.25, 0.7), &a, &b) - 0.25).abs() < 1e-15);
    // The chord reversed flips the sign; a point on the chord gives zero.
    assert!((chord_distance(&Vector3::new(2.0, 1.25, 0.0), &b, &a) + 0.25).abs() < 1e-15);
    assert!(chord_distance(&Vector3::new(7.0, 1.0, 0.0), &a, &b).abs() < 1e-15);
}

#[test]
fn rod_mass_is_rho_a2_l() {
    let p = SliderCrank::C2;
    let body = rod_body(&p, p.rod, MESH, ModeSelection::Count(2), true).unwrap();
    let m = p.rho * p.side().powi(2) * p.rod;
    assert!(
        (body.inertia.mass - m).abs() < 1e-12 * m,
        "{} vs {m}",
        body.inertia.mass
    );
}

#[test]
fn midpoint_of_the_recovered_mesh() {
    let p = SliderCrank::C2;
    let L = p.rod;
    let body = rod_body(&p, L, MESH, ModeSelection::Count(2), true).unwrap();
    let place = Vector3::new(p.crank, 0.0, 0.0);
    let frame = FrameChoice::CenterOfMass;
    // A rigid motion (translation and a 0.7 rad turn about z) leaves the rod straight.
    let R = UnitQuaternion::from_scaled_axis(Vector3::z() * 0.7);
    let (rA, rB) = (
        Vector3::new(0.3, -0.2, 0.0),
        Vector3::new(0.3, -0.2, 0.0) + R * Vector3::new(L, 0.0, 0.0),
    );
    let q = R.scaled_axis();
    let w = midpoint_from_mesh(&body, frame, &place, &record(rA, rB, q, q, vec![0.0; 2])).unwrap();
    assert!(w[0].abs() < 1e-12 * L, "rigid motion gives {}", w[0]);
    // End B turned by a small theta about z with both ends in place: the clamped-clamped
    // beam's static shape w = theta L (xi^3 - xi^2) gives -theta L / 8 at mid-length
    // (constraint modes are exact statics). Slenderness L/a = 57: shear and the rigid RBE2
    // faces change it by well under 1 %, the 8-element hex20 mesh by less.
    let theta = 1e-5;
    let (a, b) = (place, place + Vector3::new(L, 0.0, 0.0));
    let rec = record(a, b, Vector3::zeros(), Vector3::z() * theta, vec![0.0; 2]);
    let w = midpoint_from_mesh(&body, frame, &place, &rec).unwrap()[0];
    let beam = -theta * L / 8.0;
    assert!(
        (w - beam).abs() < 0.01 * beam.abs(),
        "midpoint {w:e} vs beam theory {beam:e}"
    );
}

/// `Args::choice`: the first choice is the default, a given one is read, anything else is an
/// error that names the option and the choices.
#[test]
fn named_choices_default_read_and_refuse() {
    use flexmbs_benchmarks::Args;
    let choices = [("full", 1), ("modified", 2)];
    let args = |a: &[&str]| Args::from_args(a.iter().map(|s| s.to_string())).unwrap();
    assert_eq!(args(&[]).choice("newton", &choices).unwrap(), 1);
    assert_eq!(
        args(&["--newton", "modified", "--bench"])
            .choice("newton", &choices)
            .unwrap(),
        2
    );
    let err = args(&["--newton", "modifed"])
        .choice("newton", &choices)
        .unwrap_err()
        .to_string();
    assert_eq!(err, "argument '--newton': 'modifed' is not full or modified");
}
