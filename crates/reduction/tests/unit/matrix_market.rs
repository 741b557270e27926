// Matrix Market interop (`reduction::matrix_market`) and the reduction of matrices from
// another FE code (`reduction::reduce_external`): K and M round-trip exactly; symmetric files
// are expanded; every error names the file and the line; the matrices of an FeModel, exported
// and reduced as external matrices, give the body `reduce` gives.

use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use fe_model::interface::{add_interface_on_set, SpiderKind};
use fe_model::{
    assemble, CellKind, DofMap, FeModel, IsotropicMaterial, MassKind, NodeId,
    SystemPattern,
};
use reduction::matrix_market::{parse_matrix_market, to_matrix_market};
use reduction::{
    read_matrix_market, reduce, reduce_external, reduce_external_dofs, write_matrix_market, CbSettings, DenseMatrix,
    ModeSelection, ReducedBody, ReductionError,
};
use std::path::{Path, PathBuf};

/// A free steel beam along a skewed axis, `n` elements, interfaces at both ends.
fn free_beam(n: usize) -> (FeModel, Vec<(String, NodeId)>) {
    let (model, nodes) = super::common::skew_steel_beam(n, super::common::d20(), MassKind::Consistent);
    (model, vec![("A".to_string(), nodes[0]), ("B".to_string(), nodes[n])])
}

/// K and M on the free dofs, and the (node, dof) of every free dof: what another FE code
/// would hand over.
type Exported = (SparseColMat<usize, f64>, SparseColMat<usize, f64>, Vec<(usize, usize)>);

fn export(model: &FeModel) -> Exported {
    let dofs = DofMap::new(model).unwrap();
    let a = assemble(model, &SystemPattern::new(model, &dofs)).unwrap();
    let list = (0..dofs.n_free())
        .map(|d| {
            let slot = dofs.full_slot(fe_model::Dof(d as u32));
            (slot / 6, slot % 6)
        })
        .collect();
    (a.K, a.M, list)
}

