// `reduction::checks` on the sources other than `.rbody` files (those are in `physics.rs`):
// MBDyn `.fem` records edited one at a time (record 12 against the nodal masses of record 11
// on the manual's example), and node tables of matrices from another code (against K, and
// against the mass of M: a table in millimetres of a solid mesh).

use fe_model::{assemble, DofMap, DofMask, MassKind, SystemPattern};
use reduction::checks::{node_table_problems, BodyCheckError, NodeCloud, PhysicsProblem, MIN_DENSITY};
use reduction::mbdyn::{parse_mbdyn_fem, parse_mbdyn_fem_unchecked, to_mbdyn_fem, FemError};
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

/// The manual's example (record 11: three unit masses and inertias at y = -2, 0, 2) with
/// `record_12` as its record 12 (mass; centre of mass; inertia rows).
fn manual_with_record_12(record_12: &str) -> String {
    format!(
        "{}**\n** RECORD GROUP 12, GLOBAL INERTIA\n{record_12}**\n",
        super::mbdyn::MANUAL_EXAMPLE
    )
}

/// What the manual states for its example: m = 3, centre at the origin, J = diag(11, 3, 11).
const MANUAL_RECORD_12: &str = "3\n0 0 0\n11 0 0\n0 3 0\n0 0 11\n";

fn read_manual(text: &str) -> Result<reduction::mbdyn::FemBody, FemError> {
    parse_mbdyn_fem_unchecked(text.as_bytes(), Path::new("manual.fem"), Some(&["1002".to_string()]))
}

#[test]
fn a_record_12_that_agrees_with_the_nodal_masses_passes() {
    let text = manual_with_record_12(MANUAL_RECORD_12);
    let read = read_manual(&text).unwrap();
    assert_eq!(read.problems, vec![]);
    assert_eq!(read.not_checked, Vec::<String>::new());
    parse_mbdyn_fem(text.as_bytes(), Path::new("manual.fem"), Some(&["1002".to_string()])).unwrap();
    // Within the stated tolerances: the mass 0.05 % off, the inertia 5 % off.
    let text = manual_with_record_12("3.0015\n0 0 0\n11.5 0 0\n0 3 0\n0 0 11\n");
    assert_eq!(read_manual(&text).unwrap().problems, vec![]);
}

#[test]
fn a_record_12_that_contradicts_the_nodal_masses_is_refused() {
    // Each edit, the value it names, the stated and the computed value.
    let cases = [
        ("30\n0 0 0\n11 0 0\n0 3 0\n0 0 11\n", "record 12 mass", 30.0, 3.0),
        (
            "3\n0 0.5 0\n11 0 0\n0 3 0\n0 0 11\n",
            "record 12 centre of mass [y] from the frame origin",
            0.5,
            0.0,
        ),
        (
            "3\n0 0 0\n11 0 0\n0 3 0\n0 0 22\n",
            "record 12 inertia about the centre of mass [zz]",
            22.0,
            11.0,
        ),
    ];
    for (record_12, name, value, computed) in cases {
        let text = manual_with_record_12(record_12);
        let problems = read_manual(&text).unwrap().problems;
        assert!(
            problems.iter().any(|p| matches!(p, PhysicsProblem::Stated { what, stated, implied, by }
                if what == name && *stated == value && (implied - computed).abs() < 1e-12 && by.contains("record 11"))),
            "{name}: {problems:?}"
        );
        match parse_mbdyn_fem(text.as_bytes(), Path::new("manual.fem"), Some(&["1002".to_string()])) {
            Err(FemError::Checks(e)) => {
                let message = e.to_string();
                assert!(
                    message.contains("manual.fem") && message.contains(name) && message.contains("record 11"),
                    "{message}"
                );
            }
            other => panic!("{name}: {:?}", other.map(|_| ())),
        }
    }
}

