//! Abaqus and Nastran readers (`fe_model::mesh::abaqus`, `fe_model::mesh::nastran`).
//!
//! * The fixtures of `tests/data/import` (written by `make_fixtures.py` with meshio from the
//!   gmsh fixtures) give the gmsh mesh's cells node for node, and the same frequencies of the
//!   clamped solid with a tip RBE2 spider as the gmsh file, to 1e-10; node sets, materials,
//!   supports and spiders come through.
//! * Inline cases: continuation lines, GENERATE, case, *BOUNDARY, beams; Nastran small, large
//!   and free field, exponent shorthand, CORD2R, THRU, WTMASS, MAT1 from E and G, RBE3,
//!   elements of the other handedness, cards listed once as ignored.
//! * Each malformed input gives its located error (file, line, entity): twelve kinds per
//!   format.
//! * `hex8_large.bdf` (`to_large_field.py`: `hex8_small.bdf` in large field with `*N<k>`
//!   continuation markers) and its forms with blank and `+` continuations and commas give the
//!   small-field twin's mesh, supports, spiders and frequencies.
//! * Bounds: GENERATE and THRU ranges longer than the deck, sets of sets, included files
//!   (fifteen files each including the next four times) and an included file past the byte
//!   budget each give a located limit error after work bounded by the deck, where the
//!   unbounded readers allocated terabytes or read for minutes.
//! * No panic on random bytes, on every prefix of every fixture, or on mutated fixtures.

use fe_model::mesh::import::{ImportError, ImportedModel};
use fe_model::mesh::{abaqus, gmsh, nastran};
use fe_model::units::UnitSystem;
use fe_model::{
    add_interface, modal_dense, solid_model_with_materials, CellKind, DofMask, FeModel, IsotropicMaterial, MassKind,
    Mesh, NodeId, SpiderKind,
};
use nalgebra::Point3;
use std::path::{Path, PathBuf};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

const MESHES: [&str; 5] = ["hex8", "hex20", "tet4", "tet10", "wedge6"];

fn steel() -> IsotropicMaterial {
    IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap()
}

/// The tip centre, where the fixtures' RBE2 puts its independent grid.
fn tip_centre() -> Point3<f64> {
    Point3::new(1.0, 0.1, 0.1)
}

/// The solid clamped at `clamp` with an RBE2 interface at the tip centre on `tip`.
fn clamped_with_tip(mut model: FeModel, clamp: &[NodeId], tip: &[NodeId]) -> FeModel {
    for &n in clamp {
        model.add_support(n, DofMask::TRANSLATIONS);
    }
    add_interface(&mut model, "tip", tip, Some(tip_centre()), SpiderKind::Rbe2).unwrap();
    model
}

fn frequencies(model: &FeModel) -> Vec<f64> {
    modal_dense(model, 8).unwrap().omega
}

fn gmsh_model(name: &str) -> (Mesh, FeModel) {
    let mesh = gmsh::read(&data_dir().join(format!("gmsh/{name}_41.msh"))).unwrap();
    let model = solid_model_with_materials(mesh.clone(), &[("body", steel())], MassKind::Consistent).unwrap();
    let (clamp, tip) = (mesh.node_sets["clamp"].clone(), mesh.node_sets["tip"].clone());
    (mesh, clamped_with_tip(model, &clamp, &tip))
}

fn abaqus_fixture(name: &str) -> ImportedModel {
    abaqus::read(&data_dir().join(format!("import/{name}.inp")), UnitSystem::Si).unwrap_or_else(|e| panic!("{e}"))
}

fn nastran_fixture(file: &str) -> ImportedModel {
    nastran::read(&data_dir().join(format!("import/{file}")), UnitSystem::Si).unwrap_or_else(|e| panic!("{e}"))
}

fn abaqus_model(imported: &ImportedModel) -> FeModel {
    let model = imported.to_fe_model(MassKind::Consistent, None).unwrap();
    let (clamp, tip) = (
        imported.mesh.node_sets["clamp"].clone(),
        imported.mesh.node_sets["tip"].clone(),
    );
    clamped_with_tip(model, &clamp, &tip)
}

fn nastran_model(imported: &ImportedModel) -> FeModel {
    let mut model = imported.to_fe_model(MassKind::Consistent, None).unwrap();
    for s in &imported.supports {
        for &n in &s.nodes {
            model.add_support(n, s.dofs);
        }
    }
    for s in &imported.spiders {
        add_interface(&mut model, &s.name, &s.surface, Some(s.position), s.kind).unwrap();
    }
    model
}

/// Largest relative difference of two spectra.
fn spectrum_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(x, y)| ((x - y) / x).abs()).fold(0.0, f64::max)
}

/// The volume cells of a mesh, as (kind, nodes).
fn volume_cells(mesh: &Mesh) -> Vec<(CellKind, Vec<NodeId>)> {
    mesh.cells
        .iter()
        .filter(|c| c.kind.dimension() == 3)
        .map(|c| (c.kind, c.nodes.clone()))
        .collect()
}

// ------------------------------------------------------------------------------------ fixtures

// 1e-10: the models are the same but for coordinates that the Nastran large field rounds to 15
// digits (tet4's 1/3), a relative change of 1e-15 in the geometry; the frequencies of the
// gmsh and Abaqus files, which hold the same doubles, agree to round-off.
const SAME_SPECTRUM: f64 = 1e-10;

