//! gmsh reader (`fe_model::mesh::gmsh`).
//!
//! * The fixtures of `tests/data/gmsh` (written by `make_fixtures.py`) read the same from MSH 4.1
//!   ASCII, 4.1 binary, 2.2 ASCII and 2.2 binary, with the expected cells and sets.
//! * Inline `parse` cases: sparse and unordered node tags, physical names, unnamed groups,
//!   points, MSH 2.2's repeated elements, parametric nodes, CRLF, both endiannesses.
//! * Node ordering per element type: our edge tables against gmsh's reference elements
//!   (`gmsh_reference_elements.txt`), one element per type at those coordinates, and the
//!   geometry of every fixture cell.
//! * Each malformed input gives its located error (file, line or byte, entity).
//! * No panic on random bytes, on every prefix of every fixture, or on mutated fixtures.

use fe_model::mesh::gmsh::{self, cell_kind_from_gmsh_type, node_permutation_from_gmsh, Location, MshError};
use fe_model::{CellId, CellKind, Mesh, NodeId};
use nalgebra::{Matrix3, Point3, Vector3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

// ------------------------------------------------------------------------------------ helpers

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gmsh")
}

const MESHES: [&str; 5] = ["hex8", "hex20", "tet4", "tet10", "wedge6"];
const ENCODINGS: [&str; 4] = ["41", "41_bin", "22", "22_bin"];

fn fixture_path(mesh: &str, encoding: &str) -> PathBuf {
    data_dir().join(format!("{mesh}_{encoding}.msh"))
}

fn read_fixture(mesh: &str, encoding: &str) -> Mesh {
    let path = fixture_path(mesh, encoding);
    gmsh::read(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn inline(text: &str) -> Result<Mesh, MshError> {
    gmsh::parse(text, Path::new("inline.msh"))
}

fn ids(ids: &[u32]) -> Vec<NodeId> {
    ids.iter().map(|&i| NodeId(i)).collect()
}

fn cells(ids: &[u32]) -> Vec<CellId> {
    ids.iter().map(|&i| CellId(i)).collect()
}

/// Structural invariants any successfully parsed mesh must satisfy.
fn check_invariants(mesh: &Mesh) {
    let n = mesh.nodes.len();
    assert_eq!(mesh.node_tags.len(), n);
    for cell in &mesh.cells {
        assert_eq!(cell.nodes.len(), cell.kind.node_count(), "cell {}", cell.tag);
        assert!(cell.nodes.iter().all(|id| id.index() < n), "cell {}", cell.tag);
    }
    for set in mesh.node_sets.values() {
        assert!(set.windows(2).all(|w| w[0] < w[1]) && set.iter().all(|id| id.index() < n));
    }
    for set in mesh.cell_sets.values() {
        assert!(set.windows(2).all(|w| w[0] < w[1]) && set.iter().all(|id| id.index() < mesh.cells.len()));
    }
}

/// Mid-edge nodes `(node, corner a, corner b)` of each kind, in our (= gmsh's) ordering, as
/// documented in the module docs of `fe_model::mesh::gmsh`.
fn mid_edge_nodes(kind: CellKind) -> &'static [(usize, usize, usize)] {
    match kind {
        CellKind::Tri6 => &[(3, 0, 1), (4, 1, 2), (5, 2, 0)],
        CellKind::Quad8 => &[(4, 0, 1), (5, 1, 2), (6, 2, 3), (7, 3, 0)],
        CellKind::Tet10 => &[(4, 0, 1), (5, 1, 2), (6, 2, 0), (7, 3, 0), (8, 3, 2), (9, 3, 1)],
        CellKind::Hex20 => &[
            (8, 0, 1),
            (9, 0, 3),
            (10, 0, 4),
            (11, 1, 2),
            (12, 1, 5),
            (13, 2, 3),
            (14, 2, 6),
            (15, 3, 7),
            (16, 4, 5),
            (17, 4, 7),
            (18, 5, 6),
            (19, 6, 7),
        ],
        _ => &[],
    }
}

/// Reference coordinates of the corners, in our ordering (module docs of the reader).
fn corners(kind: CellKind) -> Vec<[f64; 3]> {
    const HEX: [[f64; 3]; 8] = [
        [-1., -1., -1.],
        [1., -1., -1.],
        [1., 1., -1.],
        [-1., 1., -1.],
        [-1., -1., 1.],
        [1., -1., 1.],
        [1., 1., 1.],
        [-1., 1., 1.],
    ];
    const TET: [[f64; 3]; 4] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.], [0., 0., 1.]];
    const WEDGE: [[f64; 3]; 6] = [
        [0., 0., -1.],
        [1., 0., -1.],
        [0., 1., -1.],
        [0., 0., 1.],
        [1., 0., 1.],
        [0., 1., 1.],
    ];
    const QUAD: [[f64; 3]; 4] = [[-1., -1., 0.], [1., -1., 0.], [1., 1., 0.], [-1., 1., 0.]];
    const TRI: [[f64; 3]; 3] = [[0., 0., 0.], [1., 0., 0.], [0., 1., 0.]];
    match kind {
        CellKind::Line2 => vec![[-1., 0., 0.], [1., 0., 0.]],
        CellKind::Tri3 | CellKind::Tri6 => TRI.to_vec(),
        CellKind::Quad4 | CellKind::Quad8 => QUAD.to_vec(),
        CellKind::Tet4 | CellKind::Tet10 => TET.to_vec(),
        CellKind::Hex8 | CellKind::Hex20 => HEX.to_vec(),
        CellKind::Wedge6 => WEDGE.to_vec(),
    }
}

