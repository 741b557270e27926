// `reduction::mbdyn`: MBDyn `.fem` files (included by `tests/unit.rs`).
//
// * The manual's own example file (three nodes, two modes, lumped masses) reads into the
//   inertia the manual states and the frequencies its matrices give.
// * A written file follows the layout MBDyn's reader requires, record by record.
// * A solid body written and read back is the same body: interfaces, frequencies, K_CB, M_CB
//   and every mass invariant; a beam body too (but for the second moments, see the module
//   docs), whichever interface is the reference.
// * Malformed files give errors with file and line; no cut or mutated file panics.

use fe_model::box_mesh::{box_mesh, solid_model};
use fe_model::{add_interface_on_set, BeamProperties, BeamSection, BeamTheory, CellKind, FeModel, IsotropicMaterial, MassKind, SpiderKind};
use nalgebra::{Point3, Vector3};
use reduction::mbdyn::{parse_mbdyn_fem, to_mbdyn_fem, FemError};
use reduction::{reduce, CbSettings, DenseMatrix, ModeSelection, ReducedBody};
use std::path::Path;

/// The manual's "Example: Dynamic Model" (input manual, appendix "Modal Element Data"):
/// three aligned nodes with unit lumped masses and inertias, two modes.
pub(crate) const MANUAL_EXAMPLE: &str = "** MBDyn MODAL DATA FILE
** NODE SET \"ALL\"


** RECORD GROUP 1, HEADER
**   REVISION,  NODE,  NORMAL, ATTACHMENT, CONSTRAINT, REJECTED MODES.
      REV0         3         2         0         0         0
**
** RECORD GROUP 2, FINITE ELEMENT NODE LIST
     1001 1002 1003

**
** RECORD GROUP 3, INITIAL MODAL DISPLACEMENTS
 0 0
**
** RECORD GROUP 4, INITIAL MODALVELOCITIES
 0 0
**
** RECORD GROUP 5, NODAL X COORDINATES
 0
 0
 0
**
** RECORD GROUP 6, NODAL Y COORDINATES
-2.
 0
 2.
**
** RECORD GROUP 7, NODAL Z COORDINATES
 0
 0
 0
**
** RECORD GROUP 8, MODE SHAPES
**    NORMAL MODE SHAPE #  1
0 0 1 0 0 0
0 0 0 0 0 0
0 0 1 0 0 0
**    NORMAL MODE SHAPE #  2
1 0 0 0 0 0
0 0 0 0 0 0
1 0 0 0 0 0
**
** RECORD GROUP 9, MODAL MASS MATRIX
2 0
0 2
**
** RECORD GROUP 10, MODAL STIFFNESS MATRIX
1 0
0 1e2
**
** RECORD GROUP 11, DIAGONAL OF LUMPED MASS MATRIX
1 1 1 1 1 1
1 1 1 1 1 1
1 1 1 1 1 1
";

fn parse(text: &str, interfaces: Option<&[String]>) -> Result<ReducedBody, FemError> {
    parse_mbdyn_fem(text.as_bytes(), Path::new("body.fem"), interfaces).map(|(b, _)| b)
}

#[test]
fn the_manuals_example_reads_into_its_stated_inertia_and_frequencies() {
    let middle = ["1002".to_string()];
    let body = parse(MANUAL_EXAMPLE, Some(&middle)).unwrap();
    // The manual: m = 3, x_CM = 0, J = diag(11, 3, 11).
    let i = &body.inertia;
    assert_eq!(i.mass, 3.0);
    assert_eq!(i.center_of_mass, [0.0; 3]);
    assert_eq!(i.inertia_com, [[11.0, 0.0, 0.0], [0.0, 3.0, 0.0], [0.0, 0.0, 11.0]]);
    // With the middle node as the interface the two modes are the fixed-interface modes:
    // omega^2 = k / m = 1/2 and 100/2. 1e-14: a 2x2 eigenproblem solved in double precision.
    assert_eq!(body.n_modes, 2);
    assert!((body.fixed_interface_omega[0] - 0.5f64.sqrt()).abs() < 1e-14);
    assert!((body.fixed_interface_omega[1] - 50f64.sqrt()).abs() < 1e-13);
    // Mode 1 moves the outer nodes along z: it couples with the rotation about x
    // (int rho x~ S = sum m_i y_i~ phi_i = 0 by symmetry) and not with the translation
    // (int rho S = 2 e_z).
    let S_t = &i.S_t;
    let col = 6 + (0..2).find(|&k| body.fixed_interface_omega[k] < 1.0).unwrap();
    assert!((S_t.get(2, col).abs() - 2.0 / 2f64.sqrt()).abs() < 1e-14, "{}", S_t.get(2, col));
    // Every exposed node as an interface needs 18 coordinates: 6 rigid + 2 modes do not.
    let error = parse(MANUAL_EXAMPLE, None).unwrap_err().to_string();
    assert!(error.contains("18 coordinates"), "{error}");
}