#[test]
fn the_same_solid_gives_the_same_frequencies_from_gmsh_abaqus_and_nastran() {
    for name in MESHES {
        let (_, reference) = gmsh_model(name);
        let f_gmsh = frequencies(&reference);
        let f_abaqus = frequencies(&abaqus_model(&abaqus_fixture(name)));
        let f_nastran = frequencies(&nastran_model(&nastran_fixture(&format!("{name}.bdf"))));
        let d_abaqus = spectrum_difference(&f_gmsh, &f_abaqus);
        let d_nastran = spectrum_difference(&f_gmsh, &f_nastran);
        assert!(d_abaqus < SAME_SPECTRUM, "{name}: Abaqus differs by {d_abaqus:e}");
        assert!(d_nastran < SAME_SPECTRUM, "{name}: Nastran differs by {d_nastran:e}");
        assert!(f_gmsh[0] > 100.0, "{name}: a clamped steel bar, {f_gmsh:?}");
    }
    for (file, name) in [("hex8_small.bdf", "hex8"), ("tet10_free.bdf", "tet10")] {
        let f_gmsh = frequencies(&gmsh_model(name).1);
        let f = frequencies(&nastran_model(&nastran_fixture(file)));
        let d = spectrum_difference(&f_gmsh, &f);
        assert!(d < SAME_SPECTRUM, "{file}: differs by {d:e}");
    }
}

#[test]
fn fixtures_give_gmsh_cells_node_for_node_and_their_sets_and_materials() {
    for name in MESHES {
        let (mesh, _) = gmsh_model(name);
        let a = abaqus_fixture(name);
        let n = nastran_fixture(&format!("{name}.bdf"));
        // meshio keeps node and cell order: the same cells in our ordering.
        assert_eq!(volume_cells(&a.mesh), volume_cells(&mesh), "{name}: Abaqus cells");
        assert_eq!(volume_cells(&n.mesh), volume_cells(&mesh), "{name}: Nastran cells");
        assert_eq!(a.mesh.nodes[..mesh.nodes.len()], mesh.nodes[..], "{name}: Abaqus nodes");
        // Node sets: Abaqus by name; Nastran as the SPC1 and RBE2 sets.
        assert_eq!(a.mesh.node_sets["clamp"], mesh.node_sets["clamp"], "{name}");
        assert_eq!(a.mesh.node_sets["tip"], mesh.node_sets["tip"], "{name}");
        assert_eq!(n.mesh.node_sets["SPC1_1"], mesh.node_sets["clamp"], "{name}");
        assert_eq!(n.mesh.node_sets["RBE2_2"], mesh.node_sets["tip"], "{name}");
        assert_eq!(n.supports.len(), 1);
        assert_eq!(n.supports[0].dofs, DofMask::TRANSLATIONS);
        assert_eq!(n.spiders.len(), 1);
        assert_eq!(n.spiders[0].kind, SpiderKind::Rbe2);
        assert_eq!(n.spiders[0].position, tip_centre());
        // Materials and sections.
        assert_eq!(a.materials, vec![steel()]);
        assert_eq!(a.solid_sections.len(), 1);
        assert_eq!(a.solid_sections[0].cell_set, "body");
        let m = n.material("MAT1_1").unwrap();
        assert_eq!((m.E(), m.nu(), m.rho()), (2.1e11, 0.3, 7850.0));
        assert_eq!(n.solid_sections[0].cell_set, "PSOLID_1");
        // Skipped: meshio's *HEADING; the EIGRL card.
        assert_eq!(a.ignored.len(), 1, "{name}: {:?}", a.ignored);
        assert_eq!(a.ignored[0].name, "*HEADING");
        assert_eq!(n.ignored.len(), 1, "{name}: {:?}", n.ignored);
        assert_eq!((n.ignored[0].name.as_str(), n.ignored[0].count), ("EIGRL", 1));
        assert!(n.notes.is_empty(), "{:?}", n.notes);
    }
}

// ------------------------------------------------------------------------------------ inline Abaqus

fn abaqus_inline(text: &str) -> Result<ImportedModel, ImportError> {
    abaqus::parse(text, Path::new("inline.inp"), UnitSystem::Si)
}

const ABAQUS_HEX: &str = "*Node, nset=ALLN
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 1
6, 1, 0, 1
7, 1, 1, 1
8, 0, 1, 1
*element, type=c3d8, elset=Block
11, 1, 2, 3, 4,
5, 6, 7, 8
*nset, nset=Bottom, generate
1, 4, 1
*Nset, nset=Top
5, 6
7, 8
*Nset, nset=both
bottom, TOP
*Material, name=Alu
*Elastic
70e9, 0.33
*Density
2700.
*Solid Section, elset=BLOCK, material=alu
*Boundary
bottom, ENCASTRE
8, 1, 2
*Step
*Static
*Boundary
top, 3, 3, 0.001
*End Step
";

#[test]
fn abaqus_continuation_generate_case_and_boundaries() {
    let m = abaqus_inline(ABAQUS_HEX).unwrap();
    assert_eq!(m.mesh.cells.len(), 1);
    assert_eq!(m.mesh.cells[0].kind, CellKind::Hex8);
    assert_eq!(m.mesh.cells[0].tag, 11);
    let ids = |v: &[u32]| v.iter().map(|&i| NodeId(i)).collect::<Vec<_>>();
    assert_eq!(m.mesh.node_sets["Bottom"], ids(&[0, 1, 2, 3]));
    assert_eq!(m.mesh.node_sets["both"], ids(&[0, 1, 2, 3, 4, 5, 6, 7]));
    assert_eq!(
        m.mesh.node_sets["Block"],
        ids(&[0, 1, 2, 3, 4, 5, 6, 7]),
        "an element set's nodes"
    );
    assert_eq!(m.solid_sections[0].cell_set, "Block");
    assert_eq!(m.solid_sections[0].material, "Alu");
    assert_eq!(m.supports.len(), 2);
    assert_eq!(m.supports[0].name, "Bottom");
    assert_eq!(m.supports[0].dofs, DofMask::ALL);
    assert_eq!(m.supports[1].nodes, ids(&[7]));
    assert_eq!(m.supports[1].dofs, DofMask([true, true, false, false, false, false]));
    // The step (with its non-zero boundary condition) is skipped and listed.
    assert_eq!(m.ignored.len(), 1);
    assert!(m.ignored[0].name.starts_with("*STEP"));
    let model = m.to_fe_model(MassKind::Consistent, None).unwrap();
    assert_eq!(model.elements.len(), 1);
    // The study can replace the file's material.
    let other = IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap();
    let model = m
        .to_fe_model(MassKind::Consistent, Some(&[("Block", other.clone())]))
        .unwrap();
    assert_eq!(model.materials, vec![other]);
}