/// gmsh's reference coordinates per gmsh type, from `gmsh_reference_elements.txt`.
fn gmsh_reference_elements() -> HashMap<i32, Vec<[f64; 3]>> {
    let text = std::fs::read_to_string(data_dir().join("gmsh_reference_elements.txt")).unwrap();
    let mut out: HashMap<i32, Vec<[f64; 3]>> = HashMap::new();
    for line in text.lines().filter(|l| !l.starts_with('#') && !l.trim().is_empty()) {
        let v: Vec<f64> = line.split_whitespace().map(|t| t.parse().unwrap()).collect();
        let nodes = out.entry(v[0] as i32).or_default();
        assert_eq!(nodes.len(), v[1] as usize, "nodes listed in order");
        nodes.push([v[2], v[3], v[4]]);
    }
    out
}

const SUPPORTED_TYPES: [i32; 10] = [1, 2, 3, 4, 5, 6, 9, 11, 16, 17];

/// Signed volume spanned by three edges from corner 0 (orientation of a solid cell).
fn corner_det(x: &[Point3<f64>], a: usize, b: usize, c: usize) -> f64 {
    Matrix3::from_columns(&[x[a] - x[0], x[b] - x[0], x[c] - x[0]]).determinant()
}

// xorshift64* with a fixed seed (`fe_model::fuzz::Mutator`), so that a failure can be replayed.
use fe_model::fuzz::Mutator as Rng;

/// Parses `bytes`, turning a panic into a test failure that names the input.
fn parse_without_panic(bytes: &[u8], what: &dyn Fn() -> String) {
    let result = std::panic::catch_unwind(|| gmsh::parse(bytes, Path::new("fuzz.msh")));
    match result {
        Ok(Ok(mesh)) => check_invariants(&mesh),
        Ok(Err(error)) => {
            // Rendering the message must not panic either.
            let _ = error.to_string();
        }
        Err(_) => panic!("parse panicked on {}", what()),
    }
}

// ------------------------------------------------------------------------------------ fixtures

// Coordinates: ASCII MSH holds `%.16g`, at most half a unit in the 16th significant digit
// (5e-16 relative) away from the binary doubles; the box is of size 1.
const ASCII_ROUNDING: f64 = 4.0 * f64::EPSILON;

#[test]
fn all_encodings_of_each_fixture_give_the_same_mesh() {
    for mesh_name in MESHES {
        let reference = read_fixture(mesh_name, "41_bin");
        check_invariants(&reference);
        for encoding in ENCODINGS {
            let mesh = read_fixture(mesh_name, encoding);
            let context = format!("{mesh_name}_{encoding}");
            assert_eq!(mesh.node_tags, reference.node_tags, "{context}");
            assert_eq!(mesh.cells, reference.cells, "{context}");
            assert_eq!(mesh.node_sets, reference.node_sets, "{context}");
            assert_eq!(mesh.cell_sets, reference.cell_sets, "{context}");
            for (a, b) in mesh.nodes.iter().zip(&reference.nodes) {
                assert!((a - b).norm() <= ASCII_ROUNDING, "{context}: {a} vs {b}");
            }
        }
    }
}

/// Checks the groups every fixture has: "body" (volume), "clamp" (x = 0), "tip" (x = 1).
fn check_box_groups(mesh: &Mesh, volume: CellKind, face: CellKind, expected_volumes: usize) {
    let body = &mesh.cell_sets["body"];
    assert_eq!(body.len(), expected_volumes);
    assert!(body.iter().all(|c| mesh.cells[c.index()].kind == volume));
    // The body's node set is exactly the nodes of its cells.
    let mut body_nodes: Vec<NodeId> = body.iter().flat_map(|c| mesh.cells[c.index()].nodes.clone()).collect();
    body_nodes.sort();
    body_nodes.dedup();
    assert_eq!(mesh.node_sets["body"], body_nodes);
    for (name, x) in [("clamp", 0.0), ("tip", 1.0)] {
        let set = &mesh.cell_sets[name];
        assert!(!set.is_empty(), "{name}");
        assert!(set.iter().all(|c| mesh.cells[c.index()].kind == face), "{name}");
        let nodes = &mesh.node_sets[name];
        assert!(
            nodes
                .iter()
                .all(|n| (mesh.nodes[n.index()].x - x).abs() <= ASCII_ROUNDING),
            "{name}"
        );
        // Every node of the mesh on that face is in the set.
        let on_face = mesh.nodes.iter().filter(|p| (p.x - x).abs() <= ASCII_ROUNDING).count();
        assert_eq!(nodes.len(), on_face, "{name}");
    }
}