/// A clamped-free solid block [0, 0.6] x [0, 0.1] x [0, 0.05] (distinct frequencies) with RBE2
/// interfaces on both end faces.
fn solid_body(modes: usize) -> ReducedBody {
    let mesh = box_mesh(CellKind::Hex8, [0.6, 0.1, 0.05], [6, 2, 1]).unwrap();
    let steel = IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap();
    let mut model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
    let a = add_interface_on_set(&mut model, "end a", "x0", None, SpiderKind::Rbe2).unwrap();
    let b = add_interface_on_set(&mut model, "end b", "x1", None, SpiderKind::Rbe3).unwrap();
    let mut settings = CbSettings::new(ModeSelection::Count(modes));
    settings.keep_mesh_shapes = false;
    reduce(&model, "block", &[("end a".into(), a), ("end b".into(), b)], &settings).unwrap()
}

/// A free beam with a 2:1 rectangular section along a skewed axis, interfaces at the ends and
/// an inner node (unequal segments: no repeated fixed-interface frequencies).
fn beam_body() -> ReducedBody {
    let mut model = FeModel::default();
    let material = model.add_material(IsotropicMaterial::new("steel", 2.1e11, 0.3, 7850.0).unwrap());
    let section = model.add_section(BeamSection::rectangle("r", 0.02, 0.01, 0.3).unwrap());
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::new(0.0, 0.0, 1.0),
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    };
    let nodes = fe_model::generate::straight_beam(
        &mut model,
        Point3::new(0.1, 0.2, 0.3),
        Point3::new(1.1, 0.5, 0.4),
        8,
        &props,
        None,
    )
    .unwrap();
    let interfaces = vec![("a".to_string(), nodes[0]), ("m".to_string(), nodes[3]), ("b".to_string(), nodes[8])];
    let mut settings = CbSettings::new(ModeSelection::Count(5));
    settings.keep_mesh_shapes = false;
    reduce(&model, "beam", &interfaces, &settings).unwrap()
}

