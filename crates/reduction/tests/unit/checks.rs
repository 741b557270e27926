// `reduction::checks` on the sources other than `.rbody` files (those are in `physics.rs`):
// MBDyn `.fem` records edited one at a time, and node tables of matrices from another code.

use fe_model::{assemble, DofMap, DofMask, MassKind, SystemPattern};
use reduction::checks::{node_table_problems, BodyCheckError, PhysicsProblem};
use reduction::mbdyn::{parse_mbdyn_fem, to_mbdyn_fem, FemError};
use reduction::{reduce, CbSettings, ModeSelection, ReducedBody};
use std::path::Path;

/// The free skew beam of the physics tests, interfaces `A` and `B` at its ends, 3 modes.
fn beam_body() -> ReducedBody {
    let (model, nodes) = super::common::skew_steel_beam(6, super::common::d20(), MassKind::Consistent);
    let interfaces = vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[6])];
    let mut settings = CbSettings::new(ModeSelection::Count(3));
    settings.keep_mesh_shapes = false;
    reduce(&model, "beam", &interfaces, &settings).unwrap()
}

/// The beam written as an MBDyn file with `edit` applied to line `line` (0-based) of the
/// values of record `record`.
fn edited_fem(record: u32, line: usize, edit: &dyn Fn(&str) -> String) -> String {
    let text = to_mbdyn_fem(&beam_body(), 0, Path::new("beam.fem")).unwrap();
    let mut out = Vec::new();
    let mut in_record = false;
    let mut value_line = 0;
    for l in text.lines() {
        if l.starts_with("** RECORD GROUP ") {
            in_record = l.starts_with(&format!("** RECORD GROUP {record},"));
            value_line = 0;
            out.push(l.to_string());
        } else if in_record && !l.starts_with("**") {
            out.push(if value_line == line { edit(l) } else { l.to_string() });
            value_line += 1;
        } else {
            out.push(l.to_string());
        }
    }
    out.join("\n") + "\n"
}

/// The problems the checks name for `text`, and the message.
fn refused(text: &str) -> (Vec<PhysicsProblem>, String) {
    match parse_mbdyn_fem(text.as_bytes(), Path::new("beam.fem"), None) {
        Err(FemError::Checks(e)) => {
            let message = e.to_string();
            match e {
                BodyCheckError::Refused { problems, body, file } => {
                    assert_eq!((body.as_str(), file.as_path()), ("beam", Path::new("beam.fem")));
                    (problems, message)
                }
                other => panic!("{other}"),
            }
        }
        Ok(_) => panic!("accepted"),
        Err(e) => panic!("not refused by the checks: {e}"),
    }
}