#[test]
fn fixtures_have_the_expected_cells_and_sets() {
    let hex8 = read_fixture("hex8", "41");
    // 4 x 2 x 2 hexes; 2 x 2 quads on each end; 4 lines on the y = z = 0 edge.
    check_box_groups(&hex8, CellKind::Hex8, CellKind::Quad4, 16);
    assert_eq!(hex8.nodes.len(), 5 * 3 * 3);
    assert_eq!(hex8.cells.len(), 16 + 4 + 4 + 4);
    let corner = &hex8.node_sets["tip_corner"];
    assert_eq!(corner.len(), 1);
    assert_eq!(hex8.nodes[corner[0].index()], Point3::new(1.0, 0.2, 0.2));
    assert!(
        !hex8.cell_sets.contains_key("tip_corner"),
        "a point group has no cell set"
    );
    // The unnamed physical curve 10.
    let edge = &hex8.cell_sets["physical_1_10"];
    assert_eq!(edge.len(), 4);
    assert!(edge.iter().all(|c| hex8.cells[c.index()].kind == CellKind::Line2));
    let edge_nodes = &hex8.node_sets["physical_1_10"];
    assert_eq!(edge_nodes.len(), 5);
    assert!(edge_nodes
        .iter()
        .all(|n| hex8.nodes[n.index()].y == 0.0 && hex8.nodes[n.index()].z == 0.0));
    // Cell tags are gmsh's element tags (the point element took tag 1).
    assert_eq!(hex8.cells[0].tag, 2);

    let hex20 = read_fixture("hex20", "41");
    check_box_groups(&hex20, CellKind::Hex20, CellKind::Quad8, 4);
    let tet4 = read_fixture("tet4", "41");
    check_box_groups(&tet4, CellKind::Tet4, CellKind::Tri3, tet4.cell_sets["body"].len());
    assert!(tet4.cell_sets["body"].len() >= 6 * 3);
    let tet10 = read_fixture("tet10", "41");
    check_box_groups(&tet10, CellKind::Tet10, CellKind::Tri6, tet10.cell_sets["body"].len());
    let wedge6 = read_fixture("wedge6", "41");
    check_box_groups(
        &wedge6,
        CellKind::Wedge6,
        CellKind::Tri3,
        wedge6.cell_sets["body"].len(),
    );
    assert_eq!(wedge6.cell_sets["body"].len(), 3 * wedge6.cell_sets["clamp"].len());
}

#[test]
fn read_names_the_path_when_the_file_is_missing() {
    let path = data_dir().join("no_such_file.msh");
    let error = gmsh::read(&path).unwrap_err();
    assert!(matches!(error, MshError::Io { .. }));
    assert!(error.to_string().contains("no_such_file.msh"), "{error}");
}

// ------------------------------------------------------------------------------------ inline

/// A unit cube hex8 (gmsh tag 42) with sparse, unordered node tags, a quad (43) on its face
/// x = 0 and a point (44) at (1, 1, 1). The volume entity is in groups 1 "body" and 9 (no
/// name); the face in 5 "left face"; the point in 7 "corner"; group 6 "empty" has no entity.
const CUBE_41: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
4
0 7 "corner"
2 5 "left face"
2 6 "empty"
3 1 "body"
$EndPhysicalNames
$Comments
skipped, even with $Nodes inside
$EndComments
$Entities
1 0 1 1
3 1 1 1 1 7
2 0 0 0 0 1 1 1 5 0
1 0 0 0 1 1 1 2 1 9 1 2
$EndEntities
$Nodes
2 8 10 80
3 1 0 4
50
10
80
20
0 1 1
0 0 1
0 0 0
1 0 0
2 2 0 4
70
30
60
40
1 0 1
1 1 1
1 1 0
0 1 0
$EndNodes
$Elements
3 3 42 44
0 3 15 1
44 30
3 1 5 1
42 80 20 60 40 10 70 30 50
2 2 3 1
43 80 40 50 10
$EndElements
"#;

/// The same mesh in MSH 2.2: the hex is written once per physical group (1 and 9).
const CUBE_22: &str = r#"$MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
4
0 7 "corner"
2 5 "left face"
2 6 "empty"
3 1 "body"
$EndPhysicalNames
$Nodes
8
50 0 1 1
10 0 0 1
80 0 0 0
20 1 0 0
70 1 0 1
30 1 1 1
60 1 1 0
40 0 1 0
$EndNodes
$Elements
4
44 15 2 7 3 30
42 5 2 1 1 80 20 60 40 10 70 30 50
42 5 2 9 1 80 20 60 40 10 70 30 50
43 3 2 5 2 80 40 50 10
$EndElements
"#;