/// (row, column, bits) of every stored entry, sorted.
fn entries(A: SparseColMatRef<'_, usize, f64>) -> Vec<(usize, usize, u64)> {
    let mut e = Vec::new();
    for j in 0..A.ncols() {
        for (&i, &v) in A.row_idx_of_col_raw(j).iter().zip(A.val_of_col(j)) {
            e.push((i, j, v.to_bits()));
        }
    }
    e.sort();
    e
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("reduction-mm-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The error of parsing `text`, checked to name the file and (if given) the line.
fn parse_error(text: &str, line: Option<usize>, words: &[&str]) -> String {
    let origin = Path::new("models/K.mtx");
    let e = parse_matrix_market(text.as_bytes(), origin).unwrap_err();
    let ReductionError::MatrixMarket { path, line: got, .. } = &e else {
        panic!("not a Matrix Market error: {e}")
    };
    assert_eq!(path, origin);
    assert_eq!(*got, line, "{e}");
    let message = e.to_string();
    assert!(message.starts_with("Matrix Market file models/K.mtx"), "{message}");
    for w in words {
        assert!(message.contains(w), "'{w}' missing from: {message}");
    }
    message
}

#[test]
fn stiffness_and_mass_round_trip_exactly() {
    let (model, _) = free_beam(6);
    let (K, M, _) = export(&model);
    let dir = temp_dir("round-trip");
    for (name, A) in [("K", &K), ("M", &M)] {
        let path = dir.join(format!("{name}.mtx"));
        write_matrix_market(&path, A.as_ref()).unwrap();
        let back = read_matrix_market(&path).unwrap();
        assert_eq!((back.nrows(), back.ncols()), (A.nrows(), A.ncols()));
        // Same entries, same bits: Rust prints the shortest decimal that parses back exactly.
        assert_eq!(entries(back.as_ref()), entries(A.as_ref()), "{name} changed");
    }
    let text = String::from_utf8(to_matrix_market(K.as_ref())).unwrap();
    assert!(
        text.starts_with("%%MatrixMarket matrix coordinate real general\n"),
        "{}",
        &text[..80]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn symmetric_files_are_expanded_to_both_triangles() {
    let dense = |A: &SparseColMat<usize, f64>| {
        let mut D = vec![vec![0.0; A.ncols()]; A.nrows()];
        for (i, j, bits) in entries(A.as_ref()) {
            D[i][j] = f64::from_bits(bits);
        }
        D
    };
    let expected = vec![vec![4.0, -1.0, 0.0], vec![-1.0, 4.0, -2.5], vec![0.0, -2.5, 3.0]];
    // The standard's lower triangle, with comments, blank lines and odd spacing.
    let lower = "%%MatrixMarket  matrix coordinate real symmetric\n% from code X\n%\n3 3 5\n1 1 4\n2 1 -1\n\n2 2 4\n3 2 -2.5e0\n3  3 3.0\n";
    assert_eq!(
        dense(&parse_matrix_market(lower.as_bytes(), Path::new("l.mtx")).unwrap()),
        expected
    );
    // The upper triangle (as some writers store it), and integer values.
    let upper = "%%MatrixMarket matrix coordinate integer symmetric\n3 3 5\n1 1 4\n1 2 -1\n2 2 4\n2 3 -2\n3 3 3\n";
    let U = dense(&parse_matrix_market(upper.as_bytes(), Path::new("u.mtx")).unwrap());
    assert_eq!(U[1][2], -2.0);
    assert_eq!(U[2][1], -2.0);
    // Duplicates in a general file are summed.
    let dup = "%%MatrixMarket matrix coordinate real general\n2 2 3\n1 1 1.5\n1 1 2.5\n2 1 7\n";
    assert_eq!(
        dense(&parse_matrix_market(dup.as_bytes(), Path::new("d.mtx")).unwrap()),
        vec![vec![4.0, 0.0], vec![7.0, 0.0]]
    );
}

#[test]
fn errors_name_the_file_and_the_line() {
    parse_error("", Some(1), &["empty"]);
    parse_error(
        "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n",
        Some(1),
        &["coordinate"],
    );
    parse_error(
        "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n",
        Some(1),
        &["'complex'"],
    );
    parse_error(
        "%%MatrixMarket matrix coordinate real hermitian\n1 1 1\n1 1 1\n",
        Some(1),
        &["'hermitian'"],
    );
    parse_error("% not a banner\n", Some(1), &["not a Matrix Market banner"]);
    parse_error(
        "%%MatrixMarket matrix coordinate real general\n% only comments\n",
        None,
        &["no size line"],
    );
    parse_error(
        "%%MatrixMarket matrix coordinate real general\n3 3\n",
        Some(2),
        &["size line"],
    );
    parse_error(
        "%%MatrixMarket matrix coordinate real symmetric\n3 2 1\n1 1 1\n",
        Some(2),
        &["must be square"],
    );
    let head = "%%MatrixMarket matrix coordinate real general\n% comment\n3 3 3\n1 1 1.0\n";
    parse_error(
        &format!("{head}4 1 2.0\n3 3 1\n"),
        Some(5),
        &["row index '4' is not in 1..=3"],
    );
    parse_error(&format!("{head}1 0 2.0\n3 3 1\n"), Some(5), &["column index '0'"]);
    parse_error(&format!("{head}1 2 abc\n3 3 1\n"), Some(5), &["value 'abc'"]);
    parse_error(&format!("{head}1 2 NaN\n3 3 1\n"), Some(5), &["not a finite number"]);
    parse_error(&format!("{head}1 2\n3 3 1\n"), Some(5), &["'row column value'"]);
    parse_error(
        &format!("{head}1 2 1\n"),
        None,
        &["announces 3 entries but the file has 2"],
    );
    parse_error(
        &format!("{head}1 2 1\n2 2 1\n3 3 1\n"),
        Some(7),
        &["more entries than the 3"],
    );
    // Both triangles of an entry in a symmetric file would double it.
    let both = "%%MatrixMarket matrix coordinate real symmetric\n2 2 3\n2 1 1\n1 1 1\n1 2 1\n";
    parse_error(both, Some(5), &["entry (1, 2)", "already given on line 3"]);
    // Binary junk.
    let e = parse_matrix_market(b"%%MatrixMarket\n\xff\xfe", Path::new("models/K.mtx")).unwrap_err();
    assert!(
        e.to_string().contains("line 2") && e.to_string().contains("UTF-8"),
        "{e}"
    );
    // A missing file.
    let e = read_matrix_market(Path::new("/nonexistent/K.mtx")).unwrap_err();
    assert!(
        e.to_string().contains("/nonexistent/K.mtx") && e.to_string().contains("cannot read"),
        "{e}"
    );
}

#[test]
fn no_truncation_of_a_file_panics() {
    let (model, _) = free_beam(2);
    let (K, _, _) = export(&model);
    let text = to_matrix_market(K.as_ref());
    for len in 0..text.len() {
        // A cut inside the last value can still be a valid, shorter number: only panics and
        // hangs are failures here.
        let _ = parse_matrix_market(&text[..len], Path::new("cut.mtx"));
    }
}

/// Largest |a - b| over the largest |a|, for matrices of the same shape.
fn relative_difference(a: &DenseMatrix, b: &DenseMatrix) -> f64 {
    assert_eq!((a.nrows, a.ncols), (b.nrows, b.ncols));
    let scale = a.data.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
    a.data
        .iter()
        .zip(&b.data)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// The worst relative difference over the data both ways of reducing must share; `rigid_only`
/// leaves out the second-order invariants and the mesh shapes (which differ by design when
/// spiders were eliminated, see `reduce_external_dofs`).
fn compare(a: &ReducedBody, b: &ReducedBody, rigid_only: bool) -> f64 {
    assert_eq!(a.n_modes, b.n_modes);
    assert_eq!(a.interfaces, b.interfaces);
    let mut worst = relative_difference(&a.K_CB, &b.K_CB)
        .max(relative_difference(&a.M_CB, &b.M_CB))
        .max(relative_difference(&a.inertia.S_t, &b.inertia.S_t))
        .max(relative_difference(&a.inertia.S_r, &b.inertia.S_r))
        .max(relative_difference(&a.Phi_com, &b.Phi_com));
    for (x, y) in a.fixed_interface_omega.iter().zip(&b.fixed_interface_omega) {
        worst = worst.max((x - y).abs() / x);
    }
    let (ia, ib) = (&a.inertia, &b.inertia);
    worst = worst.max((ia.mass - ib.mass).abs() / ia.mass);
    let size = ia.center_of_mass.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for k in 0..3 {
        worst = worst.max((ia.center_of_mass[k] - ib.center_of_mass[k]).abs() / size);
        for l in 0..3 {
            worst = worst.max((ia.inertia_com[k][l] - ib.inertia_com[k][l]).abs() / ia.inertia_com[0][0].abs());
        }
    }
    if !rigid_only {
        worst = worst.max(relative_difference(&ia.S_x, &ib.S_x));
        for (x, y) in ia.S_bar.iter().zip(&ib.S_bar) {
            worst = worst.max(relative_difference(x, y));
        }
        worst = worst.max(relative_difference(
            &a.mesh.as_ref().unwrap().shapes,
            &b.mesh.as_ref().unwrap().shapes,
        ));
    }
    worst
}

#[test]
fn external_matrices_of_an_fe_model_reduce_to_the_same_body() {
    let (model, interfaces) = free_beam(10);
    let settings = CbSettings::new(ModeSelection::Count(5));
    let reference = reduce(&model, "beam", &interfaces, &settings).unwrap();
    // Export K and M through Matrix Market files and read them back, as another code would.
    let (K, M, _) = export(&model);
    let dir = temp_dir("external");
    write_matrix_market(&dir.join("K.mtx"), K.as_ref()).unwrap();
    write_matrix_market(&dir.join("M.mtx"), M.as_ref()).unwrap();
    let K = read_matrix_market(&dir.join("K.mtx")).unwrap();
    let M = read_matrix_market(&dir.join("M.mtx")).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    let by_index: Vec<(String, usize)> = interfaces.iter().map(|(n, node)| (n.clone(), node.index())).collect();
    let body = reduce_external(&nodes, K.as_ref(), M.as_ref(), 6, "beam", &by_index, &settings).unwrap();
    let worst = compare(&reference, &body, false);
    println!("beam: worst relative difference to reduce() {worst:.3e}");
    // The same matrices in the same dof order go through the same arithmetic; 1e-12 allows
    // for a different summation order in a parallel product.
    assert!(worst <= 1e-12, "worst relative difference {worst:.3e}");
}

#[test]
fn external_solid_with_spiders_keeps_the_rigid_mass_data() {
    // A hex8 bar with an RBE2 spider at each end, exported after the spiders were eliminated:
    // 3 dofs on the solid nodes, 6 on the interface nodes.
    let mesh = fe_model::box_mesh::box_mesh(CellKind::Hex8, [0.4, 0.1, 0.05], [8, 2, 1]).unwrap();
    let material = IsotropicMaterial::new("aluminium", 70e9, 0.33, 2700.0).unwrap();
    let mut model = fe_model::box_mesh::solid_model(mesh, material, MassKind::Consistent).unwrap();
    let a = add_interface_on_set(&mut model, "A", "x0", None, SpiderKind::Rbe2).unwrap();
    let b = add_interface_on_set(&mut model, "B", "x1", None, SpiderKind::Rbe2).unwrap();
    let interfaces = vec![("A".to_string(), a), ("B".to_string(), b)];
    let settings = CbSettings::new(ModeSelection::Count(4));
    let reference = reduce(&model, "bar", &interfaces, &settings).unwrap();
    let (K, M, dofs) = export(&model);
    let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    let by_index: Vec<(String, usize)> = interfaces.iter().map(|(n, node)| (n.clone(), node.index())).collect();
    let body = reduce_external_dofs(&nodes, K.as_ref(), M.as_ref(), &dofs, "bar", &by_index, &settings).unwrap();
    // K_CB, M_CB, frequencies and the rigid-body mass data are the same (the spiders
    // reproduce rigid motion, see reduce_external_dofs); the second-order invariants are not.
    let worst = compare(&reference, &body, true);
    println!("hex8 bar with RBE2 spiders: worst relative difference to reduce() {worst:.3e}");
    assert!(worst <= 1e-10, "worst relative difference {worst:.3e}");
    // With 3 dofs per node the interface nodes have no rotations: a named error.
    let n3 = nodes.len() * 3;
    let K3 = SparseColMat::<usize, f64>::try_new_from_triplets(
        n3,
        n3,
        &(0..n3).map(|i| Triplet::new(i, i, 1.0)).collect::<Vec<_>>(),
    )
    .unwrap();
    let e = reduce_external(&nodes, K3.as_ref(), K3.as_ref(), 3, "bar", &by_index, &settings).unwrap_err();
    assert!(
        matches!(&e, ReductionError::Interface { name, .. } if name == "A") && e.to_string().contains("rx"),
        "{e}"
    );
}

#[test]
fn inconsistent_external_models_are_refused_with_the_reason() {
    let (model, interfaces) = free_beam(4);
    let (K, M, _) = export(&model);
    let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    let by_index: Vec<(String, usize)> = interfaces.iter().map(|(n, node)| (n.clone(), node.index())).collect();
    let settings = CbSettings::new(ModeSelection::Count(2));
    let run = |nodes: &[[f64; 3]], K: SparseColMatRef<'_, usize, f64>, dpn: usize, ifaces: &[(String, usize)]| {
        reduce_external(nodes, K, M.as_ref(), dpn, "beam", ifaces, &settings)
            .unwrap_err()
            .to_string()
    };
    assert!(run(&nodes, K.as_ref(), 4, &by_index).contains("dofs_per_node must be 3"));
    assert!(run(&nodes[1..], K.as_ref(), 6, &by_index).contains("K has 30 rows but 4 nodes x 6 dofs per node make 24"));
    let ghost = vec![("ghost".to_string(), 17)];
    let e = run(&nodes, K.as_ref(), 6, &ghost);
    assert!(
        e.contains("interface 'ghost'") && e.contains("node 17 does not exist"),
        "{e}"
    );
    // Only the lower triangle of K: the missing upper entries are named.
    let mut lower = Vec::new();
    for j in 0..K.ncols() {
        for (&i, &v) in K.as_ref().row_idx_of_col_raw(j).iter().zip(K.as_ref().val_of_col(j)) {
            if i >= j {
                lower.push(Triplet::new(i, j, v));
            }
        }
    }
    let L = SparseColMat::try_new_from_triplets(K.nrows(), K.ncols(), &lower).unwrap();
    let e = run(&nodes, L.as_ref(), 6, &by_index);
    assert!(
        e.contains("K is not symmetric: entry (") && e.contains("both triangles"),
        "{e}"
    );
    // A non-finite coordinate.
    let mut bad = nodes.clone();
    bad[2][1] = f64::NAN;
    assert!(run(&bad, K.as_ref(), 6, &by_index).contains("node 2 has a non-finite coordinate"));
}
