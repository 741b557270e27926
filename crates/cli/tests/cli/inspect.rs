//! `flexmbs inspect` on the sources other than `.rbody` files: an MBDyn file whose record 12
//! is compared with its nodal masses (record 11), and Matrix Market matrices with a node
//! table, reduced as a study's `[bodies.matrices]` is.

use crate::support::*;
use std::path::Path;

/// An MBDyn file of one exposed node at the origin (the interface) with two modes that do not
/// move it, record 11 its lumped mass (3 kg, rotational inertias 11, 3, 11 kg m^2) and
/// `record_12` as record 12.
fn one_node_fem(record_12: &str) -> String {
    format!(
        "** MBDyn MODAL DATA FILE
** RECORD GROUP 1, HEADER
      REV0 1 2 0 0 0
** RECORD GROUP 2, FINITE ELEMENT NODE LIST
 1001
** RECORD GROUP 5, NODAL X COORDINATES
 0
** RECORD GROUP 6, NODAL Y COORDINATES
 0
** RECORD GROUP 7, NODAL Z COORDINATES
 0
** RECORD GROUP 8, MODE SHAPES
**    NORMAL MODE SHAPE #  1
0 0 0 0 0 0
**    NORMAL MODE SHAPE #  2
0 0 0 0 0 0
** RECORD GROUP 9, MODAL MASS MATRIX
2 0
0 2
** RECORD GROUP 10, MODAL STIFFNESS MATRIX
1 0
0 1e2
** RECORD GROUP 11, DIAGONAL OF LUMPED MASS MATRIX
3 3 3 11 3 11
{}** END OF FILE
",
        if record_12.is_empty() {
            String::new()
        } else {
            format!("** RECORD GROUP 12, GLOBAL INERTIA\n{record_12}")
        }
    )
}