fn check_cube(mesh: &Mesh) {
    check_invariants(mesh);
    // Dense ids in order of appearance; gmsh tags kept.
    assert_eq!(mesh.node_tags, [50, 10, 80, 20, 70, 30, 60, 40]);
    assert_eq!(mesh.nodes[2], Point3::new(0.0, 0.0, 0.0));
    assert_eq!(mesh.nodes[5], Point3::new(1.0, 1.0, 1.0));
    assert_eq!(
        mesh.cells.len(),
        2,
        "the point is not a cell; the repeated hex is one cell"
    );
    assert_eq!(mesh.cells[0].kind, CellKind::Hex8);
    assert_eq!(mesh.cells[0].tag, 42);
    // Tags 80 20 60 40 10 70 30 50 are ids 2 3 6 7 1 4 5 0.
    assert_eq!(mesh.cells[0].nodes, ids(&[2, 3, 6, 7, 1, 4, 5, 0]));
    assert_eq!(mesh.cells[1].kind, CellKind::Quad4);
    assert_eq!(mesh.cells[1].tag, 43);
    assert_eq!(mesh.cells[1].nodes, ids(&[2, 7, 0, 1]));

    let all: Vec<NodeId> = ids(&[0, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(mesh.node_sets["body"], all);
    assert_eq!(mesh.node_sets["physical_3_9"], all);
    assert_eq!(mesh.node_sets["left face"], ids(&[0, 1, 2, 7]));
    assert_eq!(mesh.node_sets["corner"], ids(&[5]));
    assert_eq!(mesh.node_sets["empty"], ids(&[]));
    assert_eq!(mesh.cell_sets["body"], cells(&[0]));
    assert_eq!(mesh.cell_sets["physical_3_9"], cells(&[0]));
    assert_eq!(mesh.cell_sets["left face"], cells(&[1]));
    assert_eq!(mesh.cell_sets["empty"], cells(&[]));
    assert!(!mesh.cell_sets.contains_key("corner"));
    assert_eq!(mesh.node_sets.len(), 5);
    assert_eq!(mesh.cell_sets.len(), 4);
}

#[test]
fn msh41_sparse_unordered_tags_and_physical_groups() {
    check_cube(&inline(CUBE_41).unwrap());
}

#[test]
fn msh22_sparse_unordered_tags_repeated_elements_and_physical_groups() {
    check_cube(&inline(CUBE_22).unwrap());
}

#[test]
fn crlf_line_endings_read_the_same() {
    for text in [CUBE_41, CUBE_22] {
        let crlf = text.replace('\n', "\r\n");
        assert_eq!(inline(&crlf).unwrap(), inline(text).unwrap());
    }
}

/// Little helper writing MSH binary values in either byte order.
struct Binary {
    out: Vec<u8>,
    big_endian: bool,
}

impl Binary {
    fn text(&mut self, s: &str) {
        self.out.extend_from_slice(s.as_bytes());
    }
    fn int(&mut self, v: i32) {
        self.out.extend(if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
    }
    fn size(&mut self, v: u64) {
        self.out.extend(if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
    }
    fn double(&mut self, v: f64) {
        self.out.extend(if self.big_endian {
            v.to_be_bytes()
        } else {
            v.to_le_bytes()
        });
    }
}

/// `CUBE_41` in binary MSH 4.1; `hex_type` replaces the hex's element type (5). Returns the
/// bytes and the offset of the hex element's record.
fn cube_41_binary(big_endian: bool, hex_type: i32) -> (Vec<u8>, usize) {
    let mut b = Binary {
        out: Vec::new(),
        big_endian,
    };
    b.text("$MeshFormat\n4.1 1 8\n");
    b.int(1);
    b.text("\n$EndMeshFormat\n$PhysicalNames\n4\n0 7 \"corner\"\n2 5 \"left face\"\n2 6 \"empty\"\n");
    b.text("3 1 \"body\"\n$EndPhysicalNames\n$Entities\n");
    for count in [1, 0, 1, 1] {
        b.size(count);
    }
    // point 3 at (1, 1, 1) in group 7
    b.int(3);
    (0..3).for_each(|_| b.double(1.0));
    b.size(1);
    b.int(7);
    // surface 2 in group 5, no bounding curves
    b.int(2);
    (0..6).for_each(|_| b.double(0.0));
    b.size(1);
    b.int(5);
    b.size(0);
    // volume 1 in groups 1 and 9, bounded by surface 2
    b.int(1);
    (0..6).for_each(|_| b.double(0.0));
    b.size(2);
    b.int(1);
    b.int(9);
    b.size(1);
    b.int(2);
    b.text("\n$EndEntities\n$Nodes\n");
    for v in [2, 8, 10, 80] {
        b.size(v);
    }
    // (entity dim, entity tag, node tags, coordinates)
    type Block = (i32, i32, [u64; 4], [[f64; 3]; 4]);
    let blocks: [Block; 2] = [
        (
            3,
            1,
            [50, 10, 80, 20],
            [[0., 1., 1.], [0., 0., 1.], [0., 0., 0.], [1., 0., 0.]],
        ),
        (
            2,
            2,
            [70, 30, 60, 40],
            [[1., 0., 1.], [1., 1., 1.], [1., 1., 0.], [0., 1., 0.]],
        ),
    ];
    for (dim, tag, tags, xs) in blocks {
        b.int(dim);
        b.int(tag);
        b.int(0);
        b.size(4);
        tags.iter().for_each(|&t| b.size(t));
        xs.iter().flatten().for_each(|&x| b.double(x));
    }
    b.text("\n$EndNodes\n$Elements\n");
    for v in [3, 3, 42, 44] {
        b.size(v);
    }
    b.int(0);
    b.int(3);
    b.int(15);
    b.size(1);
    b.size(44);
    b.size(30);
    b.int(3);
    b.int(1);
    b.int(hex_type);
    b.size(1);
    let hex_offset = b.out.len();
    [42, 80, 20, 60, 40, 10, 70, 30, 50].iter().for_each(|&t| b.size(t));
    b.int(2);
    b.int(2);
    b.int(3);
    b.size(1);
    [43, 80, 40, 50, 10].iter().for_each(|&t| b.size(t));
    b.text("\n$EndElements\n");
    (b.out, hex_offset)
}

#[test]
fn msh41_binary_in_both_byte_orders_reads_like_ascii() {
    for big_endian in [false, true] {
        let (bytes, _) = cube_41_binary(big_endian, 5);
        check_cube(&gmsh::parse(&bytes, Path::new("inline.msh")).unwrap());
    }
}

#[test]
fn msh41_parametric_nodes_skip_their_parameters() {
    let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1 2\n1 1 1 2\n1\n2\n0 0 0 0\n2 0 0 1\n\
                $EndNodes\n$Elements\n1 1 5 5\n1 1 1 1\n5 2 1\n$EndElements\n";
    let mesh = inline(text).unwrap();
    assert_eq!(mesh.nodes, [Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 0.0, 0.0)]);
    assert_eq!(mesh.cells[0].nodes, ids(&[1, 0]));
    assert!(
        mesh.node_sets.is_empty() && mesh.cell_sets.is_empty(),
        "no $Entities, no groups"
    );
}

// ------------------------------------------------------------------------------------ orderings

#[test]
fn permutations_from_gmsh_are_identities_of_the_right_length() {
    for gmsh_type in SUPPORTED_TYPES {
        let kind = cell_kind_from_gmsh_type(gmsh_type).unwrap();
        assert_eq!(gmsh::gmsh_type(kind), gmsh_type);
        let permutation = node_permutation_from_gmsh(kind);
        assert_eq!(permutation, (0..kind.node_count()).collect::<Vec<_>>(), "{kind:?}");
    }
    for unsupported in [0, 7, 8, 10, 12, 13, 14, 15, 18, 29, -1] {
        assert_eq!(cell_kind_from_gmsh_type(unsupported), None);
    }
}

/// Our documented corner coordinates and mid-edge tables are those of gmsh's reference
/// elements, as gmsh itself reports them (`getElementProperties`, dumped by the fixture
/// script).
#[test]
fn documented_orderings_match_gmsh_reference_elements() {
    let reference = gmsh_reference_elements();
    for gmsh_type in SUPPORTED_TYPES {
        let kind = cell_kind_from_gmsh_type(gmsh_type).unwrap();
        let nodes = &reference[&gmsh_type];
        assert_eq!(nodes.len(), kind.node_count(), "{kind:?}");
        let permutation = node_permutation_from_gmsh(kind);
        let ours: Vec<Vector3<f64>> = permutation.iter().map(|&g| Vector3::from(nodes[g])).collect();
        for (i, corner) in corners(kind).iter().enumerate() {
            assert_eq!(ours[i], Vector3::from(*corner), "{kind:?} corner {i}");
        }
        for &(m, a, b) in mid_edge_nodes(kind) {
            assert_eq!(
                ours[m],
                (ours[a] + ours[b]) / 2.0,
                "{kind:?} node {m} on edge ({a},{b})"
            );
        }
    }
    assert_eq!(reference[&15].len(), 1, "a point has one node");
}

/// One element of gmsh type `gmsh_type` whose nodes sit at gmsh's reference coordinates,
/// with sparse node tags listed in reverse order, as MSH 4.1 ASCII.
fn single_element_41(gmsh_type: i32, reference: &[[f64; 3]]) -> String {
    let n = reference.len();
    let tag = |i: usize| 1000 - 7 * i;
    let mut s = format!(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {n} {} {}\n3 1 0 {n}\n",
        tag(n - 1),
        tag(0)
    );
    for i in (0..n).rev() {
        s += &format!("{}\n", tag(i));
    }
    for i in (0..n).rev() {
        s += &format!("{} {} {}\n", reference[i][0], reference[i][1], reference[i][2]);
    }
    s += &format!("$EndNodes\n$Elements\n1 1 77 77\n3 1 {gmsh_type} 1\n77");
    for i in 0..n {
        s += &format!(" {}", tag(i));
    }
    s + "\n$EndElements\n"
}

/// Each supported type read from a file: our node `i` is where our ordering puts it, and
/// the mid-edge nodes are the midpoints of their edges.
#[test]
fn each_element_type_reads_into_our_node_ordering() {
    let reference = gmsh_reference_elements();
    for gmsh_type in SUPPORTED_TYPES {
        let kind = cell_kind_from_gmsh_type(gmsh_type).unwrap();
        let mesh = inline(&single_element_41(gmsh_type, &reference[&gmsh_type])).unwrap();
        assert_eq!(mesh.cells.len(), 1);
        let cell = &mesh.cells[0];
        assert_eq!((cell.kind, cell.tag), (kind, 77));
        let x: Vec<Point3<f64>> = cell.nodes.iter().map(|n| mesh.nodes[n.index()]).collect();
        for (i, corner) in corners(kind).iter().enumerate() {
            assert_eq!(x[i], Point3::from(*corner), "{kind:?} corner {i}");
        }
        for &(m, a, b) in mid_edge_nodes(kind) {
            assert_eq!(x[m], nalgebra::center(&x[a], &x[b]), "{kind:?} node {m}");
        }
    }
}

#[test]
fn hex20_node_8_is_the_midpoint_of_edge_0_1_and_tet10_node_9_of_edge_1_3() {
    let reference = gmsh_reference_elements();
    let hex20 = inline(&single_element_41(17, &reference[&17])).unwrap();
    let x = |mesh: &Mesh, i: usize| mesh.nodes[mesh.cells[0].nodes[i].index()];
    assert_eq!(x(&hex20, 8), nalgebra::center(&x(&hex20, 0), &x(&hex20, 1)));
    assert_eq!(x(&hex20, 8), Point3::new(0.0, -1.0, -1.0));
    let tet10 = inline(&single_element_41(11, &reference[&11])).unwrap();
    assert_eq!(x(&tet10, 9), nalgebra::center(&x(&tet10, 1), &x(&tet10, 3)));
    assert_eq!(x(&tet10, 8), nalgebra::center(&x(&tet10, 2), &x(&tet10, 3)));
    assert_eq!(x(&tet10, 9), Point3::new(0.5, 0.0, 0.5));
}

/// Every cell of every fixture: mid-edge nodes at the midpoints of their edges (the box has
/// straight edges), solid cells positively oriented.
#[test]
fn fixture_cells_have_our_node_ordering() {
    for mesh_name in MESHES {
        let mesh = read_fixture(mesh_name, "41_bin");
        for cell in &mesh.cells {
            let x: Vec<Point3<f64>> = cell.nodes.iter().map(|n| mesh.nodes[n.index()]).collect();
            for &(m, a, b) in mid_edge_nodes(cell.kind) {
                // gmsh computes the mid-edge point in floating point: a rounding or two.
                assert!(
                    (x[m] - nalgebra::center(&x[a], &x[b])).norm() <= ASCII_ROUNDING,
                    "{mesh_name}: cell {} node {m}",
                    cell.tag
                );
            }
            let det = match cell.kind {
                CellKind::Hex8 | CellKind::Hex20 => corner_det(&x, 1, 3, 4),
                CellKind::Tet4 | CellKind::Tet10 | CellKind::Wedge6 => corner_det(&x, 1, 2, 3),
                _ => continue,
            };
            assert!(det > 0.0, "{mesh_name}: cell {} is inverted (det {det})", cell.tag);
            if matches!(cell.kind, CellKind::Wedge6) {
                // Lateral edges join i and i + 3, all along x (the extrusion direction).
                for i in 0..3 {
                    let edge = x[i + 3] - x[i];
                    assert!(edge.y.abs() + edge.z.abs() <= ASCII_ROUNDING && edge.x > 0.0);
                }
            }
        }
    }
}

// ------------------------------------------------------------------------------------ errors

/// Parses `text` expecting an error; checks its Display names the file and `location`, and
/// contains each of `fragments`.
fn expect_error(text: &[u8], location: Location, fragments: &[&str]) -> MshError {
    let error = gmsh::parse(text, Path::new("inline.msh")).unwrap_err();
    let message = error.to_string();
    assert!(message.starts_with("inline.msh: "), "{message}");
    assert!(
        message.contains(&format!("{location}:")),
        "expected {location} in: {message}"
    );
    for fragment in fragments {
        assert!(message.contains(fragment), "expected '{fragment}' in: {message}");
    }
    error
}

const HEADER_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
const NODES_41: &str = "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n";

#[test]
fn missing_mesh_format_is_reported() {
    for text in [
        "",
        "  \n",
        "$Nodes\n1\n1 0 0 0\n$EndNodes\n",
        "$NOD\n1\n1 0 0 0\n$ENDNOD\n",
    ] {
        let error = gmsh::parse(text, Path::new("inline.msh")).unwrap_err();
        assert!(matches!(error, MshError::MissingMeshFormat { .. }), "{error}");
        assert!(
            error.to_string().starts_with("inline.msh: not a gmsh MSH file"),
            "{error}"
        );
    }
}

#[test]
fn unsupported_versions_are_reported() {
    let error = expect_error(
        b"$MeshFormat\n4 0 8\n$EndMeshFormat\n",
        Location::Line(2),
        &["MSH 4 ASCII"],
    );
    assert!(matches!(error, MshError::UnsupportedVersion { .. }));
    expect_error(
        b"$MeshFormat\n3.0 0 8\n$EndMeshFormat\n",
        Location::Line(2),
        &["MSH 3 ASCII", "not supported"],
    );
    let error = expect_error(
        b"\n$MeshFormat\n4.1 1 4\n",
        Location::Line(3),
        &["4.1 binary with data size 4", "not supported"],
    );
    assert!(matches!(error, MshError::UnsupportedVersion { .. }));
}

#[test]
fn truncated_sections_are_reported_with_their_section() {
    // Three nodes announced, two given: the end marker comes early.
    let text = format!("{HEADER_41}$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n$EndNodes\n");
    let error = expect_error(
        text.as_bytes(),
        Location::Line(12),
        &["$Nodes", "truncated", "x coordinate", "$EndNodes"],
    );
    assert!(matches!(error, MshError::Truncated { .. }));
    // The file stops inside $Elements.
    let text = format!("{HEADER_41}{NODES_41}$Elements\n1 1 1 1\n2 1 2 1\n1 1 2");
    let error = expect_error(
        text.as_bytes(),
        Location::Line(17),
        &["$Elements", "node tag", "end of file"],
    );
    assert!(matches!(error, MshError::Truncated { .. }));
    // A fixture cut in half: binary, so a byte offset.
    let bytes = std::fs::read(fixture_path("hex8", "41_bin")).unwrap();
    let cut = &bytes[..bytes.len() / 2];
    let error = expect_error(cut, Location::Byte(cut.len()), &["truncated", "end of file"]);
    assert!(matches!(error, MshError::Truncated { .. }));
    // A section without its end marker.
    let error = expect_error(
        b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Comments\nno end",
        Location::Line(5),
        &["$EndComments"],
    );
    assert!(matches!(error, MshError::Truncated { .. }));
}

#[test]
fn a_huge_binary_count_is_a_truncation_not_an_allocation() {
    let mut b = Binary {
        out: Vec::new(),
        big_endian: false,
    };
    b.text("$MeshFormat\n4.1 1 8\n");
    b.int(1);
    b.text("\n$EndMeshFormat\n$Nodes\n");
    for v in [1, u64::MAX / 2, 1, u64::MAX / 2] {
        b.size(v);
    }
    b.int(3);
    b.int(1);
    b.int(0);
    b.size(u64::MAX / 2);
    let error = gmsh::parse(&b.out, Path::new("inline.msh")).unwrap_err();
    assert!(matches!(error, MshError::Truncated { .. }), "{error}");
}

#[test]
fn unsupported_element_type_names_element_type_and_place() {
    // MSH 4.1 ASCII: a pyramid (7) in the second block, element 9 on line 19.
    let text =
        format!("{HEADER_41}{NODES_41}$Elements\n2 2 8 9\n2 1 2 1\n8 1 2 3\n2 1 7 1\n9 1 2 3 1 2\n$EndElements\n");
    let error = expect_error(text.as_bytes(), Location::Line(19), &["element 9", "gmsh type 7"]);
    assert!(matches!(
        error,
        MshError::UnsupportedElementType {
            element: 9,
            gmsh_type: 7,
            ..
        }
    ));
    // MSH 2.2 ASCII: a 27-node hexahedron (12), element 5 on line 11.
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n$Elements\n2\n4 15 2 0 1 1\n\
                5 12 2 0 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1\n$EndElements\n";
    expect_error(text.as_bytes(), Location::Line(11), &["element 5", "gmsh type 12"]);
    // MSH 4.1 binary: the byte offset of the element's record.
    let (bytes, offset) = cube_41_binary(false, 7);
    let error = expect_error(&bytes, Location::Byte(offset), &["element 42", "gmsh type 7"]);
    assert!(matches!(
        error,
        MshError::UnsupportedElementType {
            at: Location::Byte(_),
            ..
        }
    ));
}

#[test]
fn element_with_a_missing_node_is_reported() {
    let text = format!("{HEADER_41}{NODES_41}$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 99\n$EndElements\n");
    let error = expect_error(text.as_bytes(), Location::Line(17), &["element 1", "node 99"]);
    assert!(matches!(
        error,
        MshError::MissingNode {
            element: 1,
            node: 99,
            ..
        }
    ));
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n2 1 0 0\n$EndNodes\n\
                $Elements\n1\n3 1 2 0 1 1 4\n$EndElements\n";
    let error = expect_error(text.as_bytes(), Location::Line(11), &["element 3", "node 4"]);
    assert!(matches!(
        error,
        MshError::MissingNode {
            element: 3,
            node: 4,
            ..
        }
    ));
}

#[test]
fn malformed_numbers_are_reported_with_what_was_expected() {
    let text = format!("{HEADER_41}$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 0.5x 0\n$EndNodes\n");
    let error = expect_error(
        text.as_bytes(),
        Location::Line(8),
        &["$Nodes", "y coordinate", "'0.5x'"],
    );
    assert!(matches!(error, MshError::MalformedNumber { .. }));
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n-3\n$EndNodes\n";
    let error = expect_error(text.as_bytes(), Location::Line(5), &["number of nodes", "'-3'"]);
    assert!(matches!(error, MshError::MalformedNumber { .. }));
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 nan 0\n$EndNodes\n";
    expect_error(text.as_bytes(), Location::Line(6), &["y coordinate", "NaN"]);
    expect_error(
        b"$MeshFormat\nfour 0 8\n",
        Location::Line(2),
        &["MSH version number", "'four'"],
    );
}

#[test]
fn other_malformed_input_is_reported() {
    // Duplicate node tag.
    let text = format!("{HEADER_41}$Nodes\n1 2 1 1\n2 1 0 2\n1\n1\n0 0 0\n1 0 0\n$EndNodes\n");
    let error = expect_error(text.as_bytes(), Location::Line(8), &["node 1 is defined twice"]);
    assert!(matches!(error, MshError::DuplicateNode { node: 1, .. }));
    // Element tag reused for different nodes.
    let text = format!("{HEADER_41}{NODES_41}$Elements\n1 2 1 1\n2 1 2 2\n1 1 2 3\n1 3 2 1\n$EndElements\n");
    let error = expect_error(text.as_bytes(), Location::Line(18), &["element 1 is defined twice"]);
    assert!(matches!(error, MshError::DuplicateElement { element: 1, .. }));
    // Too many records: the end marker is not where the count says.
    let text = format!("{HEADER_41}$Nodes\n1 1 1 1\n2 1 0 1\n1\n0 0 0\n1 0 0\n$EndNodes\n");
    let error = expect_error(text.as_bytes(), Location::Line(9), &["expected $EndNodes", "'1'"]);
    assert!(matches!(error, MshError::Malformed { .. }));
    // A physical name without quotes.
    let text = format!("{HEADER_41}$PhysicalNames\n1\n2 1 clamp\n$EndPhysicalNames\n");
    let error = expect_error(
        text.as_bytes(),
        Location::Line(6),
        &["$PhysicalNames", "quoted name", "'clamp'"],
    );
    assert!(matches!(error, MshError::Malformed { .. }));
    // A bad endianness marker.
    let error = expect_error(
        b"$MeshFormat\n4.1 1 8\n\x02\0\0\0\n$EndMeshFormat\n",
        Location::Byte(20),
        &["endianness"],
    );
    assert!(matches!(error, MshError::Malformed { .. }));
    // A partitioned mesh.
    let text = format!("{HEADER_41}$PartitionedEntities\n2\n$EndPartitionedEntities\n");
    let error = expect_error(text.as_bytes(), Location::Line(4), &["partitioned mesh"]);
    assert!(matches!(error, MshError::UnsupportedFeature { .. }));
}

// ------------------------------------------------------------------------------------ no panic

/// Fixed seeds, so failures reproduce. `FLEXMBS_FUZZ_SCALE=100` multiplies the number of
/// random and mutated inputs to search harder (as PROPTEST_CASES would).
fn fuzz_scale() -> usize {
    fe_model::fuzz::budget(1)
}
const RANDOM_INPUTS: usize = 3000;
const MUTATIONS_PER_FIXTURE: usize = 300;

#[test]
fn random_bytes_never_panic() {
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15);
    // Plain noise, and noise behind each valid header so that the section readers see it.
    let headers: [&[u8]; 5] = [
        b"",
        b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n",
        b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n$EndMeshFormat\n$Nodes\n",
        b"$MeshFormat\n4.1 1 8\n\x01\0\0\0\n$EndMeshFormat\n$Elements\n",
        b"$MeshFormat\n2.2 1 8\n\x01\0\0\0\n$EndMeshFormat\n$Elements\n1\n",
    ];
    // Noise drawn from a small alphabet reaches deeper into ASCII readers than uniform bytes.
    const ALPHABET: &[u8] = b"0123456789 \n-.e$\"";
    for case in 0..RANDOM_INPUTS * fuzz_scale() {
        let header = headers[case % headers.len()];
        let len = rng.below(600);
        let ascii = rng.below(2) == 0;
        let mut bytes = header.to_vec();
        bytes.extend((0..len).map(|_| {
            let r = rng.next_u64();
            if ascii {
                ALPHABET[(r % ALPHABET.len() as u64) as usize]
            } else {
                r as u8
            }
        }));
        parse_without_panic(&bytes, &|| format!("random case {case}: {bytes:?}"));
    }
}

#[test]
fn every_prefix_of_every_fixture_is_an_error_or_a_mesh_never_a_panic() {
    for mesh_name in MESHES {
        for encoding in ENCODINGS {
            let bytes = std::fs::read(fixture_path(mesh_name, encoding)).unwrap();
            for len in 0..bytes.len() {
                parse_without_panic(&bytes[..len], &|| format!("{mesh_name}_{encoding} cut at {len}"));
            }
        }
    }
}

#[test]
fn mutated_fixtures_never_panic() {
    let mut rng = Rng::new(0x2545_f491_4f6c_dd1d);
    // Replacement bytes that change meaning: digits, signs, separators, markers, large bytes.
    const INTERESTING: &[u8] = b"0123456789-+.e $\n\"\xff\x7f\x80\0";
    for mesh_name in MESHES {
        for encoding in ENCODINGS {
            let original = std::fs::read(fixture_path(mesh_name, encoding)).unwrap();
            for case in 0..MUTATIONS_PER_FIXTURE * fuzz_scale() {
                let mut bytes = original.clone();
                for _ in 0..1 + rng.below(4) {
                    let at = rng.below(bytes.len());
                    match rng.below(4) {
                        0 => bytes[at] = INTERESTING[rng.below(INTERESTING.len())],
                        1 => bytes[at] = rng.next_u64() as u8,
                        2 => {
                            bytes.remove(at);
                        }
                        _ => bytes.insert(at, INTERESTING[rng.below(INTERESTING.len())]),
                    }
                    if bytes.is_empty() {
                        break;
                    }
                }
                parse_without_panic(&bytes, &|| format!("{mesh_name}_{encoding} mutation {case}"));
            }
        }
    }
}

/// The shared fuzz mutator (`fe_model::fuzz`: numbers replaced by extreme ones, lines moved,
/// files cut) over every fixture, a fixed budget per fixture.
#[test]
fn fuzz_mutants_of_every_fixture_never_panic() {
    let mut m = fe_model::fuzz::Mutator::new(0x6d73_6866_757a_7a01);
    for mesh_name in MESHES {
        for encoding in ENCODINGS {
            let original = std::fs::read(fixture_path(mesh_name, encoding)).unwrap();
            for case in 0..fe_model::fuzz::budget(150) {
                let bytes = m.mutate(&original);
                parse_without_panic(&bytes, &|| format!("{mesh_name}_{encoding} fuzz mutant {case}"));
            }
        }
    }
}

/// The totals of the MSH 4.1 `$Nodes` and `$Elements` headers (number of records, smallest
/// and largest tag) are checked against the blocks; a mismatch names the header's line and
/// the two numbers, in ASCII and in binary files.
#[test]
fn msh41_header_totals_must_match_the_blocks() {
    // NODES_41 holds nodes 1, 2, 3 (header line 5: `1 3 1 3`).
    let cases = [
        ("$Nodes\n1 4 1 3\n", "the number of nodes = 4, but the blocks hold 3"),
        ("$Nodes\n1 3 0 3\n", "the smallest node tag = 0, but the blocks hold 1"),
        ("$Nodes\n1 3 1 7\n", "the largest node tag = 7, but the blocks hold 3"),
    ];
    for (header, fragment) in cases {
        let text = format!("{HEADER_41}{}", NODES_41.replacen("$Nodes\n1 3 1 3\n", header, 1));
        let error = expect_error(text.as_bytes(), Location::Line(5), &["$Nodes", fragment]);
        assert!(matches!(error, MshError::HeaderMismatch { .. }), "{error}");
    }
    let elements = |header: &str| format!("{HEADER_41}{NODES_41}$Elements\n{header}\n2 1 2 1\n1 1 2 3\n$EndElements\n");
    inline(&elements("1 1 1 1")).unwrap();
    for (header, fragment) in [
        ("1 2 1 1", "the number of elements = 2, but the blocks hold 1"),
        ("1 1 1 5", "the largest element tag = 5, but the blocks hold 1"),
    ] {
        let error = expect_error(
            elements(header).as_bytes(),
            Location::Line(15),
            &["$Elements", fragment],
        );
        assert!(matches!(error, MshError::HeaderMismatch { .. }), "{error}");
    }
    // Binary: the number of nodes after the number of blocks, 8 bytes each, located by byte.
    let mut bytes = std::fs::read(fixture_path("hex8", "41_bin")).unwrap();
    let at = bytes.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7 + 8;
    let total = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    bytes[at..at + 8].copy_from_slice(&(total + 1).to_le_bytes());
    let error = expect_error(&bytes, Location::Byte(at), &["the number of nodes"]);
    assert!(matches!(error, MshError::HeaderMismatch { .. }), "{error}");
}