#[test]
fn abaqus_beams_get_their_section_and_orientation() {
    let text = "*NODE
1, 0., 0., 0.
2, 0.5, 0., 0.
3, 1., 0., 0.
*ELEMENT, TYPE=B31, ELSET=beam
1, 1, 2
2, 2, 3
*MATERIAL, NAME=steel
*ELASTIC
2.1e11, 0.3
*DENSITY
7850.
*BEAM SECTION, ELSET=beam, MATERIAL=steel, SECTION=RECT
0.02, 0.01
0., 1., 0.
";
    let m = abaqus_inline(text).unwrap();
    let model = m.to_fe_model(MassKind::Consistent, None).unwrap();
    assert_eq!(model.elements.len(), 2);
    let s = &model.sections[0];
    // RECT a, b: a along n1 (local y), b along n2 (local z): Iy = a b^3 / 12.
    assert!((s.A() - 2e-4).abs() < 1e-18);
    assert!((s.Iy() - 0.02 * 1e-6 / 12.0).abs() < 1e-20);
    assert!((s.Iz() - 0.01 * 8e-6 / 12.0).abs() < 1e-20);
    match &model.elements[0] {
        fe_model::Element::Beam2(b) => assert_eq!(b.orientation, nalgebra::Vector3::new(0.0, 1.0, 0.0)),
        other => panic!("{other:?}"),
    }
}

// ------------------------------------------------------------------------------------ inline Nastran

fn nastran_inline(text: &str) -> Result<ImportedModel, ImportError> {
    nastran::parse(text, Path::new("inline.bdf"), UnitSystem::Si)
}

#[test]
fn a_contradictory_mat1_in_mm_t_s_is_quoted_in_the_decks_units() {
    // E = 210000 MPa and NU = 0.3 give G = 80769 MPa; the card says 50000. The message quotes
    // the numbers as written in the deck (MPa), not their SI conversion (Pa).
    let text = "BEGIN BULK
GRID    1               0.      0.      0.
GRID    2               1.      0.      0.
GRID    3               0.      1.      0.
GRID    4               0.      0.      1.
CTETRA  7       1       1       2       3       4
PSOLID  1       3
MAT1    3       210000. 50000.  0.3     7.85-9
ENDDATA
";
    let err = nastran::parse(text, Path::new("mm.bdf"), UnitSystem::MmTonneSecond).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("mm.bdf") && msg.contains("MAT1 3"), "{msg}");
    assert!(msg.contains("G = 5e4") && msg.contains("8.0769"), "{msg}");
    assert!(!msg.contains("e10"), "SI values in the message: {msg}");
}

#[test]
fn nastran_field_formats_shorthand_coordinate_systems_and_lists() {
    let text = "SOL 103
CEND
BEGIN BULK
$ a tet in a rotated, shifted system: CORD2R 5 with z along basic x
CORD2R  5               1.      2.      3.      2.      2.      3.
+       1.      2.      4.
GRID    1       5       0.      0.      0.
GRID*   2               5               1.0+0           0.
*       0.
GRID,3,5,0.,2.-0,0.
GRID    4       5       0.      0.      3.
CTETRA  7       1       1       3       2       4
PSOLID,1,3
MAT1,3,2.1+11,8.077+10,,7.85-9
PARAM   WTMASS  1000.
PARAM   POST    -1
SPC1    9       123456  1       THRU    3
FORCE   1       4               1.      1.      0.      0.
FORCE   1       4               1.      1.      0.      0.
ENDDATA
GRID    99      BAD
";
    let m = nastran_inline(text).unwrap();
    // z = B - A = basic x; y = z x (C - A) = basic x x basic z = -basic y; x = y x z = basic z.
    let x = &m.mesh.nodes;
    let close = |a: Point3<f64>, b: [f64; 3]| (a - Point3::from(b)).norm() < 1e-12;
    assert!(close(x[0], [1.0, 2.0, 3.0]), "{:?}", x[0]);
    assert!(close(x[1], [1.0, 2.0, 4.0]), "local x is basic z: {:?}", x[1]);
    assert!(close(x[2], [1.0, 0.0, 3.0]), "local y is minus basic y: {:?}", x[2]);
    assert!(close(x[3], [4.0, 2.0, 3.0]), "local z is basic x: {:?}", x[3]);
    // The tet (1, 3, 2, 4) has the other handedness and was renumbered; the density, 7.85e-6
    // kg/m^3 in SI, is lighter than air (a unit warning).
    assert_eq!(m.notes.len(), 2, "{:?}", m.notes);
    assert!(m.notes[1].contains("renumbered"), "{:?}", m.notes);
    assert!(
        m.notes[0].contains("MAT1_3") && m.notes[0].contains("lighter than air"),
        "{:?}",
        m.notes
    );
    let model = m.to_fe_model(MassKind::Consistent, None).unwrap();
    assert_eq!(model.elements.len(), 1);
    let mat = m.material("MAT1_3").unwrap();
    assert!((mat.nu() - (2.1e11 / (2.0 * 8.077e10) - 1.0)).abs() < 1e-15);
    assert!((mat.rho() - 7.85e-6).abs() < 1e-20, "WTMASS scales RHO: {}", mat.rho());
    assert_eq!(m.supports[0].nodes, vec![NodeId(0), NodeId(1), NodeId(2)]);
    assert_eq!(m.supports[0].dofs, DofMask::ALL);
    let names: Vec<(&str, usize)> = m.ignored.iter().map(|i| (i.name.as_str(), i.count)).collect();
    assert_eq!(names, vec![("PARAM,POST", 1), ("FORCE", 2)]);
    assert_eq!(m.ignored[1].first_line, 18);
}

