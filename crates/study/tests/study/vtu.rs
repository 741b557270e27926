//! Our node orders (gmsh's) mapped into VTK's. Each test takes the reference nodes of one
//! element kind from `fe_model`, permutes them with `study::output::vtu::vtk_cell`, and compares
//! them with VTK's definition of the cell: the parametric coordinates of its cell class
//! (`GetParametricCoords` of vtkHexahedron, vtkQuadraticHexahedron, vtkTetra,
//! vtkQuadraticTetra, vtkWedge in VTK 9.7), and for the wedge also its documented orientation
//! (`study::output::vtu` module docs).

use fe_model::{CellKind, NodeId, SolidKind};
use study::output::vtu::{vtk_cell, vtu_text, PointField, VtuMesh};

/// VTK's hexahedron corners in [0, 1]^3.
const VTK_HEX: [[f64; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
];

/// vtkQuadraticHexahedron: the corners, then the mid-edge nodes of the bottom face, the top
/// face and the vertical edges.
const VTK_HEX20: [[f64; 3]; 20] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
    [0.5, 0.0, 0.0],
    [1.0, 0.5, 0.0],
    [0.5, 1.0, 0.0],
    [0.0, 0.5, 0.0],
    [0.5, 0.0, 1.0],
    [1.0, 0.5, 1.0],
    [0.5, 1.0, 1.0],
    [0.0, 0.5, 1.0],
    [0.0, 0.0, 0.5],
    [1.0, 0.0, 0.5],
    [1.0, 1.0, 0.5],
    [0.0, 1.0, 0.5],
];

/// vtkQuadraticTetra (the first four are vtkTetra's).
const VTK_TET10: [[f64; 3]; 10] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5],
    [0.5, 0.0, 0.5],
    [0.0, 0.5, 0.5],
];

/// Our reference nodes of `kind` in VTK order, mapped by `map`.
fn permuted(kind: SolidKind, map: impl Fn([f64; 3]) -> [f64; 3]) -> (u8, Vec<[f64; 3]>) {
    let (vtk, perm) = vtk_cell(kind.cell_kind());
    let reference = kind.reference_nodes();
    assert_eq!(perm.len(), reference.len());
    let mut sorted = perm.to_vec();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        (0..perm.len()).collect::<Vec<_>>(),
        "{kind:?}: not a permutation"
    );
    (vtk, perm.iter().map(|&k| map(reference[k])).collect())
}

fn assert_same(kind: SolidKind, ours: &[[f64; 3]], vtk: &[[f64; 3]]) {
    assert_eq!(ours.len(), vtk.len());
    for (k, (a, b)) in ours.iter().zip(vtk).enumerate() {
        let d: f64 = (0..3).map(|i| (a[i] - b[i]).abs()).sum();
        assert!(d < 1e-12, "{kind:?}: VTK node {k} is at {a:?}, VTK puts it at {b:?}");
    }
}

/// Our hexahedra live on [-1, 1]^3, VTK's on [0, 1]^3.
fn unit(x: [f64; 3]) -> [f64; 3] {
    x.map(|c| 0.5 * (c + 1.0))
}

#[test]
fn vtk_line_is_type_3_in_our_order() {
    assert_eq!(vtk_cell(CellKind::Line2), (3, &[0usize, 1][..]));
}

#[test]
fn vtk_tetra_is_type_10_in_our_order() {
    let (vtk, ours) = permuted(SolidKind::Tet4, |x| x);
    assert_eq!(vtk, 10);
    assert_same(SolidKind::Tet4, &ours, &VTK_TET10[..4]);
}

#[test]
fn vtk_hexahedron_is_type_12_in_our_order() {
    let (vtk, ours) = permuted(SolidKind::Hex8, unit);
    assert_eq!(vtk, 12);
    assert_same(SolidKind::Hex8, &ours, &VTK_HEX);
}

#[test]
fn vtk_quadratic_tetra_is_type_24_with_nodes_8_and_9_swapped() {
    let (vtk, ours) = permuted(SolidKind::Tet10, |x| x);
    assert_eq!(vtk, 24);
    assert_same(SolidKind::Tet10, &ours, &VTK_TET10);
    assert_eq!(&vtk_cell(CellKind::Tet10).1[8..], &[9, 8]);
}

#[test]
fn vtk_quadratic_hexahedron_is_type_25_with_edges_reordered() {
    let (vtk, ours) = permuted(SolidKind::Hex20, unit);
    assert_eq!(vtk, 25);
    assert_same(SolidKind::Hex20, &ours, &VTK_HEX20);
}

/// vtkWedge: two triangles, 3, 4, 5 above 0, 1, 2; its documentation (VTK 9.7): "(0, 2, 1)
/// is the base of the wedge which, using the right hand rule, forms a triangle whose normal
/// points away from the triangular face (3, 4, 5)".
const VTK_WEDGE: [[f64; 3]; 6] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
];

#[test]
fn vtk_wedge_is_type_13_in_our_order() {
    let (vtk, p) = permuted(SolidKind::Wedge6, |x| [x[0], x[1], 0.5 * (x[2] + 1.0)]);
    assert_eq!(vtk, 13);
    assert_same(SolidKind::Wedge6, &p, &VTK_WEDGE);
    // The documented orientation, checked on the geometry itself.
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let (e1, e2) = (sub(p[2], p[0]), sub(p[1], p[0]));
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let top = [0, 1, 2].map(|i| (p[3][i] + p[4][i] + p[5][i]) / 3.0);
    let to_top = sub(top, p[0]);
    let dot: f64 = (0..3).map(|i| n[i] * to_top[i]).sum();
    assert!(dot < 0.0, "the normal of (0, 2, 1), {n:?}, points towards the top");
}

/// A written file: one hex20 brick plus an interface node with two spider legs.
#[test]
fn vtu_file_lists_points_cells_offsets_and_types() {
    let mesh = fe_model::box_mesh(CellKind::Hex20, [1.0, 2.0, 3.0], [1, 1, 1]).unwrap();
    let model = fe_model::solid_model(
        mesh,
        fe_model::IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap(),
        fe_model::MassKind::Consistent,
    )
    .unwrap();
    let n = model.node_count();
    let grid = VtuMesh::from_model(&model, &[(NodeId(0), vec![NodeId(1), NodeId(2)])]);
    let values: Vec<f64> = (0..3 * n).map(|i| i as f64).collect();
    let text = vtu_text(
        &grid,
        &[PointField {
            name: "displacement",
            components: 3,
            values: &values,
        }],
    );
    assert!(
        text.contains(&format!("NumberOfPoints=\"{n}\" NumberOfCells=\"4\"")),
        "{text}"
    );
    let array = |name: &str| -> Vec<i64> {
        let start = text.find(&format!("Name=\"{name}\"")).unwrap();
        let body = &text[start..];
        let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
        body.split_whitespace().map(|s| s.parse().unwrap()).collect()
    };
    assert_eq!(array("types"), [25, 1, 3, 3]);
    assert_eq!(array("offsets"), [20, 21, 23, 25]);
    assert_eq!(array("kind"), [0, 2, 1, 1]);
    let connectivity = array("connectivity");
    let hex = &model.elements[0].nodes();
    let expected: Vec<i64> = vtk_cell(CellKind::Hex20)
        .1
        .iter()
        .map(|&k| hex[k].index() as i64)
        .collect();
    assert_eq!(&connectivity[..20], &expected[..]);
    assert_eq!(&connectivity[20..], &[0, 0, 1, 0, 2]);
    assert!(text.contains("Name=\"displacement\" NumberOfComponents=\"3\""));
}