#[test]
fn a_record_12_without_nodal_masses_is_reported_as_not_compared() {
    // Written by flexmbs: no record 11; the first moment still checks mass and centre.
    let text = to_mbdyn_fem(&beam_body(), 0, Path::new("beam.fem")).unwrap();
    let read = parse_mbdyn_fem_unchecked(text.as_bytes(), Path::new("beam.fem"), None).unwrap();
    assert_eq!(read.problems, vec![]);
    assert_eq!(read.not_checked.len(), 1, "{:?}", read.not_checked);
    assert!(
        read.not_checked[0].contains("no record 11") && read.not_checked[0].contains("FLEXMBS FIRST MOMENT"),
        "{}",
        read.not_checked[0]
    );
    // Without the FLEXMBS lines nothing checks record 12.
    let bare: String = text.lines().filter(|l| !l.starts_with("** FLEXMBS")).map(|l| format!("{l}\n")).collect();
    let read = parse_mbdyn_fem_unchecked(bare.as_bytes(), Path::new("beam.fem"), None).unwrap();
    assert!(read.not_checked[0].contains("are not checked"), "{:?}", read.not_checked);
    // ... and a study loading it is told (the notes become its warnings); flexmbs's own file
    // above adds no note.
    assert_eq!(read.notes, read.not_checked);
    let own = parse_mbdyn_fem_unchecked(text.as_bytes(), Path::new("beam.fem"), None).unwrap();
    assert!(own.notes.iter().all(|n| !n.contains("record 12")), "{:?}", own.notes);
    // Record 11 alone: the mass data are its own, nothing to compare.
    let read = read_manual(super::mbdyn::MANUAL_EXAMPLE).unwrap();
    assert_eq!(read.not_checked, Vec::<String>::new());
}

/// A free steel block [0, 0.4] x [0, 0.1] x [0, 0.05] of hex8 solids: K, M (three
/// translations per node), node table and dof table.
fn solid_matrices() -> (Exported, faer::sparse::SparseColMat<usize, f64>) {
    let mesh = fe_model::box_mesh::box_mesh(fe_model::CellKind::Hex8, [0.4, 0.1, 0.05], [8, 2, 1]).unwrap();
    let steel = fe_model::IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap();
    let model = fe_model::box_mesh::solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let dofs = DofMap::new(&model).unwrap();
    let a = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap();
    let table = (0..dofs.n_free())
        .map(|d| {
            let slot = dofs.full_slot(fe_model::Dof(d as u32));
            (slot / 6, slot % 6)
        })
        .collect();
    let xyz = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    ((a.K, xyz, table), a.M)
}

#[test]
fn the_node_cloud_of_a_solid_in_metres_has_the_density_of_its_material() {
    let ((_, nodes, dofs), M) = solid_matrices();
    let cloud = NodeCloud::new(&nodes, M.as_ref(), &dofs);
    // A full box: the bound is the density, to round-off of the assembled mass.
    assert!((cloud.density_bound - 7850.0).abs() < 1e-9 * 7850.0, "{cloud:?}");
    assert_eq!(cloud.problem(), None);
    // A skew beam: its nodes lie on a line, which spans no volume along the principal axes
    // (a bound far above any material), though the axis-aligned box around them has one.
    let (model, _) = super::common::skew_steel_beam(6, super::common::d20(), MassKind::Consistent);
    let (_, nodes, dofs) = beam_matrices(false);
    let map = DofMap::new(&model).unwrap();
    let M = assemble(&model, &SystemPattern::new(&model, &map)).unwrap().M;
    let cloud = NodeCloud::new(&nodes, M.as_ref(), &dofs);
    assert!(cloud.density_bound > 1e6, "{cloud:?}");
    assert_eq!(cloud.problem(), None);
}

#[test]
fn a_solid_node_table_in_millimetres_is_refused_by_the_mass() {
    let ((K, nodes, dofs), M) = solid_matrices();
    let mm: Vec<[f64; 3]> = nodes.iter().map(|x| x.map(|c| 1e3 * c)).collect();
    // The rigid motions of K do not see a uniform scale of three-dof nodes ...
    assert_eq!(node_table_problems(&mm, K.as_ref(), &dofs), vec![]);
    // ... the mass over the volume does: 7850 kg/m^3 becomes 7.85e-6.
    let cloud = NodeCloud::new(&mm, M.as_ref(), &dofs);
    assert!((cloud.density_bound - 7.85e-6).abs() < 1e-9 * 7.85e-6, "{cloud:?}");
    let problem = cloud.problem().unwrap();
    assert!(
        matches!(problem, PhysicsProblem::ImplausibleDensity { density, .. } if density < MIN_DENSITY),
        "{problem:?}"
    );
    let message = problem.to_string();
    assert!(message.contains("node table") && message.contains("millimetres"), "{message}");
}

#[test]
fn a_node_cloud_with_a_non_finite_coordinate_ends() {
    // The readers refuse such tables; the measure itself must still return (no endless
    // eigensolver iteration, no problem claimed on a NaN).
    let ((_, mut nodes, dofs), M) = solid_matrices();
    nodes[3] = [f64::NAN, 0.0, f64::INFINITY];
    let cloud = NodeCloud::new(&nodes, M.as_ref(), &dofs);
    assert_eq!(cloud.problem(), None, "{cloud:?}");
}