#[test]
fn nastran_rbe3_is_an_interpolation_spider_with_a_note() {
    let mut text = String::from("BEGIN BULK\n");
    for (i, (y, z)) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].iter().enumerate() {
        text += &format!("GRID,{},,0.,{y:?},{z:?}\n", i + 1);
    }
    text += "GRID,10,,0.,.5,.5\nRBE3,5,,10,123456,1.0,123,1,2,\n,3,4,UM,1,123\n";
    let m = nastran_inline(&text).unwrap();
    assert_eq!(m.spiders.len(), 1);
    let s = &m.spiders[0];
    assert_eq!((s.name.as_str(), s.kind), ("RBE3_5", SpiderKind::Rbe3));
    assert_eq!(s.surface, vec![NodeId(0), NodeId(1), NodeId(2), NodeId(3)]);
    assert_eq!(s.position, Point3::new(0.0, 0.5, 0.5));
    assert_eq!(m.notes.len(), 2, "UM and the weights: {:?}", m.notes);
}

// ------------------------------------------------------------------------------------ errors

/// Parses `text`, expects an error at `line` of `file` whose message has every fragment.
fn expect(result: Result<ImportedModel, ImportError>, file: &str, line: usize, fragments: &[&str]) -> ImportError {
    let error = match result {
        Ok(_) => panic!("expected an error with {fragments:?}"),
        Err(e) => e,
    };
    let message = error.to_string();
    assert!(message.starts_with(&format!("{file}:{line}:")), "{message}");
    for f in fragments {
        assert!(message.contains(f), "'{f}' missing from: {message}");
    }
    error
}

const NODES_4: &str = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 0\n4, 0, 0, 1\n";

#[test]
fn abaqus_errors_name_file_line_and_entity() {
    let with = |rest: &str| abaqus_inline(&format!("{NODES_4}{rest}"));
    // 1. A coordinate that is not a number.
    let e = expect(
        abaqus_inline("*NODE\n1, 0, x, 0\n"),
        "inline.inp",
        2,
        &["*NODE 1", "coordinate", "'x'"],
    );
    assert!(matches!(e, ImportError::Malformed { .. }));
    // 2. An element type we do not read.
    let e = expect(
        with("*ELEMENT, TYPE=S4R\n1, 1, 2, 3, 4\n"),
        "inline.inp",
        6,
        &["S4R", "C3D4"],
    );
    assert!(matches!(e, ImportError::Unsupported { .. }));
    // 3. An element with a node that does not exist.
    let e = expect(
        with("*ELEMENT, TYPE=C3D4\n7, 1, 2, 3, 9\n"),
        "inline.inp",
        7,
        &["element 7", "node 9"],
    );
    assert!(matches!(e, ImportError::Undefined { .. }));
    // 4. A node defined twice.
    let e = expect(
        with("*NODE\n2, 5, 5, 5\n"),
        "inline.inp",
        7,
        &["node 2", "twice", "line 3"],
    );
    assert!(matches!(e, ImportError::Duplicate { .. }));
    // 5. Too few nodes for the element type.
    expect(
        with("*ELEMENT, TYPE=C3D10\n1, 1, 2, 3, 4\n"),
        "inline.inp",
        7,
        &["element 1", "10 node ids"],
    );
    // 6. *ELASTIC before any *MATERIAL.
    expect(
        with("*ELASTIC\n1e9, 0.3\n"),
        "inline.inp",
        6,
        &["*ELASTIC", "*MATERIAL"],
    );
    // 7. A section naming a material that does not exist.
    expect(
        with("*ELEMENT, TYPE=C3D4, ELSET=e\n1, 1, 2, 3, 4\n*SOLID SECTION, ELSET=e, MATERIAL=steel\n"),
        "inline.inp",
        8,
        &["material steel", "not defined"],
    );
    // 8. A section on an element set that does not exist.
    expect(
        with("*MATERIAL, NAME=m\n*ELASTIC\n1e9, 0.3\n*DENSITY\n1.\n*SOLID SECTION, ELSET=nope, MATERIAL=m\n"),
        "inline.inp",
        11,
        &["element set nope"],
    );
    // 9. A node set made of a set that does not exist.
    expect(with("*NSET, NSET=a\nb\n"), "inline.inp", 7, &["*NSET a", "node set b"]);
    // 10. GENERATE that never reaches its end.
    expect(
        with("*NSET, NSET=a, GENERATE\n1, 4, 2\n"),
        "inline.inp",
        7,
        &["*NSET a", "GENERATE"],
    );
    // 11. An *INCLUDE of a file that does not exist names that file.
    expect_io(with("*INCLUDE, INPUT=missing.inc\n"), "missing.inc");
    // 12. Parts and assemblies are refused with what to do.
    expect(with("*PART, NAME=p\n"), "inline.inp", 6, &["*PART", "without them"]);
    // 13. *ELEMENT without TYPE.
    expect(
        with("*ELEMENT\n1, 1, 2, 3, 4\n"),
        "inline.inp",
        6,
        &["*ELEMENT", "TYPE="],
    );
    // 14. A material outside its physical range.
    let e = expect(
        with("*MATERIAL, NAME=m\n*ELASTIC\n1e9, 0.7\n*DENSITY\n1.\n"),
        "inline.inp",
        6,
        &["*MATERIAL m", "Poisson"],
    );
    assert!(matches!(e, ImportError::Property { .. }));
    // 15. A material without density.
    expect(
        with("*MATERIAL, NAME=m\n*ELASTIC\n1e9, 0.3\n"),
        "inline.inp",
        6,
        &["*MATERIAL m", "*DENSITY"],
    );
    // 16. A beam section shape we do not read.
    expect(
        with("*BEAM SECTION, ELSET=e, MATERIAL=m, SECTION=I\n1,2,3,4,5,6,7\n"),
        "inline.inp",
        6,
        &["SECTION=I", "RECT"],
    );
    // 17. A data line before any keyword.
    expect(abaqus_inline("1, 2, 3\n"), "inline.inp", 1, &["data line"]);
}