/// max |a - b| / max |a|.
fn relative(a: &DenseMatrix, b: &DenseMatrix) -> f64 {
    assert_eq!((a.nrows, a.ncols), (b.nrows, b.ncols));
    let scale = a.data.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
    a.data.iter().zip(&b.data).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

// The file holds every value to round-trip precision; the read-back body is rebuilt by a
// change of basis (pseudo-inverse, null space, Cholesky, a dense eigensolution) whose
// round-off, amplified by the ratio of the largest to the smallest stiffness (about 1e5 for
// these bodies), stays below 1e-9 of each matrix's largest entry.
const SAME_BODY: f64 = 1e-9;

fn compare(original: &ReducedBody, back: &ReducedBody, second_moments: bool) {
    assert_eq!(back.interfaces.len(), original.interfaces.len());
    for (p, q) in original.interfaces.iter().zip(&back.interfaces) {
        assert_eq!(q.name, p.name.replace(' ', "_"));
        for k in 0..3 {
            assert!((p.position[k] - q.position[k]).abs() < 1e-14, "{:?} {:?}", p.position, q.position);
        }
    }
    assert_eq!(back.n_modes, original.n_modes);
    for (w, v) in original.fixed_interface_omega.iter().zip(&back.fixed_interface_omega) {
        assert!(((w - v) / w).abs() < 1e-10, "{w} {v}");
    }
    let (o, b) = (&original.inertia, &back.inertia);
    assert!(((o.mass - b.mass) / o.mass).abs() < 1e-14);
    for k in 0..3 {
        assert!((o.center_of_mass[k] - b.center_of_mass[k]).abs() < 1e-14);
    }
    let mut checks = vec![
        ("K_CB", relative(&original.K_CB, &back.K_CB)),
        ("M_CB", relative(&original.M_CB, &back.M_CB)),
        ("S_t", relative(&o.S_t, &b.S_t)),
        ("S_r", relative(&o.S_r, &b.S_r)),
        ("Phi_com", relative(&original.Phi_com, &back.Phi_com)),
    ];
    if second_moments {
        checks.push(("S_x", relative(&o.S_x, &b.S_x)));
        for k in 0..9 {
            checks.push(("S_bar", relative(&o.S_bar[k], &b.S_bar[k])));
        }
    }
    for (what, d) in checks {
        assert!(d < SAME_BODY, "{what} differs by {d:e}");
    }
}

#[test]
fn a_solid_body_written_and_read_back_is_the_same_body() {
    let body = solid_body(6);
    for reference in [0, 1] {
        let text = to_mbdyn_fem(&body, reference, Path::new("block.fem")).unwrap();
        let back = parse(&text, None).unwrap();
        assert_eq!(back.name, "block");
        compare(&body, &back, true);
    }
}

#[test]
fn a_beam_body_written_and_read_back_is_the_same_body() {
    let body = beam_body();
    let text = to_mbdyn_fem(&body, 1, Path::new("beam.fem")).unwrap();
    compare(&body, &parse(&text, None).unwrap(), true);
    // Without the FLEXMBS SECOND MOMENT line (a file from elsewhere), the second moment of
    // the rigid motions comes from J, which holds the sections' rotary inertia: all but the
    // second-order invariants still agree.
    let foreign: String = text
        .lines()
        .filter(|l| !l.starts_with("** FLEXMBS SECOND MOMENT"))
        .map(|l| format!("{l}\n"))
        .collect();
    compare(&body, &parse(&foreign, None).unwrap(), false);
    let error = to_mbdyn_fem(&body, 3, Path::new("beam.fem")).unwrap_err().to_string();
    assert!(error.contains("reference interface 3"), "{error}");
}

/// The layout MBDyn's reader (`struct/modal.cc`, `ReadModal`) needs, checked line by line as
/// it reads: record numbers it knows, exactly one comment line between RECORD GROUP 1 and the
/// header values, a comment line before each mode's values in record 8, each mode's values
/// ending its line, the value counts of every record, and no record 11 (which would make MBDyn
/// add lumped-mass invariants to the ones given).
#[test]
fn a_written_file_has_the_layout_mbdyns_reader_needs() {
    let body = solid_body(4);
    let text = to_mbdyn_fem(&body, 0, Path::new("block.fem")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let header = lines.iter().position(|l| l.starts_with("** RECORD GROUP 1,")).unwrap();
    assert!(lines[header + 1].starts_with("**"), "one comment line after the header record");
    let values: Vec<&str> = lines[header + 2].split_whitespace().collect();
    let (N, nx) = (body.interfaces.len(), body.n_coordinates() - 6);
    assert_eq!(values, vec!["REV0".to_string(), N.to_string(), nx.to_string(), "0".into(), "0".into(), "0".into()]);
    let records: Vec<u32> = lines
        .iter()
        .filter_map(|l| l.strip_prefix("** RECORD GROUP "))
        .map(|r| r.split(',').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(records, vec![1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 15, 16, 17, 18]);
    // Everything else is a comment line ("**" first), which MBDyn skips between records.
    assert!(lines[..header].iter().all(|l| l.starts_with("**")));
    // Values per record.
    let count = |record: u32| -> usize {
        let start = lines.iter().position(|l| l.starts_with(&format!("** RECORD GROUP {record},"))).unwrap();
        lines[start + 1..]
            .iter()
            .take_while(|l| !l.starts_with("** RECORD GROUP") && !l.starts_with("** END"))
            .filter(|l| !l.starts_with("**"))
            .map(|l| l.split_whitespace().count())
            .sum()
    };
    for (record, expected) in [
        (2, N),
        (3, nx),
        (4, nx),
        (5, N),
        (6, N),
        (7, N),
        (8, 6 * N * nx),
        (9, nx * nx),
        (10, nx * nx),
        (12, 13),
        (14, 3 * nx),
        (15, 3 * nx),
        (16, 9 * nx),
        (17, 3 * nx * nx),
        (18, 9 * nx * nx),
    ] {
        assert_eq!(count(record), expected, "record {record}");
    }
    // Record 8: per mode a comment line, then N lines of six values.
    let start = lines.iter().position(|l| l.starts_with("** RECORD GROUP 8,")).unwrap();
    for mode in 0..nx {
        let at = start + 1 + mode * (N + 1);
        assert!(lines[at].starts_with("**    NORMAL MODE SHAPE #"), "{}", lines[at]);
        for node in 0..N {
            assert_eq!(lines[at + 1 + node].split_whitespace().count(), 6);
        }
    }
    assert_eq!(lines.last(), Some(&"** END OF FILE"));
}

#[test]
fn malformed_files_are_located() {
    let body = solid_body(2);
    let good = to_mbdyn_fem(&body, 0, Path::new("block.fem")).unwrap();
    let line_of = |text: &str, prefix: &str| text.lines().position(|l| l.starts_with(prefix)).unwrap() + 1;
    let expect = |text: &str, line: Option<usize>, fragments: &[&str]| {
        let message = parse(text, None).unwrap_err().to_string();
        if let Some(line) = line {
            assert!(message.starts_with(&format!("body.fem:{line}:")), "{message}");
        } else {
            assert!(message.starts_with("body.fem"), "{message}");
        }
        for f in fragments {
            assert!(message.contains(f), "'{f}' missing: {message}");
        }
    };
    // 1. A value that is not a number.
    let at = line_of(&good, "** RECORD GROUP 9,") + 1;
    let bad = good.replacen(good.lines().nth(at - 1).unwrap(), "1.0 x 2", 1);
    expect(&bad, Some(at), &["RECORD GROUP 9", "modal mass", "'x'"]);
    // 2. A record group MBDyn does not know.
    let bad = good.replace("** RECORD GROUP 17,", "** RECORD GROUP 20,");
    expect(&bad, Some(line_of(&good, "** RECORD GROUP 17,")), &["RECORD GROUP 20"]);
    // 3. A record given twice.
    let bad = good.replace("** RECORD GROUP 4,", "** RECORD GROUP 3,");
    expect(&bad, Some(line_of(&good, "** RECORD GROUP 4,")), &["RECORD GROUP 3 is given twice"]);
    // 4. A missing record.
    let cut = good.find("** RECORD GROUP 10,").unwrap();
    let end = good.find("** RECORD GROUP 12,").unwrap();
    let bad = format!("{}{}", &good[..cut], &good[end..]);
    expect(&bad, None, &["RECORD GROUP 10", "missing"]);
    // 5. Too few values in a record.
    let at = line_of(&good, "** RECORD GROUP 7,") + 1;
    let bad: String = good
        .lines()
        .enumerate()
        .filter(|(k, _)| k + 1 != at)
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    expect(&bad, None, &["RECORD GROUP 7", "node coordinate", "end of the record"]);
    // 6. Too many values.
    let bad = good.replacen("** RECORD GROUP 3, INITIAL MODAL DISPLACEMENTS\n", "** RECORD GROUP 3, INITIAL MODAL DISPLACEMENTS\n0\n", 1);
    expect(&bad, None, &["RECORD GROUP 3", "end of the record"]);
    // 7. A record before the header.
    expect("** RECORD GROUP 2\n1 2\n", Some(1), &["before RECORD GROUP 1"]);
    // 8. Data before any record.
    expect("1 2 3\n", Some(1), &["before the first RECORD GROUP"]);
    // 9. No inertia at all.
    let cut = good.find("** RECORD GROUP 12,").unwrap();
    let bad = format!("{}** END OF FILE\n", &good[..cut]);
    expect(&bad, None, &["no inertia"]);
    // 10. An interface label the file does not have.
    let message = parse_mbdyn_fem(good.as_bytes(), Path::new("body.fem"), Some(&["nope".to_string()]))
        .unwrap_err()
        .to_string();
    assert!(message.contains("'nope'") && message.contains("end_a"), "{message}");
    // 11. A non-positive mass.
    let at = line_of(&good, "** RECORD GROUP 12,") + 1;
    let bad = good.replacen(good.lines().nth(at - 1).unwrap(), "-1.0", 1);
    expect(&bad, None, &["mass is -1e0"]);
    // 12. The static example of the manual: zero modal mass cannot give fixed-interface modes.
    let static_example = MANUAL_EXAMPLE
        .replace("2 0\n0 2\n", "0 0\n0 0\n")
        .replace(
            "** RECORD GROUP 11, DIAGONAL OF LUMPED MASS MATRIX\n1 1 1 1 1 1\n1 1 1 1 1 1\n1 1 1 1 1 1\n",
            "** RECORD GROUP 12, GLOBAL INERTIA\n 3\n 0  0  0\n11  0  0\n 0  3  0\n 0  0 11\n",
        );
    let message = parse(&static_example, Some(&["1002".to_string()])).unwrap_err().to_string();
    assert!(message.contains("modal mass is not positive definite"), "{message}");
}

#[test]
fn cut_and_mutated_files_never_panic() {
    let body = solid_body(2);
    let good = to_mbdyn_fem(&body, 0, Path::new("block.fem")).unwrap().into_bytes();
    let run = |bytes: &[u8], what: &dyn Fn() -> String| {
        let result = std::panic::catch_unwind(|| parse_mbdyn_fem(bytes, Path::new("fuzz.fem"), None));
        match result {
            Ok(Ok(_)) | Ok(Err(_)) => {}
            Err(_) => panic!("panicked on {}", what()),
        }
    };
    for len in (0..good.len()).step_by(97) {
        run(&good[..len], &|| format!("cut at {len}"));
    }
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    };
    const INTERESTING: &[u8] = b"0123456789-+.e *\n";
    for case in 0..200 {
        let mut bytes = good.clone();
        for _ in 0..1 + next() % 4 {
            let at = (next() % bytes.len() as u64) as usize;
            bytes[at] = INTERESTING[(next() % INTERESTING.len() as u64) as usize];
        }
        run(&bytes, &|| format!("mutation {case}"));
    }
}
