// Physical checks of reduced bodies on load (`reduction::physics`): every tampered body below
// has valid checksums (written by `file::to_bytes`) and was accepted before the checks.

use fe_model::{DofMask, MassKind};
use reduction::file;
use reduction::{physical_problems, reduce, BodyFileProblem, CbSettings, ModeSelection, PhysicsProblem, ReducedBody, ReductionError};
use std::path::Path;

/// A free steel beam of 1 m along a skew axis, 6 elements, interfaces at both ends, 3 modes;
/// `clamped`: its first node supported in the FE model.
fn beam_body(clamped: bool) -> ReducedBody {
    let (mut model, nodes) = super::common::skew_steel_beam(6, super::common::d20(), MassKind::Consistent);
    let interfaces = if clamped {
        model.add_support(nodes[0], DofMask::ALL);
        vec![("B".to_string(), nodes[6])]
    } else {
        vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[6])]
    };
    let settings = CbSettings::new(ModeSelection::Count(3));
    reduce(&model, "beam", &interfaces, &settings).unwrap()
}

/// The problems `from_bytes` names for `body` written with valid checksums.
fn problems(body: &ReducedBody) -> Vec<PhysicsProblem> {
    let bytes = file::to_bytes(body, Path::new("t.rbody")).unwrap();
    match file::from_bytes(&bytes, Path::new("t.rbody")) {
        Ok(_) => Vec::new(),
        Err(ReductionError::BodyFile {
            problem: BodyFileProblem::Physics { problems },
            ..
        }) => problems,
        Err(e) => panic!("not a physics error: {e}"),
    }
}

fn set(A: &mut reduction::DenseMatrix, i: usize, j: usize, v: f64) {
    let n = A.nrows;
    A.data[i + j * n] = v;
}

#[test]
fn sound_bodies_pass_free_and_supported() {
    assert_eq!(physical_problems(&beam_body(false)), vec![]);
    // A body clamped in its FE model: fewer free rigid motions, allowed.
    assert_eq!(physical_problems(&beam_body(true)), vec![]);
    // The stored version-1 file of the format tests.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cantilever_v1.rbody");
    file::read(&path).unwrap();
}

#[test]
fn non_symmetric_stiffness_is_refused() {
    let mut b = beam_body(false);
    let v = b.K_CB.get(0, 1) + 0.1 * b.K_CB.get(0, 0);
    set(&mut b.K_CB, 0, 1, v);
    let p = problems(&b);
    assert!(
        p.iter().any(|p| matches!(p, PhysicsProblem::NotSymmetric { matrix: "K_CB", row: 0, col: 1, .. })),
        "{p:?}"
    );
    assert!(p[0].to_string().contains("K_CB is not symmetric"), "{}", p[0]);
}

#[test]
fn indefinite_stiffness_is_refused() {
    // A negative modal stiffness: omega^2 < 0 for the first fixed-interface mode.
    let mut b = beam_body(false);
    let i = 12;
    let v = -b.K_CB.get(i, i);
    set(&mut b.K_CB, i, i, v);
    let p = problems(&b);
    assert!(p.iter().any(|p| matches!(p, PhysicsProblem::StiffnessIndefinite { .. })), "{p:?}");
    // A symmetric change in the static block that makes a rigid motion strained and an
    // elastic one negative: K_00 -> -K_00.
    let mut b = beam_body(false);
    let v = -b.K_CB.get(0, 0);
    set(&mut b.K_CB, 0, 0, v);
    let p = problems(&b);
    assert!(p.iter().any(|p| matches!(p, PhysicsProblem::StiffnessIndefinite { .. })), "{p:?}");
}

#[test]
fn a_mechanism_is_refused() {
    // A zero modal stiffness: a deformation without strain energy.
    let mut b = beam_body(false);
    set(&mut b.K_CB, 13, 13, 0.0);
    b.fixed_interface_omega[1] = 0.0;
    let p = problems(&b);
    assert_eq!(p, vec![PhysicsProblem::Mechanism { count: 1, largest: match &p[0] { PhysicsProblem::Mechanism { largest, .. } => *largest, _ => f64::NAN } }], "{p:?}");
}

#[test]
fn non_positive_modal_mass_is_refused() {
    for v in [-1.0, 0.0] {
        let mut b = beam_body(false);
        set(&mut b.M_CB, 14, 14, v);
        let p = problems(&b);
        assert!(p.contains(&PhysicsProblem::ModalMass { mode: 3, value: v }), "{p:?}");
    }
    // An indefinite mass matrix with positive diagonal: a 2x2 block with a too large coupling.
    let mut b = beam_body(false);
    let c = 2.0 * (b.M_CB.get(12, 12) * b.M_CB.get(13, 13)).sqrt();
    set(&mut b.M_CB, 12, 13, c);
    set(&mut b.M_CB, 13, 12, c);
    assert!(problems(&b).contains(&PhysicsProblem::MassIndefinite));
}

#[test]
fn metadata_that_contradicts_the_matrices_is_refused() {
    let what = |p: &[PhysicsProblem]| -> Vec<String> {
        p.iter()
            .filter_map(|p| match p {
                PhysicsProblem::Metadata { what, .. } => Some(what.clone()),
                _ => None,
            })
            .collect()
    };
    let mut b = beam_body(false);
    b.inertia.mass *= 1.1;
    assert_eq!(what(&problems(&b)), vec!["mass".to_string()]);
    let mut b = beam_body(false);
    b.inertia.center_of_mass[1] += 0.01;
    assert_eq!(what(&problems(&b)), vec!["centre of mass [y]".to_string()]);
    let mut b = beam_body(false);
    b.inertia.inertia_com[2][2] *= 1.01;
    assert_eq!(what(&problems(&b)), vec!["inertia about the centre of mass [zz]".to_string()]);
    let mut b = beam_body(false);
    b.fixed_interface_omega[2] *= 1.001;
    let p = problems(&b);
    assert!(matches!(p.as_slice(), [PhysicsProblem::Frequency { mode: 3, .. }]), "{p:?}");
}

#[test]
fn coincident_and_duplicate_interfaces_are_refused() {
    let mut b = beam_body(false);
    b.interfaces[1].name = "A".into();
    assert_eq!(problems(&b), vec![PhysicsProblem::DuplicateName { name: "A".into() }]);
    let mut b = beam_body(false);
    b.interfaces[1].position = b.interfaces[0].position;
    let p = problems(&b);
    assert!(
        p.iter().any(|p| matches!(p, PhysicsProblem::Coincident { a, b, .. } if a == "A" && b == "B")),
        "{p:?}"
    );
}