fn expect_io(result: Result<ImportedModel, ImportError>, file: &str) {
    match result {
        Err(ImportError::Io { path, .. }) => assert!(path.ends_with(file), "{path:?}"),
        other => panic!("expected an I/O error on {file}, got {other:?}"),
    }
}

#[test]
fn missing_files_are_named() {
    expect_io(abaqus::read(Path::new("no/such.inp"), UnitSystem::Si), "such.inp");
    expect_io(nastran::read(Path::new("no/such.bdf"), UnitSystem::Si), "such.bdf");
    expect_io(nastran_inline("INCLUDE 'gone.bdf'\n"), "gone.bdf");
}

const GRIDS_4: &str = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n";

#[test]
fn nastran_errors_name_file_line_and_entity() {
    let with = |rest: &str| nastran_inline(&format!("{GRIDS_4}{rest}"));
    // 1. A coordinate that is not a number.
    let e = expect(
        nastran_inline("GRID,1,,0.,abc,0.\n"),
        "inline.bdf",
        1,
        &["GRID 1", "X2", "'abc'"],
    );
    assert!(matches!(e, ImportError::Malformed { .. }));
    // 2. An element card we refuse (it would change the stiffness).
    let e = expect(with("CQUAD4,1,1,1,2,3,4\n"), "inline.bdf", 5, &["CQUAD4", "stiffness"]);
    assert!(matches!(e, ImportError::Unsupported { .. }));
    // 3. An element with a grid that does not exist.
    expect(
        with("CTETRA,1,1,1,2,3,9\nPSOLID,1,1\nMAT1,1,1e9,,.3,1.\n"),
        "inline.bdf",
        5,
        &["element 1", "node 9"],
    );
    // 4. A grid defined twice.
    expect(
        with("GRID,3,,5.,5.,5.\n"),
        "inline.bdf",
        5,
        &["node 3", "twice", "line 3"],
    );
    // 5. A wrong number of grids.
    expect(
        with("CHEXA,1,1,1,2,3,4,5,6\n"),
        "inline.bdf",
        5,
        &["CHEXA 1", "8 or 20"],
    );
    // 6. An element whose PSOLID does not exist.
    expect(
        with("CTETRA,1,8,1,2,3,4\n"),
        "inline.bdf",
        5,
        &["element 1", "PSOLID 8"],
    );
    // 7. A PSOLID whose MAT1 does not exist.
    expect(
        with("CTETRA,1,8,1,2,3,4\nPSOLID,8,3\n"),
        "inline.bdf",
        6,
        &["PSOLID 8", "MAT1 3"],
    );
    // 8. A grid in a coordinate system that does not exist, or is not a CORD2R.
    expect(
        nastran_inline("GRID,1,4,0.,0.,0.\n"),
        "inline.bdf",
        1,
        &["GRID 1", "coordinate system 4"],
    );
    expect(
        nastran_inline("CORD2C,4,,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\nGRID,1,4,0.,0.,0.\n"),
        "inline.bdf",
        3,
        &["CORD2C", "only CORD2R"],
    );
    // 9. A CORD2R whose points are on a line.
    expect(
        nastran_inline("CORD2R,4,,0.,0.,0.,0.,0.,1.\n,0.,0.,2.\nGRID,1,4,0.,0.,0.\n"),
        "inline.bdf",
        1,
        &["CORD2R 4", "not on one line"],
    );
    // 10. Bad component digits.
    expect(with("SPC1,1,127,1\n"), "inline.bdf", 5, &["SPC1 1", "component digits"]);
    // 11. MAT1 with one constant only, and with three that disagree.
    expect(with("MAT1,1,1e9\n"), "inline.bdf", 5, &["MAT1 1", "two of E, G, NU"]);
    expect(with("MAT1,1,1e9,1e9,.3\n"), "inline.bdf", 5, &["MAT1 1", "isotropic"]);
    // 12. An RBE2 that does not tie all translations.
    expect(with("RBE2,1,1,12,2,3\n"), "inline.bdf", 5, &["RBE2 1", "123"]);
    // 13. THRU with a decreasing range.
    expect(with("SPC1,1,123,4,THRU,2\n"), "inline.bdf", 5, &["SPC1 1", "THRU"]);
    // 14. A continuation line without a card.
    expect(nastran_inline("+,1,2\n"), "inline.bdf", 1, &["continuation"]);
    // 15. A non-zero enforced displacement.
    expect(with("SPC,1,1,123,0.5\n"), "inline.bdf", 5, &["SPC 1", "non-zero"]);
    // 16. A support on a grid whose dofs are in a local system.
    expect(
        nastran_inline("CORD2R,4,,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\nGRID,1,,0.,0.,0.,4\nSPC1,1,1,1\n"),
        "inline.bdf",
        4,
        &["SPC1 1", "CD = 4"],
    );
}

// ------------------------------------------------------------------------------------ large field