#[test]
fn inspect_compares_record_12_with_the_nodal_masses() {
    let dir = scratch("inspect-record-12");
    let write = |text: &str| std::fs::write(dir.join("body.fem"), text).unwrap();
    // Record 12 as record 11 implies it: compared, passed.
    write(&one_node_fem("3\n0 0 0\n11 0 0\n0 3 0\n0 0 11\n"));
    let out = flexmbs(&dir, &["inspect", "body.fem"]);
    assert_eq!(out.code, 0, "{}\n{}", out.stdout, out.stderr);
    assert!(out.stdout.contains("physical checks: passed"), "{}", out.stdout);
    assert!(!out.stdout.contains("not made"), "{}", out.stdout);
    // The mass ten times too large, the centre moved, the inertia wrong: exit 1, each value
    // named with its record, the stated and the computed value; a study refuses the file.
    for (record_12, what, stated, computed) in [
        (
            "30\n0 0 0\n11 0 0\n0 3 0\n0 0 11\n",
            "record 12 mass",
            "3.000000000e1",
            "3.000000000e0",
        ),
        (
            "3\n0 0.5 0\n11 0 0\n0 3 0\n0 0 11\n",
            "record 12 centre of mass [y]",
            "5.000000000e-1",
            "0.000000000e0",
        ),
        (
            "3\n0 0 0\n11 0 0\n0 3 0\n0 0 22\n",
            "record 12 inertia about the centre of mass [zz]",
            "2.200000000e1",
            "1.100000000e1",
        ),
    ] {
        write(&one_node_fem(record_12));
        let out = flexmbs(&dir, &["inspect", "body.fem"]);
        assert_eq!(out.code, 1, "{what}: {}\n{}", out.stdout, out.stderr);
        let line = out
            .stdout
            .lines()
            .find(|l| l.contains(what))
            .unwrap_or_else(|| panic!("{what} not in\n{}", out.stdout));
        assert!(
            line.contains("record 11") && line.contains(stated) && line.contains(computed),
            "{line}"
        );
        assert!(out.stderr.contains("body.fem fails"), "{}", out.stderr);
        std::fs::write(
            dir.join("study.toml"),
            "[[bodies]]\nname = \"b\"\nfile = \"body.fem\"\n",
        )
        .unwrap();
        let out = flexmbs(&dir, &["check", "study.toml"]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert!(
            out.stderr.contains("body.fem") && out.stderr.contains(what),
            "{}",
            out.stderr
        );
    }
    // Without record 11 the comparison cannot be made, and inspect says so.
    let text = one_node_fem("3\n0 0 0\n11 0 0\n0 3 0\n0 0 11\n");
    let at = text.find("** RECORD GROUP 11").unwrap();
    let end = text.find("** RECORD GROUP 12").unwrap();
    write(&format!("{}{}", &text[..at], &text[end..]));
    let out = flexmbs(&dir, &["inspect", "body.fem"]);
    assert_eq!(out.code, 0, "{}\n{}", out.stdout, out.stderr);
    assert!(
        out.stdout.contains(
            "not made: record 12 (rigid-body inertia) was not compared with nodal masses: the file has no record 11"
        ),
        "{}",
        out.stdout
    );
}

/// A free steel block [0, 0.4] x [0, 0.1] x [0, 0.05] of hex8 solids with RBE2 spiders on
/// both end faces, exported as another code would after eliminating the spiders (K.mtx,
/// M.mtx, nodes.txt, dofs.txt: three translations on the solid nodes, six on the interface
/// nodes), node coordinates times `scale`; the interface nodes.
fn export_block(dir: &Path, scale: f64) -> (usize, usize) {
    use fe_model::{
        add_interface_on_set, assemble, CellKind, DofMap, IsotropicMaterial, MassKind, SpiderKind, SystemPattern,
    };
    let mesh = fe_model::box_mesh::box_mesh(CellKind::Hex8, [0.4, 0.1, 0.05], [8, 2, 1]).unwrap();
    let steel = IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap();
    let mut model = fe_model::box_mesh::solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let a = add_interface_on_set(&mut model, "a", "x0", None, SpiderKind::Rbe2).unwrap();
    let b = add_interface_on_set(&mut model, "b", "x1", None, SpiderKind::Rbe2).unwrap();
    let dofs = DofMap::new(&model).unwrap();
    let assembled = assemble(&model, &SystemPattern::new(&model, &dofs)).unwrap();
    reduction::write_matrix_market(&dir.join("K.mtx"), assembled.K.as_ref()).unwrap();
    reduction::write_matrix_market(&dir.join("M.mtx"), assembled.M.as_ref()).unwrap();
    let nodes: String = model
        .mesh
        .nodes
        .iter()
        .map(|x| format!("{} {} {}\n", scale * x.x, scale * x.y, scale * x.z))
        .collect();
    std::fs::write(dir.join("nodes.txt"), nodes).unwrap();
    let names = ["ux", "uy", "uz", "rx", "ry", "rz"];
    let table: String = (0..dofs.n_free())
        .map(|d| {
            let slot = dofs.full_slot(fe_model::Dof(d as u32));
            format!("{} {}\n", slot / 6, names[slot % 6])
        })
        .collect();
    std::fs::write(dir.join("dofs.txt"), table).unwrap();
    (a.index(), b.index())
}

#[test]
fn inspect_reduces_and_checks_matrix_market_matrices() {
    let dir = scratch("inspect-matrices");
    let (a, b) = export_block(&dir, 1.0);
    let (ia, ib) = (format!("a={a}"), format!("b={b}"));
    let args = [
        "inspect",
        "K.mtx",
        "--mass",
        "M.mtx",
        "--nodes",
        "nodes.txt",
        "--dofs",
        "dofs.txt",
        "--interface",
        &ia,
        "--interface",
        &ib,
        "--modes",
        "4",
    ];
    let out = flexmbs(&dir, &args);
    assert_eq!(out.code, 0, "{}\n{}", out.stdout, out.stderr);
    for text in [
        "reduced body 'K' (K.mtx",
        "Matrix Market K, mass M.mtx, node table nodes.txt",
        "CB coordinates: 16 = 6 x 2 interfaces + 4 fixed-interface modes",
        "mass            1.570000e1 kg",
        "node table: box",
        "mass / box volume 7.850e3 kg/m^3",
        "physical checks: passed",
    ] {
        assert!(out.stdout.contains(text), "missing '{text}' in\n{}", out.stdout);
    }
    // The node table in millimetres, K and M in SI: the report, the problem naming the node
    // table and the likely units, exit 1.
    export_block(&dir, 1e3);
    let out = flexmbs(&dir, &args);
    assert_eq!(out.code, 1, "{}\n{}", out.stdout, out.stderr);
    assert!(
        out.stdout.contains("physical checks: FAILED")
            && out
                .stdout
                .contains("over the volume of the box around the node table's nodes")
            && out.stdout.contains("millimetres"),
        "{}",
        out.stdout
    );
    assert!(out.stderr.contains("K.mtx fails"), "{}", out.stderr);
    // What a Matrix Market stiffness needs, and options only it takes.
    let out = flexmbs(&dir, &["inspect", "K.mtx", "--nodes", "nodes.txt"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("needs --mass"), "{}", out.stderr);
    let out = flexmbs(&dir, &["inspect", "K.mtx", "--mass", "M.mtx", "--nodes", "nodes.txt"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("needs --interface NAME=NODE"), "{}", out.stderr);
    let out = flexmbs(&dir, &["inspect", "body.rbody", "--mass", "M.mtx"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("--mass is for a Matrix Market stiffness"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &[&args[..10], &["--interface", "b=x"]].concat());
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("--interface needs NAME=NODE"), "{}", out.stderr);
    let out = flexmbs(&dir, &[&args[..12], &["--cutoff-hz", "-1"]].concat());
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("--cutoff-hz needs a positive frequency"),
        "{}",
        out.stderr
    );
    // A file that cannot be read: exit 2, the key and the file.
    let out = flexmbs(&dir, &[&args[..2], &["--mass", "missing.mtx"], &args[4..]].concat());
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("missing.mtx"), "{}", out.stderr);
}
