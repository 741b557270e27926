//! A flexible body through an MBDyn `.fem` file and back (`reduction::mbdyn`) in a mechanism.

use crate::fixtures::beam_body;
use mbs::{solve_static, spectrum, JointKind, Model, StaticSettings, Support, System};
use nalgebra::{Isometry3, Vector3};
use reduction::mbdyn::{parse_mbdyn_fem, to_mbdyn_fem};
use reduction::{ModeSelection, ReducedBody};
use std::path::Path;
use superelement::{FrameChoice, MassVariant};

/// Two flexible beams along x, each clamped at its outer end and joined by a revolute joint
/// about z at x = 1, sagging under gravity (-y): the lowest frequencies of the linearised
/// motion about the static state (which the second-order mass invariants enter, through the
/// sag).
fn hinged_beams_frequencies(left: ReducedBody, right: ReducedBody) -> Vec<f64> {
    let mut m = Model::new("hinged beams");
    let a = m.add_node("a", Vector3::zeros());
    let b_left = m.add_node("b left", Vector3::new(1.0, 0.0, 0.0));
    let b_right = m.add_node("b right", Vector3::new(1.0, 0.0, 0.0));
    let c = m.add_node("c", Vector3::new(1.6, 0.0, 0.0));
    m.add_support(Support::clamp(a));
    m.add_support(Support::clamp(c));
    m.add_joint("hinge", b_left, b_right, JointKind::Revolute { axis: Vector3::z() });
    m.add_flexible_body(
        left,
        vec![a, b_left],
        Isometry3::identity(),
        FrameChoice::CenterOfMass,
        MassVariant::Exact,
    );
    m.add_flexible_body(
        right,
        vec![b_right, c],
        Isometry3::identity(),
        FrameChoice::InterfaceNode(0),
        MassVariant::Exact,
    );
    m.gravity = Vector3::new(0.0, -9.81, 0.0);
    let sys = System::new(&m).unwrap();
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(1)).unwrap();
    spectrum(&sys, &sol.state).unwrap().omega
}

/// Writes `body` to MBDyn's format with interface `reference` held and reads it back.
fn through_fem(body: &ReducedBody, reference: usize) -> ReducedBody {
    let text = to_mbdyn_fem(body, reference, Path::new("body.fem")).unwrap();
    parse_mbdyn_fem(text.as_bytes(), Path::new("body.fem"), None).unwrap().0
}

#[test]
fn a_body_through_an_mbdyn_file_gives_the_same_linearised_frequencies() {
    let beam = |name: &str, a: f64, b: f64, elements: usize, side: f64, modes: usize| {
        let (a, b) = (Vector3::new(a, 0.0, 0.0), Vector3::new(b, 0.0, 0.0));
        beam_body(name, a, b, elements, side, 2.1e11, 7850.0, ModeSelection::Count(modes))
    };
    let left = beam("left", 0.0, 1.0, 6, 0.02, 3);
    let right = beam("right", 1.0, 1.6, 4, 0.015, 2);
    let original = hinged_beams_frequencies(left.clone(), right.clone());
    let back = hinged_beams_frequencies(through_fem(&left, 0), through_fem(&right, 1));
    assert_eq!(original.len(), back.len());
    assert!(original[0] > 10.0, "bending of the hinged beams: {original:?}");
    // 1e-10: the read-back bodies span the same space with the same interface coordinates;
    // their matrices differ from the originals by the round-off of the change of basis
    // (about 1e-13 of the largest entries), which the eigensolution amplifies by at most the
    // spread of the spectrum, (w_max / w_min)^2 < 1e5 here: below 1e-10 for every frequency.
    // (A gravity pendulum, whose 3 rad/s sits under 2e4 rad/s bending modes, cannot be
    // compared that closely: the solver alone moves its lowest frequency by a few 1e-9.)
    for (w, v) in original.iter().zip(&back) {
        assert!(((w - v) / w).abs() < 1e-10, "{w} vs {v}: {original:?} {back:?}");
    }
}