/// `hex8_large.bdf` (every card of `hex8_small.bdf` in large field, `*N<k>` markers in
/// columns 73-80 and 1-8, as pre-processors write it) in another continuation form: markers
/// replaced by blanks or by `+`, or the free-field large form with commas.
fn large_field_variants() -> Vec<(&'static str, String)> {
    let text = std::fs::read_to_string(data_dir().join("import/hex8_large.bdf")).unwrap();
    let map = |f: &dyn Fn(&str) -> String| text.lines().map(|l| f(l) + "\n").collect::<String>();
    let is_card = |l: &str| !(l.starts_with('$') || l == "BEGIN BULK" || l == "ENDDATA");
    let col = |l: &str, a: usize, b: usize| l.get(a..b.min(l.len())).unwrap_or("").trim().to_string();
    let blank = map(&|l| match l.strip_prefix("*N") {
        Some(_) => format!("{:8}{}", "", l.get(8..).unwrap_or("")),
        None => l.to_string(),
    });
    let plus = map(&|l| {
        let l = l.replace("*N", "+N");
        if l.starts_with("+N") || !is_card(&l) {
            l
        } else {
            l.replacen("+N", "*N", usize::from(l.len() <= 72))
        }
    });
    let free = map(&|l| {
        if !is_card(l) {
            return l.to_string();
        }
        let fields: Vec<String> = (0..5).map(|i| col(l, 8 + 16 * i, 24 + 16 * i)).collect();
        format!("{},{}", col(l, 0, 8), fields.join(","))
    });
    vec![
        ("'*' markers", text.clone()),
        ("blank continuations", blank),
        ("'+' markers", plus),
        ("free field", free),
    ]
}

#[test]
fn large_field_decks_in_every_continuation_form_equal_their_small_field_twin() {
    let small = nastran_fixture("hex8_small.bdf");
    let f_small = frequencies(&nastran_model(&small));
    for (form, text) in large_field_variants() {
        let large = nastran_inline(&text).unwrap_or_else(|e| panic!("{form}: {e}"));
        assert_eq!(large.mesh.nodes, small.mesh.nodes, "{form}");
        assert_eq!(volume_cells(&large.mesh), volume_cells(&small.mesh), "{form}");
        assert_eq!(large.supports, small.supports, "{form}");
        assert_eq!(large.spiders, small.spiders, "{form}");
        let d = spectrum_difference(&f_small, &frequencies(&nastran_model(&large)));
        assert!(d < SAME_SPECTRUM, "{form}: differs by {d:e}");
    }
}

#[test]
fn a_large_field_continuation_with_a_marker_is_read_in_16_columns() {
    // Read in 8 columns (as before), the `*G1` line gave X3 blank and CD = '3.5', refused
    // with "expected CD (an integer) in field 7".
    let text = "GRID*                  7                             1.5             2.5*G1\n*G1                  3.5               0\n";
    let m = nastran_inline(text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.mesh.nodes, vec![Point3::new(1.5, 2.5, 3.5)]);
    assert_eq!(m.mesh.node_tags, vec![7]);
}

// ------------------------------------------------------------------------------------ bounds

/// A folder of its own under the test target's temporary folder.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Fifteen files, each including the next four times: 4^14 (268 million) reads of the last
/// one without the bound on included files, a located error after 10,000 with it.
fn include_amplification(dir: &Path, ext: &str, include: &str, leaf: &str) -> PathBuf {
    for k in 0..15 {
        let body = if k == 14 {
            leaf.to_string()
        } else {
            include.replace("{}", &format!("f{}.{ext}", k + 1)).repeat(4)
        };
        std::fs::write(dir.join(format!("f{k}.{ext}")), body).unwrap();
    }
    dir.join(format!("f0.{ext}"))
}

fn expect_limit(result: Result<ImportedModel, ImportError>, fragments: &[&str]) -> String {
    let message = match result {
        Err(e @ ImportError::Limit { .. }) => e.to_string(),
        other => panic!("expected a limit error with {fragments:?}, got {:?}", other.map(|_| ())),
    };
    for f in fragments {
        assert!(message.contains(f), "'{f}' missing from: {message}");
    }
    message
}

#[test]
fn include_amplification_stops_at_the_file_budget_with_the_include_chain() {
    let dir = scratch("include_amplification_abaqus");
    let main = include_amplification(&dir, "inp", "*INCLUDE, INPUT={}\n", "** leaf\n");
    let m = expect_limit(
        abaqus::read(&main, UnitSystem::Si),
        &[
            "*INCLUDE",
            "more than 10000 files included",
            "included by",
            "/f0.inp:1 -> ",
            "/f1.inp:1 -> ",
        ],
    );
    assert!(m.starts_with(&dir.display().to_string()), "{m}");
    let dir = scratch("include_amplification_nastran");
    let main = include_amplification(&dir, "bdf", "INCLUDE '{}'\n", "$ leaf\n");
    expect_limit(
        nastran::read(&main, UnitSystem::Si),
        &["INCLUDE", "more than 10000 files included", "/f0.bdf:1 -> "],
    );
}

#[test]
fn an_included_file_past_the_byte_budget_is_refused_before_it_is_read() {
    let dir = scratch("include_bytes");
    // A sparse file: 1 GiB and a byte long, no disk space, never read.
    let big = std::fs::File::create(dir.join("big.inc")).unwrap();
    big.set_len((fe_model::mesh::import::MAX_EXPANDED_BYTES + 1) as u64)
        .unwrap();
    std::fs::write(dir.join("main.inp"), format!("{NODES_4}*INCLUDE, INPUT=big.inc\n")).unwrap();
    let m = expect_limit(
        abaqus::read(&dir.join("main.inp"), UnitSystem::Si),
        &["main.inp:6: *INCLUDE", "'big.inc'", "bytes"],
    );
    assert!(!m.contains("included by"), "the main file includes it: {m}");
    std::fs::write(dir.join("main.bdf"), "GRID,1,,0.,0.,0.\nINCLUDE 'big.inc'\n").unwrap();
    expect_limit(
        nastran::read(&dir.join("main.bdf"), UnitSystem::Si),
        &["main.bdf:2: INCLUDE", "'big.inc'"],
    );
}