/// Each value of `line` through `f` (index, value).
fn map_values(line: &str, f: &dyn Fn(usize, f64) -> f64) -> String {
    line.split_whitespace()
        .enumerate()
        .map(|(k, v)| format!("{:.17e}", f(k, v.parse::<f64>().unwrap())))
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn a_sound_fem_file_passes() {
    let text = edited_fem(12, 0, &|l| l.to_string());
    parse_mbdyn_fem(text.as_bytes(), Path::new("beam.fem"), None).unwrap();
}

#[test]
fn a_wrong_record_12_mass_is_refused() {
    // The mass 12.5 times too small, as a hand-edited record 12 would have it.
    let text = edited_fem(12, 0, &|l| map_values(l, &|_, m| m / 12.5));
    let (problems, message) = refused(&text);
    assert!(
        problems.iter().any(|p| matches!(p, PhysicsProblem::Stated { what, .. } if what == "record 12 mass")),
        "{problems:?}"
    );
    assert!(message.contains("beam.fem") && message.contains("record 12 mass"), "{message}");
}

#[test]
fn a_non_symmetric_modal_stiffness_is_refused() {
    let text = edited_fem(10, 0, &|l| {
        let d = l.split_whitespace().next().unwrap().parse::<f64>().unwrap();
        map_values(l, &|k, v| if k == 1 { v + 0.1 * d.abs() } else { v })
    });
    let (problems, message) = refused(&text);
    assert!(
        problems
            .iter()
            .any(|p| matches!(p, PhysicsProblem::NotSymmetric { matrix: "record 10 (modal stiffness)", row: 0, col: 1, .. })),
        "{problems:?}"
    );
    assert!(message.contains("record 10 (modal stiffness) is not symmetric"), "{message}");
}

#[test]
fn an_indefinite_modal_mass_is_refused() {
    // A symmetric change that makes the mass of the first kept coordinate negative.
    let text = edited_fem(9, 0, &|l| map_values(l, &|k, v| if k == 0 { -v } else { v }));
    match parse_mbdyn_fem(text.as_bytes(), Path::new("beam.fem"), None) {
        Err(FemError::Checks(BodyCheckError::Refused { problems, .. })) => assert!(
            problems
                .iter()
                .any(|p| matches!(p, PhysicsProblem::MassIndefinite | PhysicsProblem::ModalMass { .. })),
            "{problems:?}"
        ),
        other => panic!("{:?}", other.map(|_| ())),
    }
}

#[test]
fn coincident_and_duplicate_interfaces_are_refused() {
    // Interface B (second exposed node) moved onto A, the reference at the frame origin.
    let mut text = to_mbdyn_fem(&beam_body(), 0, Path::new("beam.fem")).unwrap();
    for record in 5..=7 {
        let edited = edited_fem(record, 1, &|_| "0.0".into());
        // Apply record by record: each edit starts from the written file.
        let header = format!("** RECORD GROUP {record},");
        let at = edited.find(&header).unwrap();
        let end = at + edited[at..].find("**\n").unwrap();
        let (a, b) = (text.find(&header).unwrap(), text.find(&header).unwrap());
        let old_end = b + text[b..].find("**\n").unwrap();
        text.replace_range(a..old_end, &edited[at..end]);
    }
    let (problems, message) = refused(&text);
    assert!(
        problems.iter().any(|p| matches!(p, PhysicsProblem::Coincident { a, b, .. } if a == "A" && b == "B")),
        "{problems:?}"
    );
    assert!(message.contains("interfaces 'A' and 'B' coincide"), "{message}");

    let text = edited_fem(2, 0, &|_| "A A".into());
    let (problems, message) = refused(&text);
    assert!(
        problems.iter().any(|p| matches!(p, PhysicsProblem::DuplicateName { name } if name == "A")),
        "{problems:?}"
    );
    assert!(message.contains("two interfaces are named 'A'"), "{message}");
}

/// Matrices from another code: K, the node table and the dof table.
type Exported = (faer::sparse::SparseColMat<usize, f64>, Vec<[f64; 3]>, Vec<(usize, usize)>);

/// The skew beam's assembled K, its node table and dof table, `clamped`: node 0 supported
/// (its dofs left out of the matrices).
fn beam_matrices(clamped: bool) -> Exported {
    let (mut model, nodes) = super::common::skew_steel_beam(6, super::common::d20(), MassKind::Consistent);
    if clamped {
        model.add_support(nodes[0], DofMask::ALL);
    }
    let dofs = DofMap::new(&model).unwrap();
    let a = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap();
    let table = (0..dofs.n_free())
        .map(|d| {
            let slot = dofs.full_slot(fe_model::Dof(d as u32));
            (slot / 6, slot % 6)
        })
        .collect();
    let xyz = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    (a.K, xyz, table)
}

#[test]
fn node_tables_that_match_k_pass_free_and_supported() {
    for clamped in [false, true] {
        let (K, nodes, dofs) = beam_matrices(clamped);
        assert_eq!(node_table_problems(&nodes, K.as_ref(), &dofs), vec![], "clamped {clamped}");
    }
}

#[test]
fn a_node_table_in_millimetres_is_refused() {
    for clamped in [false, true] {
        let (K, nodes, dofs) = beam_matrices(clamped);
        let mm: Vec<[f64; 3]> = nodes.iter().map(|x| x.map(|c| 1e3 * c)).collect();
        let problems = node_table_problems(&mm, K.as_ref(), &dofs);
        assert!(
            problems
                .iter()
                .any(|p| matches!(p, PhysicsProblem::RigidMotionStrained { nodes, .. } if *nodes >= 5)),
            "clamped {clamped}: {problems:?}"
        );
        assert!(problems[0].to_string().contains("other units than m"), "{}", problems[0]);
    }
}

#[test]
fn coincident_nodes_in_a_node_table_are_refused() {
    // The tip node listed at the position of the node before it.
    let (K, mut nodes, dofs) = beam_matrices(false);
    nodes[6] = nodes[5];
    let problems = node_table_problems(&nodes, K.as_ref(), &dofs);
    assert!(
        problems
            .iter()
            .any(|p| matches!(p, PhysicsProblem::RigidMotionStrained { node, .. } if *node == 5 || *node == 6)),
        "{problems:?}"
    );
}
