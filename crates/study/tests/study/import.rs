//! Models from other codes in study files: a part's mesh from Abaqus and Nastran files (with
//! their materials, sets and spiders), a body from an MBDyn `.fem` file, a body from Matrix
//! Market matrices.

use fe_model::{modal_dense, DofMap, DofMask, SystemPattern};
use nalgebra::Point3;
use std::path::{Path, PathBuf};
use study::input::validate::mechanism::BodySource;

use crate::common;

fn scratch(name: &str) -> PathBuf {
    common::scratch_dir("import", name)
}

fn fixture(file: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fe-model/tests/data")
        .join(file)
        .display()
        .to_string()
}

fn study(dir: &Path, text: &str) -> study::Study {
    let path = dir.join("study.toml");
    std::fs::write(&path, text).unwrap();
    study::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The part's frequencies, clamped at the node set `clamp`, with the interfaces built.
fn clamped_frequencies(part: &study::input::part::Part, clamp: &[fe_model::NodeId]) -> Vec<f64> {
    let mut built = part.build(&[]).unwrap().model;
    for &n in clamp {
        built.add_support(n, DofMask::TRANSLATIONS);
    }
    modal_dense(&built, 6).unwrap().omega
}

fn steel() -> String {
    common::material("steel", 2.1e11, 0.3, 7850.0)
}

/// A `[[parts]]` entry whose mesh is `file` (`mesh`: more `[parts.mesh]` lines) with the
/// interface `tip` on the node set `set` (`interface`: more of its lines).
fn mesh_part(name: &str, file: &str, mesh: &str, set: &str, interface: &str) -> String {
    format!(
        "[[parts]]\nname = \"{name}\"\n[parts.mesh]\nfile = \"{file}\"\n{mesh}\
         [[parts.interfaces]]\nname = \"tip\"\nset = \"{set}\"\n{interface}"
    )
}

#[test]
fn parts_from_abaqus_and_nastran_files_match_the_gmsh_part() {
    let dir = scratch("parts");
    let tip = "spider = \"rbe2\"\nnode_position = [1.0, 0.1, 0.1]\n";
    let text = [
        steel(),
        mesh_part(
            "gmsh",
            &fixture("gmsh/hex20_41.msh"),
            "materials = { body = \"steel\" }\n",
            "tip",
            tip,
        ),
        mesh_part("abaqus", &fixture("import/hex20.inp"), "", "tip", tip),
        mesh_part("nastran", &fixture("import/hex20.bdf"), "", "RBE2_2", ""),
    ]
    .join("\n");
    let s = study(&dir, &text);
    let [g, a, n] = [&s.parts[0], &s.parts[1], &s.parts[2]];
    assert!(a.description.starts_with("Abaqus mesh"), "{}", a.description);
    // The Abaqus file's material (steel, as in the gmsh part) and sets; the Nastran file's
    // RBE2 gives the interface its kind and position, its SPC1 the clamp set.
    let f_gmsh = clamped_frequencies(g, &g.base.mesh.node_sets["clamp"]);
    let f_abaqus = clamped_frequencies(a, &a.base.mesh.node_sets["clamp"]);
    let f_nastran = clamped_frequencies(n, &n.base.mesh.node_sets["SPC1_1"]);
    for f in [&f_abaqus, &f_nastran] {
        for (x, y) in f_gmsh.iter().zip(f) {
            // The same model read three ways (see fe-model's import tests): round-off only.
            assert!(((x - y) / x).abs() < 1e-10, "{f_gmsh:?} {f:?}");
        }
    }
    // The skipped cards are warnings: meshio's *HEADING, the EIGRL card.
    assert!(s.warnings.iter().any(|w| w.contains("*HEADING")), "{:?}", s.warnings);
    assert!(s.warnings.iter().any(|w| w.contains("EIGRL")), "{:?}", s.warnings);

    // A study material replaces the file's: a softer material lowers every frequency.
    let soft = text.replace(
        &format!("file = \"{}\"\n", fixture("import/hex20.inp")),
        &format!(
            "file = \"{}\"\n[parts.mesh.materials]\nbody = \"soft\"\n",
            fixture("import/hex20.inp")
        ),
    );
    let soft = format!("{soft}\n{}", common::material("soft", 2.1e10, 0.3, 7850.0));
    let s2 = study(&dir, &soft);
    let f_soft = clamped_frequencies(&s2.parts[1], &s2.parts[1].base.mesh.node_sets["clamp"]);
    // E / 10 scales the frequencies by 1 / sqrt(10).
    assert!(((f_soft[0] * 10f64.sqrt() - f_abaqus[0]) / f_abaqus[0]).abs() < 1e-9);

    // A malformed file is located by its own file and line, under the study's key.
    let bad = dir.join("bad.inp");
    std::fs::write(&bad, "*NODE\n1, 0, 0, x\n").unwrap();
    let text = format!(
        "{}\n[[parts]]\nname = \"bad\"\nmaterial = \"steel\"\n[parts.mesh]\nfile = \"bad.inp\"\n",
        steel()
    );
    std::fs::write(dir.join("bad.toml"), text).unwrap();
    let e = study::load(&dir.join("bad.toml")).unwrap_err().to_string();
    assert!(
        e.contains("parts[0].mesh.file") && e.contains("bad.inp:2:") && e.contains("'x'"),
        "{e}"
    );
}

#[test]
fn decks_in_mm_t_s_with_their_units_declared_are_their_si_twins_and_a_warning_without() {
    let dir = scratch("units");
    let tip = "spider = \"rbe2\"\nnode_position = [1.0, 0.1, 0.1]\n";
    let mm = "units = \"mm-t-s\"\n";
    let text = [
        mesh_part("abaqus", &fixture("import/hex20.inp"), "", "tip", tip),
        mesh_part("abaqus_mm", &fixture("import/hex20_mm.inp"), mm, "tip", tip),
        mesh_part("nastran", &fixture("import/hex20.bdf"), "", "RBE2_2", ""),
        mesh_part("nastran_mm", &fixture("import/hex20_mm.bdf"), mm, "RBE2_2", ""),
    ]
    .join("\n");
    let s = study(&dir, &text);
    assert!(!s.warnings.iter().any(|w| w.contains("material")), "{:?}", s.warnings);
    for (si, mm, clamp) in [(0, 1, "clamp"), (2, 3, "SPC1_1")] {
        let (si, mm) = (&s.parts[si], &s.parts[mm]);
        let f_si = clamped_frequencies(si, &si.base.mesh.node_sets[clamp]);
        let f_mm = clamped_frequencies(mm, &mm.base.mesh.node_sets[clamp]);
        for (x, y) in f_si.iter().zip(&f_mm) {
            assert!(((x - y) / x).abs() < 1e-10, "{}: {f_si:?} {f_mm:?}", mm.name);
        }
        let m_si = fe_model::center_of_mass(&si.base).unwrap().0;
        let m_mm = fe_model::center_of_mass(&mm.base).unwrap().0;
        assert!(
            ((m_si - m_mm) / m_si).abs() < 1e-12,
            "{}: {m_si} kg, {m_mm} kg",
            mm.name
        );
    }
    // Undeclared, each deck's material is a warning under its part's file key that names
    // the material, its line and the unit system the numbers fit.
    let text = [
        mesh_part(
            "abaqus_mm",
            &fixture("import/hex20_mm.inp"),
            "",
            "tip",
            "spider = \"rbe3\"\n",
        ),
        mesh_part("nastran_mm", &fixture("import/hex20_mm.bdf"), "", "RBE2_2", ""),
    ]
    .join("\n");
    let s = study(&dir, &text);
    for (part, material) in [(0, "material steel ("), (1, "material MAT1_1 (")] {
        let w = s
            .warnings
            .iter()
            .find(|w| w.contains(material))
            .unwrap_or_else(|| panic!("{material}: {:?}", s.warnings));
        for fragment in [
            format!("parts[{part}].mesh.file"),
            "lighter than air".into(),
            "units = \"mm-t-s\"".into(),
        ] {
            assert!(w.contains(&fragment), "'{fragment}' in: {w}");
        }
    }
    // A gmsh file has only lengths: read in mm, its nodes are a thousandth of the file's.
    let gmsh = |units: &str| {
        let text = [
            steel(),
            mesh_part("g", &fixture("gmsh/hex20_41.msh"), units, "tip", "spider = \"rbe3\"\n")
                .replace("[parts.mesh]", "material = \"steel\"\n[parts.mesh]"),
        ]
        .join("\n");
        study(&dir, &text).parts[0].base.mesh.nodes.clone()
    };
    let (m, mm) = (gmsh(""), gmsh("units = \"mm-kg-ms\"\n"));
    assert!(m.iter().zip(&mm).all(|(a, b)| (a * 1e-3 - b).norm() < 1e-18));
    // An unknown system is a located error that lists the known ones.
    let text = mesh_part(
        "abaqus_mm",
        &fixture("import/hex20_mm.inp"),
        "units = \"mm\"\n",
        "tip",
        "",
    );
    std::fs::write(dir.join("bad.toml"), text).unwrap();
    let e = study::load(&dir.join("bad.toml")).unwrap_err().to_string();
    assert!(e.contains("units") && e.contains("mm-t-s"), "{e}");
}

/// A free steel beam with interfaces at both ends, and its reduced body.
fn beam() -> (fe_model::FeModel, Vec<(String, fe_model::NodeId)>) {
    let mut model = fe_model::FeModel::default();
    let material = model.add_material(fe_model::IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap());
    let section = model.add_section(fe_model::BeamSection::rectangle("r", 0.02, 0.01, 0.3).unwrap());
    let props = fe_model::BeamProperties {
        section,
        material,
        orientation: nalgebra::Vector3::z(),
        theory: fe_model::BeamTheory::Timoshenko,
        mass: fe_model::MassKind::Consistent,
    };
    let nodes = fe_model::generate::straight_beam(
        &mut model,
        Point3::origin(),
        Point3::new(1.0, 0.0, 0.0),
        6,
        &props,
        None,
    )
    .unwrap();
    (model, vec![("a".into(), nodes[0]), ("b".into(), nodes[6])])
}

fn flexible_body(s: &study::Study) -> reduction::ReducedBody {
    match &s.mechanism.bodies[0].source {
        BodySource::File(_, body) => (**body).clone(),
        BodySource::Part(_) => panic!("expected a body read from files"),
    }
}

#[test]
fn bodies_from_an_mbdyn_file_and_from_matrix_market_matrices() {
    let dir = scratch("bodies");
    let (model, interfaces) = beam();
    let mut settings = reduction::CbSettings::new(reduction::ModeSelection::Count(3));
    settings.keep_mesh_shapes = false;
    let body = reduction::reduce(&model, "beam", &interfaces, &settings).unwrap();

    // MBDyn: every exposed node is an interface.
    reduction::mbdyn::write_mbdyn_fem(&dir.join("beam.fem"), &body, 0).unwrap();
    let s = study(&dir, "[[bodies]]\nname = \"beam\"\nfile = \"beam.fem\"\n");
    assert_eq!(s.mechanism.bodies[0].interfaces, vec!["a".to_string(), "b".to_string()]);
    let back = flexible_body(&s);
    for (w, v) in body.fixed_interface_omega.iter().zip(&back.fixed_interface_omega) {
        // A change of basis and back (reduction's tests): round-off.
        assert!(((w - v) / w).abs() < 1e-10);
    }

    // Matrix Market: K, M on the free dofs, a node table and a dof table.
    export_matrices(&dir, &model);
    let text = matrices_study(interfaces[0].1.index(), interfaces[1].1.index());
    let s = study(&dir, &text);
    let from_matrices = flexible_body(&s);
    let scale = body.K_CB.data.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for (x, y) in body.K_CB.data.iter().zip(&from_matrices.K_CB.data) {
        // The same reduction of the same matrices (reduction's matrix_market tests): round-off.
        assert!((x - y).abs() < 1e-10 * scale, "{x} {y}");
    }
    for (w, v) in body
        .fixed_interface_omega
        .iter()
        .zip(&from_matrices.fixed_interface_omega)
    {
        assert!(((w - v) / w).abs() < 1e-10);
    }
    // A bad table is located by its file and line.
    std::fs::write(dir.join("nodes.txt"), "0 0 0\n1 x 0\n").unwrap();
    std::fs::write(dir.join("study.toml"), &text).unwrap();
    let e = study::load(&dir.join("study.toml")).unwrap_err().to_string();
    assert!(
        e.contains("bodies[0].matrices.nodes") && e.contains("nodes.txt:2:"),
        "{e}"
    );
}

/// `model`'s K and M on its free dofs (Matrix Market), its node table and dof table, in `dir`.
fn export_matrices(dir: &Path, model: &fe_model::FeModel) {
    let dofs = DofMap::new(model).unwrap();
    let pattern = SystemPattern::new(model, &dofs);
    let assembled = fe_model::assemble(model, &pattern).unwrap();
    reduction::write_matrix_market(&dir.join("K.mtx"), assembled.K.as_ref()).unwrap();
    reduction::write_matrix_market(&dir.join("M.mtx"), assembled.M.as_ref()).unwrap();
    let nodes: String = model
        .mesh
        .nodes
        .iter()
        .map(|x| format!("{} {} {}\n", x.x, x.y, x.z))
        .collect();
    std::fs::write(dir.join("nodes.txt"), format!("# x y z\n{nodes}")).unwrap();
    let names = ["ux", "uy", "uz", "rx", "ry", "rz"];
    let table: String = (0..dofs.n_free())
        .map(|d| {
            let slot = dofs.full_slot(fe_model::Dof(d as u32));
            format!("{} {}\n", slot / 6, names[slot % 6])
        })
        .collect();
    std::fs::write(dir.join("dofs.txt"), table).unwrap();
}

/// A study of one body from the files of [`export_matrices`], interfaces on nodes `a`, `b`.
fn matrices_study(a: usize, b: usize) -> String {
    format!(
        "[[bodies]]
name = \"beam\"
[bodies.matrices]
stiffness = \"K.mtx\"
mass = \"M.mtx\"
nodes = \"nodes.txt\"
dofs = \"dofs.txt\"
interfaces = {{ a = {a}, b = {b} }}
modes = 3
"
    )
}

/// The error of loading `text` as `dir`/study.toml.
fn load_error(dir: &Path, text: &str) -> String {
    std::fs::write(dir.join("study.toml"), text).unwrap();
    study::error::report(&*study::load(&dir.join("study.toml")).unwrap_err())
}

#[test]
fn imported_bodies_that_fail_the_physical_checks_are_refused_where_they_are_given() {
    let dir = scratch("checks");
    let (model, interfaces) = beam();
    let (a, b) = (interfaces[0].1.index(), interfaces[1].1.index());
    let mut settings = reduction::CbSettings::new(reduction::ModeSelection::Count(3));
    settings.keep_mesh_shapes = false;
    let body = reduction::reduce(&model, "beam", &interfaces, &settings).unwrap();

    // MBDyn: record 12 with the mass 12.5 times too small.
    let fem = reduction::mbdyn::to_mbdyn_fem(&body, 0, &dir.join("beam.fem")).unwrap();
    let mass = format!("{:.17e}", body.inertia.mass);
    let at = fem.find("** RECORD GROUP 12").unwrap();
    let line_start = at + fem[at..].find('\n').unwrap() + 1;
    let line_end = line_start + fem[line_start..].find('\n').unwrap();
    let mut wrong = fem.clone();
    wrong.replace_range(line_start..line_end, &format!("{:.17e}", body.inertia.mass / 12.5));
    assert_ne!(
        &fem[line_start..line_end],
        mass.as_str(),
        "the mass line is found by position"
    );
    std::fs::write(dir.join("beam.fem"), wrong).unwrap();
    let e = load_error(&dir, "[[bodies]]\nname = \"beam\"\nfile = \"beam.fem\"\n");
    assert!(
        e.contains("bodies[0].file") && e.contains("beam.fem") && e.contains("record 12 mass"),
        "{e}"
    );

    // Matrices: the node table in millimetres, located at the table's line of a node.
    export_matrices(&dir, &model);
    let text = matrices_study(a, b);
    let mm: String = model
        .mesh
        .nodes
        .iter()
        .map(|x| format!("{} {} {}\n", 1e3 * x.x, 1e3 * x.y, 1e3 * x.z))
        .collect();
    std::fs::write(dir.join("nodes.txt"), format!("# x y z in mm\n{mm}")).unwrap();
    let e = load_error(&dir, &text);
    assert!(
        e.contains("bodies[0].matrices.nodes") && e.contains("nodes.txt:") && e.contains("other units than m"),
        "{e}"
    );

    // The tip node listed at the root's position: the interfaces' nodes coincide.
    let mut lines: Vec<String> = model
        .mesh
        .nodes
        .iter()
        .map(|x| format!("{} {} {}", x.x, x.y, x.z))
        .collect();
    lines[b] = lines[a].clone();
    std::fs::write(dir.join("nodes.txt"), lines.join("\n") + "\n").unwrap();
    let e = load_error(&dir, &text);
    assert!(
        e.contains("bodies[0].matrices.nodes") && e.contains(&format!("nodes.txt:{}: node", b + 1)),
        "{e}"
    );

    // Both interfaces on one node: refused by the reduction, located.
    export_matrices(&dir, &model);
    let e = load_error(&dir, &matrices_study(a, a));
    assert!(
        e.contains("bodies[0].matrices") && e.contains("used by two interfaces"),
        "{e}"
    );
}

/// A free steel block [0, 0.4] x [0, 0.1] x [0, 0.05] of hex8 solids with RBE2 spiders on
/// both end faces, and its interface nodes.
fn spidered_block() -> (fe_model::FeModel, usize, usize) {
    let mesh = fe_model::box_mesh::box_mesh(fe_model::CellKind::Hex8, [0.4, 0.1, 0.05], [8, 2, 1]).unwrap();
    let steel = fe_model::IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap();
    let mut model = fe_model::box_mesh::solid_model(mesh, steel, fe_model::MassKind::Consistent).unwrap();
    let a = fe_model::add_interface_on_set(&mut model, "a", "x0", None, fe_model::SpiderKind::Rbe2).unwrap();
    let b = fe_model::add_interface_on_set(&mut model, "b", "x1", None, fe_model::SpiderKind::Rbe2).unwrap();
    (model, a.index(), b.index())
}

#[test]
fn a_solid_node_table_in_millimetres_is_refused_by_the_mass_of_m() {
    // Exported after the spiders were eliminated: three translations on the solid nodes,
    // six on the interface nodes.
    let dir = scratch("solid-mm");
    let (model, a, b) = spidered_block();
    export_matrices(&dir, &model);
    let text = matrices_study(a, b);
    let body = flexible_body(&study(&dir, &text));
    assert!((body.inertia.mass - 7850.0 * 0.4 * 0.1 * 0.05).abs() < 1e-9 * body.inertia.mass);
    // The table in millimetres, K and M in SI: the mass over the table's volume is 1e9
    // times too small for any material.
    let mm: String = model
        .mesh
        .nodes
        .iter()
        .map(|x| format!("{} {} {}\n", 1e3 * x.x, 1e3 * x.y, 1e3 * x.z))
        .collect();
    std::fs::write(dir.join("nodes.txt"), mm).unwrap();
    let e = load_error(&dir, &text);
    assert!(
        e.contains("bodies[0].matrices.nodes")
            && e.contains("nodes.txt")
            && e.contains("kg/m^3")
            && e.contains("millimetres"),
        "{e}"
    );
}

/// Interfaces of a deck's part carry the deck's node numbers: a beam deck numbered sparsely
/// (10, 20, ...) gives its interface and auxiliary nodes their labels, from the reduction and
/// from the cache; a solid deck's spider nodes, which the deck does not have, get none.
/// A beam part from an Abaqus deck numbered sparsely (nodes 10, 20, ..., 50; sets `root`
/// (10) and `end` (50)), interfaces `tip` and `root`, reduced with the auxiliary node; and a
/// solid part from a deck whose interface `tip` is an RBE2 spider node.
fn labelled_parts(dir: &Path) -> String {
    let deck = dir.join("beam.inp");
    let mut text = String::from("*NODE\n");
    for k in 0..=4 {
        text += &format!("{}, {}, 0., 0.\n", 10 * (k + 1), 0.25 * k as f64);
    }
    text += "*ELEMENT, TYPE=B31, ELSET=beam\n";
    for k in 0..4 {
        text += &format!("{}, {}, {}\n", k + 1, 10 * (k + 1), 10 * (k + 2));
    }
    text += "*NSET, NSET=root\n10\n*NSET, NSET=end\n50\n*MATERIAL, NAME=steel\n*ELASTIC\n2.1e11, 0.3\n\
             *DENSITY\n7850.\n*BEAM SECTION, ELSET=beam, MATERIAL=steel, SECTION=RECT\n0.02, 0.01\n0., 1., 0.\n";
    std::fs::write(&deck, text).unwrap();
    let beam = format!(
        "{}[[parts.interfaces]]\nname = \"root\"\nset = \"root\"\n[parts.reduction]\nmodes = 2\nauxiliary_node = true\n",
        mesh_part("beam", &deck.display().to_string(), "", "end", "")
    );
    let solid = format!(
        "{}spider = \"rbe2\"\n[parts.reduction]\nmodes = 2\n",
        mesh_part("solid", &fixture("import/hex20_labels.inp"), "", "tip", "")
    );
    [beam, solid].concat()
}

#[test]
fn interfaces_on_deck_nodes_keep_the_decks_labels() {
    let dir = scratch("interface-labels");
    let s = study(&dir, &labelled_parts(&dir));
    let cache = dir.join("cache");
    let labels = |part: usize| {
        let r = study::reduce_part(&s, &s.parts[part], &cache, &mut ()).unwrap();
        let labels: Vec<_> = r
            .body
            .interfaces
            .iter()
            .map(|i| (i.name.clone(), i.node_label))
            .collect();
        (r.from_cache, labels)
    };
    let beam_labels = vec![
        ("tip".to_string(), Some(50)),
        ("root".to_string(), Some(10)),
        ("auxiliary".to_string(), Some(30)),
    ];
    assert_eq!(labels(0), (false, beam_labels.clone()));
    assert_eq!(labels(0), (true, beam_labels));
    assert_eq!(labels(1), (false, vec![("tip".to_string(), None)]));
}

/// The results' `interfaces.csv` (of a static and of a reduce analysis) end with the column
/// `node label`, the deck's node number, empty for the spider node the deck does not have;
/// the columns before it are those readers already know.
#[test]
fn interfaces_csv_ends_with_the_deck_label() {
    let dir = scratch("interfaces-csv");
    let analyses = "[[analyses]]\ntype = \"static\"\nname = \"bend\"\npart = \"beam\"\n\
                    supports = [{ at = \"root\" }]\nloads = [{ at = \"tip\", force = [0.0, 0.0, -10.0] }]\n\
                    [[analyses]]\ntype = \"reduce\"\nname = \"reduce-beam\"\npart = \"beam\"\n\
                    [[analyses]]\ntype = \"reduce\"\nname = \"reduce-solid\"\npart = \"solid\"\n";
    let s = study(&dir, &format!("{}\n{analyses}", labelled_parts(&dir)));
    let out = dir.join("results");
    let options = study::Options {
        out: Some(out.clone()),
        cache: Some(dir.join("cache")),
        ..study::Options::default()
    };
    study::run(&s, &options, &mut ()).unwrap();
    let table = |analysis: &str| {
        let text = std::fs::read_to_string(out.join(analysis).join("interfaces.csv")).unwrap();
        let mut lines = text
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>());
        let header = lines.next().unwrap();
        (header, lines.collect::<Vec<_>>())
    };
    let (header, rows) = table("bend");
    assert_eq!(
        header,
        [
            "interface",
            "node",
            "ux [m]",
            "uy [m]",
            "uz [m]",
            "rx [rad]",
            "ry [rad]",
            "rz [rad]",
            "node label"
        ]
    );
    let labels: Vec<(&str, &str)> = rows.iter().map(|r| (r[0].as_str(), r[8].as_str())).collect();
    assert_eq!(labels, [("tip", "50"), ("root", "10")]);
    let (header, rows) = table("reduce-beam");
    assert_eq!(
        header,
        ["index", "name", "node", "x [m]", "y [m]", "z [m]", "node label"]
    );
    let labels: Vec<(&str, &str)> = rows.iter().map(|r| (r[1].as_str(), r[6].as_str())).collect();
    assert_eq!(labels, [("tip", "50"), ("root", "10"), ("auxiliary", "30")]);
    let (_, rows) = table("reduce-solid");
    assert_eq!((rows[0][1].as_str(), rows[0][6].as_str()), ("tip", ""));
}