#[test]
fn generate_ranges_longer_than_the_deck_are_located_errors_not_allocations() {
    // 1e12 ids: 24 TB of set members without the bound.
    let deck = format!("{NODES_4}*ELEMENT, TYPE=C3D4\n1, 1, 2, 3, 4\n*ELSET, ELSET=ALL, GENERATE\n1, 1000000000000\n");
    expect_limit(
        abaqus_inline(&deck),
        &[
            "inline.inp:9: *ELSET ALL",
            "GENERATE '1, 1000000000000' names 1000000000000 elements",
            "the 1 the deck",
        ],
    );
    let deck = format!("{NODES_4}*NSET, NSET=N, GENERATE\n1, 9999999999999, 2\n");
    expect_limit(
        abaqus_inline(&deck),
        &["inline.inp:7: *NSET N", "names 5000000000000 nodes, more than the 4"],
    );
    // A range within the deck is read.
    let deck = format!("{NODES_4}*NSET, NSET=N, GENERATE\n1, 4\n");
    assert_eq!(abaqus_inline(&deck).unwrap().mesh.node_sets["N"].len(), 4);
}

#[test]
fn sets_of_sets_stop_at_the_member_budget() {
    // Each set twice the one before: 4 * 2^40 members without the bound; 32 times the four
    // nodes (128) with it, passed by the copies into S5 (8 + 16 + 32 + 64 + 64 of 128).
    let mut deck = format!("{NODES_4}*NSET, NSET=S0\n1, 2, 3, 4\n");
    for k in 1..=40 {
        deck.push_str(&format!("*NSET, NSET=S{k}\nS{}, S{}\n", k - 1, k - 1));
    }
    expect_limit(
        abaqus_inline(&deck),
        &["inline.inp:17: *NSET S5", "more than 128 members"],
    );
}

#[test]
fn boundaries_on_sets_stop_at_the_member_budget() {
    // Each line holds a copy of the set: a million lines on a set of a million nodes would
    // be 10^12 copies; here 32 times the four nodes (128), passed by the 33rd line.
    let deck = format!(
        "{NODES_4}*NSET, NSET=ALL\n1, 2, 3, 4\n*BOUNDARY\n{}",
        "ALL, ENCASTRE\n".repeat(200)
    );
    expect_limit(
        abaqus_inline(&deck),
        &["inline.inp:41: *BOUNDARY ALL", "more than 128 nodes"],
    );
    let deck = format!(
        "{NODES_4}*NSET, NSET=ALL\n1, 2, 3, 4\n*BOUNDARY\n{}",
        "ALL, ENCASTRE\n".repeat(32)
    );
    assert_eq!(abaqus_inline(&deck).unwrap().supports.len(), 32);
}

#[test]
fn thru_ranges_longer_than_the_deck_are_located_errors_not_allocations() {
    let grids = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,0.,1.,0.\nGRID,4,,0.,0.,1.\n";
    // Eight ranges of 1e8 grids: 800 MB each without the bound.
    let deck = format!("{grids}{}", "SPC1,1,123,1,THRU,100000000\n".repeat(8));
    expect_limit(
        nastran_inline(&deck),
        &[
            "inline.bdf:5: SPC1 1",
            "'1 THRU 100000000' names 100000000 grids, more than the 4 GRIDs",
        ],
    );
    let deck = format!("{grids}RBE2,9,4,123,1,THRU,5\n");
    expect_limit(nastran_inline(&deck), &["inline.bdf:5: RBE2 9", "names 5 grids"]);
    // Many ranges over every grid: at most 32 times the grids together (the 33rd card).
    let deck = format!("{grids}{}", "SPC1,1,123,1,THRU,4\n".repeat(200));
    expect_limit(
        nastran_inline(&deck),
        &["inline.bdf:37: SPC1 1", "more than 32 times its 4 GRIDs"],
    );
    let deck = format!("{grids}{}", "SPC1,1,123,1,THRU,4\n".repeat(32));
    let supports = nastran_inline(&deck).unwrap().supports;
    assert_eq!(supports.len(), 32);
    assert!(supports.iter().all(|s| s.nodes.len() == 4));
}

// ------------------------------------------------------------------------------------ no panic

// xorshift64* with a fixed seed (`fe_model::fuzz::Mutator`), so that a failure can be replayed.
use fe_model::fuzz::Mutator as Rng;

#[derive(Clone, Copy)]
enum Format {
    Abaqus,
    Nastran,
}

/// Parses `bytes` as if it were the file `origin` (so includes resolve next to it), turning
/// a panic into a failure that names the input; a model that is read must build.
fn parse_without_panic(format: Format, bytes: &[u8], origin: &Path, what: &dyn Fn() -> String) {
    let result = std::panic::catch_unwind(|| match format {
        Format::Abaqus => abaqus::parse(bytes, origin, UnitSystem::Si),
        Format::Nastran => nastran::parse(bytes, origin, UnitSystem::Si),
    });
    match result {
        Ok(Ok(model)) => {
            let n = model.mesh.nodes.len();
            assert!(model.mesh.cells.iter().all(|c| c.nodes.iter().all(|id| id.index() < n)));
            let _ = model.to_fe_model(MassKind::Consistent, None);
        }
        Ok(Err(error)) => {
            let _ = error.to_string();
        }
        Err(_) => panic!("parse panicked on {}", what()),
    }
}

/// `FLEXMBS_FUZZ_SCALE=100` multiplies the number of random and mutated inputs (the knob of
/// every fuzz test, `fe_model::fuzz::budget`).
fn fuzz_scale() -> usize {
    fe_model::fuzz::budget(1)
}

fn fixture_files() -> Vec<(Format, PathBuf)> {
    let dir = data_dir().join("import");
    let mut out: Vec<(Format, PathBuf)> = MESHES
        .iter()
        .flat_map(|m| {
            [
                (Format::Abaqus, dir.join(format!("{m}.inp"))),
                (Format::Nastran, dir.join(format!("{m}.bdf"))),
            ]
        })
        .collect();
    out.push((Format::Nastran, dir.join("hex8_small.bdf")));
    out.push((Format::Nastran, dir.join("hex8_large.bdf")));
    out.push((Format::Nastran, dir.join("tet10_free.bdf")));
    out
}

#[test]
fn random_text_never_panics() {
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15);
    let headers: [(Format, &str); 6] = [
        (Format::Abaqus, ""),
        (Format::Abaqus, "*NODE\n"),
        (Format::Abaqus, "*NODE\n1,0,0,0\n2,1,0,0\n*ELEMENT, TYPE=C3D4\n"),
        (Format::Nastran, ""),
        (Format::Nastran, "GRID    1               0.      0.      0.\n"),
        (Format::Nastran, "GRID,1,,0.,0.,0.\nCTETRA,1,1,"),
    ];
    const ALPHABET: &[u8] = b"0123456789 ,\n-.e+*$=CTRAGIDNEXPSOLMBK";
    for case in 0..2000 * fuzz_scale() {
        let (format, header) = headers[case % headers.len()];
        let mut bytes = header.as_bytes().to_vec();
        let ascii = rng.below(3) != 0;
        bytes.extend((0..rng.below(400)).map(|_| {
            let r = rng.next_u64();
            if ascii {
                ALPHABET[(r % ALPHABET.len() as u64) as usize]
            } else {
                r as u8
            }
        }));
        parse_without_panic(format, &bytes, Path::new("fuzz"), &|| {
            format!("random case {case}: {bytes:?}")
        });
    }
}

#[test]
fn every_prefix_of_every_fixture_is_an_error_or_a_model_never_a_panic() {
    for (format, path) in fixture_files() {
        let bytes = std::fs::read(&path).unwrap();
        // Every 7th cut: the fixtures are a few kilobytes, and neighbouring cuts exercise the
        // same code.
        for len in (0..bytes.len()).step_by(7) {
            parse_without_panic(format, &bytes[..len], &path, &|| {
                format!("{} cut at {len}", path.display())
            });
        }
    }
}

#[test]
fn mutated_fixtures_never_panic() {
    let mut rng = Rng::new(0x2545_f491_4f6c_dd1d);
    const INTERESTING: &[u8] = b"0123456789-+.,eE *\n$=\xff";
    for (format, path) in fixture_files() {
        let original = std::fs::read(&path).unwrap();
        for case in 0..60 * fuzz_scale() {
            let mut bytes = original.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                match rng.below(3) {
                    0 => bytes[at] = INTERESTING[rng.below(INTERESTING.len())],
                    1 => {
                        bytes.remove(at);
                    }
                    _ => bytes.insert(at, INTERESTING[rng.below(INTERESTING.len())]),
                }
                if bytes.is_empty() {
                    break;
                }
            }
            parse_without_panic(format, &bytes, &path, &|| format!("{} mutation {case}", path.display()));
        }
    }
}

/// The shared fuzz mutator (`fe_model::fuzz`: numbers replaced by extreme ones, lines deleted,
/// duplicated or moved, the file cut), a fixed budget per fixture, as for the gmsh,
/// reduced-body, Matrix Market and study readers: every Abaqus and Nastran mutant is an error
/// or a model that builds, never a panic.
#[test]
fn shared_fuzz_mutants_of_abaqus_and_nastran_fixtures_never_panic() {
    let mut m = fe_model::fuzz::Mutator::new(0x6162_6e61_7366_7a01);
    for (format, path) in fixture_files() {
        let original = std::fs::read(&path).unwrap();
        for case in 0..fe_model::fuzz::budget(100) {
            let bytes = m.mutate(&original);
            parse_without_panic(format, &bytes, &path, &|| {
                format!(
                    "{} fuzz mutant {case}: {:?}",
                    path.display(),
                    String::from_utf8_lossy(&bytes)
                )
            });
        }
    }
}

/// The shared adversarial decks (`fe_model::fuzz::adversarial_decks`: ranges far longer than
/// the deck, doubling sets of sets, every Nastran continuation form): each, read as it is,
/// is a model or an error located by the deck's file and line (within the readers' bounds,
/// not after allocating the ranges); their mutants are errors or models, never a panic.
#[test]
fn adversarial_decks_are_models_or_located_errors_and_their_mutants_never_panic() {
    use fe_model::fuzz::DeckFormat;
    let mut m = fe_model::fuzz::Mutator::new(0x6164_7665_7273_6501);
    for deck in fe_model::fuzz::adversarial_decks() {
        let (format, origin) = match deck.format {
            DeckFormat::Abaqus => (Format::Abaqus, Path::new("adversarial.inp")),
            DeckFormat::Nastran => (Format::Nastran, Path::new("adversarial.bdf")),
        };
        let result = match format {
            Format::Abaqus => abaqus::parse(&deck.text, origin, UnitSystem::Si),
            Format::Nastran => nastran::parse(&deck.text, origin, UnitSystem::Si),
        };
        if let Err(e) = result {
            let message = e.to_string();
            let file = format!("{}:", origin.display());
            let located = message
                .find(&file)
                .is_some_and(|at| message[at + file.len()..].starts_with(|c: char| c.is_ascii_digit()));
            assert!(located, "{}: the error names no file and line: {message}", deck.name);
        }
        for case in 0..fe_model::fuzz::budget(20) {
            let bytes = m.mutate(deck.text.as_bytes());
            parse_without_panic(format, &bytes, origin, &|| {
                format!("{} mutant {case}: {:?}", deck.name, String::from_utf8_lossy(&bytes))
            });
        }
    }
}
