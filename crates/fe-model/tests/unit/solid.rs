//! Solid elements (tet4, tet10, hex8, hex20, wedge6), box meshes and solid models, in the
//! three tiers:
//! - element level: partition of unity, $N_i(\boldsymbol\xi_j) = \delta_{ij}$, derivatives
//!   against central differences, symmetry, exactly six rigid modes on a distorted element,
//!   $\mathbf K_e$ against an independent $\mathbf B^T \mathbf D \mathbf B$, mass sums to
//!   $\rho V$, inverted elements reported by index;
//! - patch test on distorted multi-element patches; box meshes (counts, sets, volume,
//!   conformity, six rigid modes of a free body);
//! - structure level: slender cantilever against Timoshenko beam theory (tip deflection and
//!   the first bending frequencies) with hex20 and tet10, and the locking of tet4.

use fe_model::box_mesh::{box_mesh, solid_model, solid_model_with_materials};
use fe_model::element::solid::{self, elasticity_matrix, strain_displacement, SolidKind};
use fe_model::element::{Element, Solid};
use fe_model::generate::straight_beam;
use fe_model::interface::{add_interface_on_set, SpiderKind};
use fe_model::{
    assemble, solve_static, BeamProperties, BeamSection, BeamTheory, CellKind, DofMap, DofMask, ElementError, FeError,
    FeModel, IsotropicMaterial, MassKind, Mesh, NodalLoad, NodeId, SystemPattern,
};
use nalgebra::{DMatrix, DVector, Matrix3, Point3, Vector3};

/// Steel-like material with a non-zero Poisson's ratio, for element-level checks.
pub fn material() -> IsotropicMaterial {
    IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap()
}

/// All five solid cell kinds.
pub const KINDS: [CellKind; 5] = [
    CellKind::Tet4,
    CellKind::Tet10,
    CellKind::Hex8,
    CellKind::Hex20,
    CellKind::Wedge6,
];

fn kind_of(c: CellKind) -> SolidKind {
    SolidKind::from_cell_kind(c).unwrap()
}

/// Number of corner (vertex) nodes of a kind; the rest are edge nodes.
fn corner_count(kind: SolidKind) -> usize {
    match kind {
        SolidKind::Tet10 => 4,
        SolidKind::Hex20 => 8,
        k => k.node_count(),
    }
}

/// For each edge node of `kind`: (node, corner a, corner b) with the node at the midpoint of
/// a and b in reference coordinates.
fn edge_pairs(kind: SolidKind) -> Vec<(usize, usize, usize)> {
    let r = kind.reference_nodes();
    let nc = corner_count(kind);
    (nc..r.len())
        .map(|e| {
            for a in 0..nc {
                for b in a + 1..nc {
                    if (0..3).all(|k| (0.5 * (r[a][k] + r[b][k]) - r[e][k]).abs() < 1e-15) {
                        return (e, a, b);
                    }
                }
            }
            panic!("{kind:?} node {e} is not an edge midpoint")
        })
        .collect()
}

/// Shape functions at `xi`.
fn shape(kind: SolidKind, xi: &[f64; 3]) -> (Vec<f64>, Vec<[f64; 3]>) {
    let n = kind.node_count();
    let (mut N, mut dN) = (vec![0.0; n], vec![[0.0; 3]; n]);
    kind.shape_functions(xi, &mut N, &mut dN);
    (N, dN)
}

/// A few points inside the reference element (and on its boundary).
fn sample_points(kind: SolidKind) -> Vec<[f64; 3]> {
    match kind {
        SolidKind::Tet4 | SolidKind::Tet10 => {
            vec![
                [0.1, 0.2, 0.3],
                [0.25, 0.25, 0.25],
                [0.6, 0.1, 0.05],
                [0.0, 0.0, 0.0],
                [0.3, 0.7, 0.0],
            ]
        }
        SolidKind::Hex8 | SolidKind::Hex20 => {
            vec![
                [0.1, -0.3, 0.7],
                [0.0, 0.0, 0.0],
                [-0.9, 0.5, -0.2],
                [1.0, 1.0, -1.0],
                [0.33, 0.77, 1.0],
            ]
        }
        SolidKind::Wedge6 => vec![
            [0.1, 0.2, 0.3],
            [1.0 / 3.0, 1.0 / 3.0, 0.0],
            [0.6, 0.1, -0.8],
            [0.0, 1.0, 1.0],
        ],
    }
}

/// The reference element mapped by `x = A xi + c`, plus a non-affine node perturbation of
/// relative size `bump` (curved edges for the quadratic kinds).
pub fn element_nodes(kind: SolidKind, bump: f64) -> Vec<Point3<f64>> {
    let A = Matrix3::new(2.0, 0.3, 0.1, 0.2, 1.5, -0.2, 0.1, 0.25, 1.2);
    let c = Vector3::new(0.4, -1.0, 2.0);
    kind.reference_nodes()
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let f = i as f64;
            let d = Vector3::new((1.3 * f + 0.7).sin(), (2.1 * f).cos(), (0.7 * f + 1.1).sin());
            Point3::from(A * Vector3::new(r[0], r[1], r[2]) + c + bump * d)
        })
        .collect()
}

/// Reference volume of a kind.
fn reference_volume(kind: SolidKind) -> f64 {
    match kind {
        SolidKind::Tet4 | SolidKind::Tet10 => 1.0 / 6.0,
        SolidKind::Hex8 | SolidKind::Hex20 => 8.0,
        SolidKind::Wedge6 => 1.0,
    }
}

/// Dense copy of a faer sparse matrix.
pub fn dense(m: &faer::sparse::SparseColMat<usize, f64>) -> DMatrix<f64> {
    let d = m.to_dense();
    DMatrix::from_fn(d.nrows(), d.ncols(), |i, j| d[(i, j)])
}

/// Ascending eigenvalues of a symmetric matrix.
fn eigenvalues(K: &DMatrix<f64>) -> Vec<f64> {
    let mut ev: Vec<f64> = nalgebra::SymmetricEigen::new(K.clone())
        .eigenvalues
        .iter()
        .copied()
        .collect();
    ev.sort_by(f64::total_cmp);
    ev
}

/// Number of eigenvalues of `K` at round-off level, and the smallest one above it, relative
/// to the largest.
fn null_space(K: &DMatrix<f64>) -> (usize, f64) {
    let ev = eigenvalues(K);
    let max = ev.last().unwrap().abs();
    // Round-off of an eigenvalue of a symmetric matrix is ~ n eps ||K||; 1e-10 ||K|| is far
    // above that for n <= 3000 and far below the softest deformation mode of any element here
    // (>= 1e-6 ||K|| for the aspect ratios used).
    let zero = 1e-10 * max;
    let count = ev.iter().filter(|v| v.abs() <= zero).count();
    let next = ev.iter().find(|v| v.abs() > zero).copied().unwrap_or(0.0) / max;
    (count, next)
}

/// The `n` lowest frequencies [Hz] of `model` (dense, shift-inverted: `fe_model::modal_dense`).
pub fn lowest_frequencies_hz(model: &FeModel, n: usize) -> Vec<f64> {
    fe_model::modal_dense(model, n).unwrap().frequencies_hz()
}

// ---------------------------------------------------------------- element level

#[test]
fn shape_functions_partition_unity_and_reproduce_linear_fields() {
    for kind in SolidKind::ALL {
        let r = kind.reference_nodes();
        for xi in sample_points(kind) {
            let (N, dN) = shape(kind, &xi);
            // Round-off: sums of <= 20 terms of size <= ~1.
            let tol = 32.0 * f64::EPSILON;
            assert!(
                (N.iter().sum::<f64>() - 1.0).abs() <= tol,
                "{kind:?}: sum N = {}",
                N.iter().sum::<f64>()
            );
            for k in 0..3 {
                let s: f64 = dN.iter().map(|d| d[k]).sum();
                assert!(s.abs() <= tol, "{kind:?}: sum dN/dxi_{k} = {s}");
                // Isoparametric completeness: sum N_a xi_a = xi and sum dN_a xi_a = e_k.
                let x: f64 = N.iter().zip(r).map(|(n, r)| n * r[k]).sum();
                assert!((x - xi[k]).abs() <= tol, "{kind:?}: sum N xi_{k} = {x} at {xi:?}");
                for j in 0..3 {
                    let g: f64 = dN.iter().zip(r).map(|(d, r)| d[j] * r[k]).sum();
                    let e = if j == k { 1.0 } else { 0.0 };
                    assert!((g - e).abs() <= tol, "{kind:?}: d(sum N xi_{k})/dxi_{j} = {g}");
                }
            }
        }
    }
}

#[test]
fn shape_functions_are_nodal() {
    for kind in SolidKind::ALL {
        for (j, xj) in kind.reference_nodes().iter().enumerate() {
            let (N, _) = shape(kind, xj);
            for (i, n) in N.iter().enumerate() {
                let delta = if i == j { 1.0 } else { 0.0 };
                // Round-off of a product of <= 4 factors at exact nodal coordinates.
                assert!((n - delta).abs() <= 8.0 * f64::EPSILON, "{kind:?}: N_{i}(xi_{j}) = {n}");
            }
        }
    }
}

#[test]
fn shape_derivatives_match_central_differences() {
    let h = 1e-5;
    for kind in SolidKind::ALL {
        for xi in sample_points(kind) {
            let (_, dN) = shape(kind, &xi);
            for k in 0..3 {
                let (mut p, mut m) = (xi, xi);
                p[k] += h;
                m[k] -= h;
                let (Np, _) = shape(kind, &p);
                let (Nm, _) = shape(kind, &m);
                for a in 0..kind.node_count() {
                    let fd = (Np[a] - Nm[a]) / (2.0 * h);
                    // Truncation O(h^2 |N'''|) ~ 1e-10 (cubic terms have O(1) coefficients)
                    // plus round-off eps / h ~ 1e-11.
                    assert!(
                        (fd - dN[a][k]).abs() <= 1e-9,
                        "{kind:?}: dN_{a}/dxi_{k} = {} vs fd {fd}",
                        dN[a][k]
                    );
                }
            }
        }
    }
}

#[test]
fn faces_are_boundary_faces_with_edge_nodes_at_midpoints() {
    for kind in SolidKind::ALL {
        let r = kind.reference_nodes();
        let pairs = edge_pairs(kind);
        let mut seen = std::collections::BTreeSet::new();
        for face in kind.faces() {
            let corners = match face.len() {
                3 | 6 => 3,
                4 | 8 => 4,
                n => panic!("{kind:?}: face with {n} nodes"),
            };
            // Edge node i of the face lies between face corners i and i + 1.
            for i in corners..face.len() {
                let (a, b) = (face[i - corners], face[(i - corners + 1) % corners]);
                let e = face[i];
                assert!(
                    pairs
                        .iter()
                        .any(|&(n, p, q)| n == e && ((p, q) == (a, b) || (p, q) == (b, a))),
                    "{kind:?}: face {face:?} node {e} is not on edge ({a}, {b})"
                );
            }
            // Outward orientation: (x1 - x0) x (x2 - x0) points away from the centroid.
            let c: Vec<f64> = (0..3)
                .map(|k| r.iter().map(|x| x[k]).sum::<f64>() / r.len() as f64)
                .collect();
            let p = |i: usize| Vector3::new(r[face[i]][0], r[face[i]][1], r[face[i]][2]);
            let n = (p(1) - p(0)).cross(&(p(2) - p(0)));
            assert!(
                n.dot(&(p(0) - Vector3::new(c[0], c[1], c[2]))) > 0.0,
                "{kind:?}: face {face:?} points inwards"
            );
            let mut key = face.to_vec();
            key.sort_unstable();
            assert!(seen.insert(key), "{kind:?}: face {face:?} listed twice");
        }
    }
}

#[test]
fn stiffness_is_symmetric_with_exactly_six_rigid_modes_on_a_distorted_element() {
    for kind in SolidKind::ALL {
        let X = element_nodes(kind, 0.08);
        let K = solid::stiffness(kind, 0, &X, &material()).unwrap();
        let max = K.amax();
        assert_eq!(K, K.transpose(), "{kind:?}: K_e is not symmetric");
        let (zeros, next) = null_space(&K);
        assert_eq!(
            zeros, 6,
            "{kind:?}: {zeros} zero eigenvalues, expected the 6 rigid modes"
        );
        assert!(
            next > 1e-8,
            "{kind:?}: softest deformation mode {next:.2e} of the largest"
        );
        // The rigid modes themselves are in the null space to round-off (n eps ||K|| |u|).
        for mode in 0..6 {
            let mut u = DVector::zeros(3 * X.len());
            for (a, x) in X.iter().enumerate() {
                let v = if mode < 3 {
                    Vector3::ith(mode, 1.0)
                } else {
                    Vector3::ith(mode - 3, 1.0).cross(&x.coords)
                };
                u.fixed_rows_mut::<3>(3 * a).copy_from(&v);
            }
            let f = &K * &u;
            let tol = 64.0 * f64::EPSILON * max * u.amax() * (X.len() as f64);
            assert!(
                f.amax() <= tol,
                "{kind:?}: rigid mode {mode} gives force {:.2e} > {tol:.2e}",
                f.amax()
            );
        }
    }
}

/// The nodal-block form of the kernel (see `solid::stiffness`) equals the textbook
/// $\sum_q w_q \det J_q B_q^T D B_q$ built from `strain_displacement` and `elasticity_matrix`.
#[test]
fn stiffness_equals_BtDB() {
    let m = material();
    let D = elasticity_matrix(&m);
    for kind in SolidKind::ALL {
        let X = element_nodes(kind, 0.08);
        let K = solid::stiffness(kind, 0, &X, &m).unwrap();
        let rule = kind.stiffness_rule();
        let mut K_ref = DMatrix::zeros(K.nrows(), K.ncols());
        for (q, (xi, w)) in rule.points.iter().zip(&rule.weights).enumerate() {
            let p = solid::point_values(kind, 0, q, &X, xi).unwrap();
            let B = strain_displacement(&p.g);
            K_ref += (w * p.det_J) * B.transpose() * DMatrix::from_iterator(6, 6, D.iter().copied()) * &B;
        }
        // Round-off: the two forms sum the same products in a different order.
        let tol = 1e-13 * K.amax();
        assert!(
            (&K - &K_ref).amax() <= tol,
            "{kind:?}: |K - B^T D B| = {:.2e}",
            (&K - &K_ref).amax()
        );
    }
}

#[test]
fn mass_sums_to_rho_V_consistent_and_lumped() {
    let m = material();
    for kind in SolidKind::ALL {
        // Affine map: V = det(A) V_ref exactly.
        let X = element_nodes(kind, 0.0);
        let A = Matrix3::new(2.0, 0.3, 0.1, 0.2, 1.5, -0.2, 0.1, 0.25, 1.2);
        let V = A.determinant() * reference_volume(kind);
        for mass in [MassKind::Consistent, MassKind::Lumped] {
            let M = solid::solid_matrices(kind, 3, &X, &m, mass).unwrap().M_e;
            // Each direction carries the whole mass: the sum over all dofs is 3 rho V.
            let total: f64 = M.iter().sum();
            // Round-off of summing (3n)^2 entries.
            let tol = 1e-13 * 3.0 * m.rho() * V;
            assert!(
                (total - 3.0 * m.rho() * V).abs() <= tol,
                "{kind:?} {mass:?}: {total} vs {}",
                3.0 * m.rho() * V
            );
            assert_eq!(M, M.transpose(), "{kind:?} {mass:?}: M_e is not symmetric");
            if mass == MassKind::Lumped {
                assert!(
                    (0..M.nrows()).all(|i| M[(i, i)] > 0.0),
                    "{kind:?}: a non-positive lumped mass"
                );
                assert_eq!(
                    M.iter().filter(|v| **v != 0.0).count(),
                    M.nrows(),
                    "{kind:?}: lumped mass not diagonal"
                );
            } else {
                // Consistent mass is positive definite.
                assert!(
                    M.clone().cholesky().is_some(),
                    "{kind:?}: consistent mass not positive definite"
                );
            }
        }
        // The mass rule's volume on a distorted element agrees with the element's own volume.
        let Xd = element_nodes(kind, 0.08);
        let Vd = solid::volume(kind, 0, &Xd).unwrap();
        let Md: f64 = solid::scalar_mass(kind, 0, &Xd, 1.0, MassKind::Consistent)
            .unwrap()
            .iter()
            .sum();
        assert!(
            (Md - Vd).abs() <= 1e-13 * Vd,
            "{kind:?}: sum of unit-density mass {Md} vs volume {Vd}"
        );
    }
}

#[test]
fn inverted_or_collapsed_element_is_reported_by_index() {
    for kind in SolidKind::ALL {
        // Mirror x -> -x: the same shape, inverted.
        let X: Vec<Point3<f64>> = element_nodes(kind, 0.0)
            .iter()
            .map(|p| Point3::new(-p.x, p.y, p.z))
            .collect();
        let err = solid::solid_matrices(kind, 7, &X, &material(), MassKind::Consistent).unwrap_err();
        assert!(
            matches!(err, ElementError::NonPositiveJacobian { element: 7, point: 0, det_j } if det_j < 0.0),
            "{kind:?}: {err:?}"
        );
        let msg = err.to_string();
        assert!(msg.contains("element 7") && msg.contains("quadrature point 0"), "{msg}");
        // Flattened into the plane z = 0: zero volume.
        let X: Vec<Point3<f64>> = element_nodes(kind, 0.0)
            .iter()
            .map(|p| Point3::new(p.x, p.y, 0.0))
            .collect();
        let err = solid::stiffness(kind, 2, &X, &material()).unwrap_err();
        assert!(
            matches!(err, ElementError::NonPositiveJacobian { element: 2, .. }),
            "{kind:?}: {err:?}"
        );
    }
    // Through the Element dispatch, with the wrong node count.
    let e = Element::Hex8(Solid {
        nodes: (0..8).map(NodeId).collect(),
        material: fe_model::MaterialId(0),
        mass: MassKind::Consistent,
    });
    let props = fe_model::Properties {
        materials: &[material()],
        sections: &[],
    };
    let err = e
        .local_matrices(4, &element_nodes(SolidKind::Hex8, 0.0)[..7], &props)
        .unwrap_err();
    assert!(
        matches!(
            err,
            ElementError::WrongNodeCount {
                element: 4,
                expected: 8,
                got: 7,
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(e.node_dofs(), &[0, 1, 2]);
    assert_eq!(e.kind_name(), "hex8");
}

// ---------------------------------------------------------------- patch test and meshes

/// Moves every interior corner node of a box mesh by a deterministic offset of up to
/// `fraction` of the cell size, then puts edge nodes back at the midpoints of their corners
/// (straight edges, so that the isoparametric map stays one the rules integrate well).
pub fn distort_interior(mesh: &mut Mesh, fraction: f64, h: f64) {
    let boundary: std::collections::BTreeSet<NodeId> = mesh.node_sets.values().flatten().copied().collect();
    let mut corner = vec![false; mesh.nodes.len()];
    for cell in &mesh.cells {
        let kind = kind_of(cell.kind);
        for &n in &cell.nodes[..corner_count(kind)] {
            corner[n.index()] = true;
        }
    }
    for (i, x) in mesh.nodes.iter_mut().enumerate() {
        if corner[i] && !boundary.contains(&NodeId(i as u32)) {
            let f = i as f64;
            *x += fraction * h * Vector3::new((1.7 * f).sin(), (2.3 * f + 0.5).cos(), (0.9 * f + 0.2).sin());
        }
    }
    let cells = mesh.cells.clone();
    for cell in &cells {
        let kind = kind_of(cell.kind);
        for (e, a, b) in edge_pairs(kind) {
            let mid = nalgebra::center(&mesh.nodes[cell.nodes[a].index()], &mesh.nodes[cell.nodes[b].index()]);
            mesh.nodes[cell.nodes[e].index()] = mid;
        }
    }
}

/// Assembled free-free stiffness (no supports) as a dense matrix, with the dof of each
/// (node, direction).
fn free_stiffness(model: &FeModel) -> (DMatrix<f64>, DofMap) {
    let dofs = DofMap::new(model).unwrap();
    let pattern = SystemPattern::new(model, &dofs);
    let a = assemble(model, &pattern).unwrap();
    (dense(&a.K), dofs)
}

/// Patch test (Irons; Zienkiewicz, Taylor & Zhu, 7th ed., ch. 9): boundary nodes of a
/// distorted multi-element patch get the values of a linear field, the interior nodes are
/// solved for, and must take the linear field's values exactly (to round-off).
#[test]
fn patch_test_reproduces_a_linear_field_on_distorted_patches() {
    let A = Matrix3::new(1.0, 2.0, -3.0, 4.0, -5.0, 6.0, 7.0, 8.0, 10.0) * 1e-3;
    let b = Vector3::new(1e-3, -2e-3, 3e-3);
    for cell_kind in KINDS {
        let divisions = if matches!(cell_kind, CellKind::Tet10 | CellKind::Hex20) {
            [2, 2, 2]
        } else {
            [3, 3, 3]
        };
        let mut mesh = box_mesh(cell_kind, [1.0, 1.2, 0.9], divisions).unwrap();
        distort_interior(&mut mesh, 0.2, 0.3);
        let boundary: std::collections::BTreeSet<NodeId> = mesh.node_sets.values().flatten().copied().collect();
        let model = solid_model(mesh, material(), MassKind::Consistent).unwrap();
        let (K, dofs) = free_stiffness(&model);
        let exact = |n: NodeId| A * model.mesh.nodes[n.index()].coords + b;
        let (mut interior, mut fixed) = (vec![], vec![]);
        for n in 0..model.node_count() {
            let node = NodeId(n as u32);
            for k in 0..3 {
                let d = dofs.free_dof(node, k).unwrap().index();
                if boundary.contains(&node) {
                    fixed.push((d, exact(node)[k]));
                } else {
                    interior.push((d, node, k));
                }
            }
        }
        assert!(!interior.is_empty(), "{cell_kind:?}: the patch has no interior node");
        let K_ii = DMatrix::from_fn(interior.len(), interior.len(), |i, j| K[(interior[i].0, interior[j].0)]);
        let rhs = DVector::from_fn(interior.len(), |i, _| {
            -fixed.iter().map(|&(d, v)| K[(interior[i].0, d)] * v).sum::<f64>()
        });
        let u = K_ii.cholesky().expect("K_ii positive definite").solve(&rhs);
        let scale = (A.amax() + b.amax()) * 2.0;
        let err = interior
            .iter()
            .enumerate()
            .map(|(i, &(_, node, k))| (u[i] - exact(node)[k]).abs())
            .fold(0.0, f64::max);
        // Round-off: cond(K_ii) ~ 1e3 for these patches, times eps, times the field's size.
        assert!(err <= 1e-10 * scale, "{cell_kind:?}: patch test error {err:.2e}");
    }
}

fn expected_node_count(kind: CellKind, [nx, ny, nz]: [usize; 3]) -> usize {
    let corners = (nx + 1) * (ny + 1) * (nz + 1);
    match kind {
        CellKind::Hex8 | CellKind::Tet4 | CellKind::Wedge6 => corners,
        CellKind::Hex20 => corners + nx * (ny + 1) * (nz + 1) + (nx + 1) * ny * (nz + 1) + (nx + 1) * (ny + 1) * nz,
        // Kuhn tets use the brick edges, one diagonal per face and the body diagonal: every
        // point of the half-spacing grid.
        CellKind::Tet10 => (2 * nx + 1) * (2 * ny + 1) * (2 * nz + 1),
        _ => unreachable!(),
    }
}

#[test]
fn box_mesh_counts_sets_and_volume() {
    let lengths = [2.0, 1.0, 0.5];
    let divisions = [3, 2, 2];
    for kind in KINDS {
        let mesh = box_mesh(kind, lengths, divisions).unwrap();
        assert_eq!(
            mesh.nodes.len(),
            expected_node_count(kind, divisions),
            "{kind:?} node count"
        );
        let per_brick = match kind {
            CellKind::Tet4 | CellKind::Tet10 => 6,
            CellKind::Wedge6 => 2,
            _ => 1,
        };
        assert_eq!(mesh.cells.len(), per_brick * 12, "{kind:?} cell count");
        assert_eq!(mesh.cell_sets["volume"].len(), mesh.cells.len());
        // Face sets: exactly the nodes on each face (coordinates are exact multiples of the
        // half spacing, so the comparison with the box's faces is exact).
        for (name, axis, value) in [
            ("x0", 0, 0.0),
            ("x1", 0, lengths[0]),
            ("y0", 1, 0.0),
            ("y1", 1, lengths[1]),
            ("z0", 2, 0.0),
            ("z1", 2, lengths[2]),
        ] {
            let set = mesh.node_set(name).unwrap();
            let on: Vec<NodeId> = (0..mesh.nodes.len() as u32)
                .map(NodeId)
                .filter(|n| (mesh.nodes[n.index()][axis] - value).abs() <= 1e-12)
                .collect();
            assert_eq!(set, on.as_slice(), "{kind:?}: set {name}");
        }
        let sk = kind_of(kind);
        let V: f64 = mesh
            .cells
            .iter()
            .enumerate()
            .map(|(c, cell)| {
                let X: Vec<Point3<f64>> = cell.nodes.iter().map(|n| mesh.nodes[n.index()]).collect();
                solid::volume(sk, c, &X).unwrap()
            })
            .sum();
        // Round-off of summing ~100 element volumes.
        assert!((V - 1.0).abs() <= 1e-13, "{kind:?}: volume {V}");
    }
}

/// Conformity: every face appears in one cell (boundary) or two (interior), and the boundary
/// faces cover exactly the surface of the box.
#[test]
fn box_mesh_is_conforming() {
    let lengths = [2.0, 1.0, 0.5];
    for kind in KINDS {
        let mesh = box_mesh(kind, lengths, [3, 2, 2]).unwrap();
        let sk = kind_of(kind);
        let mut count: std::collections::BTreeMap<Vec<NodeId>, usize> = Default::default();
        let mut area = std::collections::BTreeMap::new();
        for cell in &mesh.cells {
            for face in sk.faces() {
                let mut key: Vec<NodeId> = face.iter().map(|&a| cell.nodes[a]).collect();
                // Corner-only area (all faces are flat parallelograms or triangles here).
                let p: Vec<Point3<f64>> = key.iter().take(4).map(|n| mesh.nodes[n.index()]).collect();
                let corners = if face.len() == 3 || face.len() == 6 { 3 } else { 4 };
                let a = if corners == 3 {
                    0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm()
                } else {
                    (p[1] - p[0]).cross(&(p[3] - p[0])).norm()
                };
                key.sort_unstable();
                *count.entry(key.clone()).or_default() += 1;
                area.insert(key, a);
            }
        }
        assert!(
            count.values().all(|&c| c == 1 || c == 2),
            "{kind:?}: a face shared by more than two cells"
        );
        let boundary: f64 = count.iter().filter(|(_, &c)| c == 1).map(|(k, _)| area[k]).sum();
        let surface = 2.0 * (lengths[0] * lengths[1] + lengths[1] * lengths[2] + lengths[2] * lengths[0]);
        // Round-off of summing ~100 face areas.
        assert!(
            (boundary - surface).abs() <= 1e-12,
            "{kind:?}: boundary faces cover {boundary}, box surface {surface}"
        );
    }
}

#[test]
fn free_meshed_body_has_six_rigid_modes() {
    for kind in KINDS {
        let model = solid_model(
            box_mesh(kind, [1.0, 0.8, 0.6], [2, 2, 2]).unwrap(),
            material(),
            MassKind::Consistent,
        )
        .unwrap();
        let (K, _) = free_stiffness(&model);
        let (zeros, next) = null_space(&K);
        assert_eq!(zeros, 6, "{kind:?}: {zeros} zero eigenvalues");
        assert!(
            next > 1e-8,
            "{kind:?}: softest deformation mode {next:.2e} of the largest"
        );
    }
}

#[test]
fn solid_model_with_materials_assigns_and_reports() {
    let mut mesh = box_mesh(CellKind::Hex8, [2.0, 1.0, 1.0], [2, 1, 1]).unwrap();
    mesh.cell_sets.insert("left".into(), vec![fe_model::CellId(0)]);
    mesh.cell_sets.insert("right".into(), vec![fe_model::CellId(1)]);
    let soft = IsotropicMaterial::new("soft", 1e9, 0.3, 1000.0).unwrap();
    let model = solid_model_with_materials(
        mesh.clone(),
        &[("left", material()), ("right", soft.clone())],
        MassKind::Consistent,
    )
    .unwrap();
    assert_eq!(model.elements.len(), 2);
    assert_eq!(model.materials.len(), 2);
    let (_, s1) = model.elements[1].solid().unwrap();
    assert_eq!(model.materials[s1.material.0 as usize].name(), "soft");

    let err = solid_model_with_materials(mesh.clone(), &[("lft", material())], MassKind::Consistent).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, FeError::UnknownCellSet { .. }), "{err:?}");
    assert!(msg.contains("'lft'") && msg.contains("left"), "{msg}");

    let err = solid_model_with_materials(mesh.clone(), &[("left", material())], MassKind::Consistent).unwrap_err();
    assert!(err.to_string().contains("cell 2 (hex8) is in none"), "{err}");

    let err =
        solid_model_with_materials(mesh, &[("volume", material()), ("left", soft)], MassKind::Consistent).unwrap_err();
    assert!(
        err.to_string().contains("in both cell sets 'volume' and 'left'"),
        "{err}"
    );
}

// ---------------------------------------------------------------- structure level

const L: f64 = 10.0;
const E: f64 = 200e9;
const RHO: f64 = 7850.0;

/// Poisson's ratio 0: the solid then has no Poisson stresses at the clamp, and its shear
/// factor is Cowper's 10 (1 + nu) / (12 + 11 nu) = 5/6 exactly, as in the beam model.
fn cantilever_material() -> IsotropicMaterial {
    IsotropicMaterial::new("nu0", E, 0.0, RHO).unwrap()
}

/// A 10 x 1 x 1 cantilever along x, clamped at x = 0 (all nodes of the face), with an RBE3
/// interface at the centroid of the face x = L.
fn cantilever(kind: CellKind, divisions: [usize; 3]) -> (FeModel, NodeId) {
    let mesh = box_mesh(kind, [L, 1.0, 1.0], divisions).unwrap();
    let mut model = solid_model(mesh, cantilever_material(), MassKind::Consistent).unwrap();
    for n in model.node_set("x0", "clamp").unwrap().to_vec() {
        model.add_support(n, DofMask::ALL);
    }
    let tip = add_interface_on_set(&mut model, "tip", "x1", None, SpiderKind::Rbe3).unwrap();
    (model, tip)
}

/// Timoshenko cantilever tip deflection under an end load: $PL^3/3EI + PL/(kGA)$.
fn timoshenko_tip_deflection(P: f64) -> f64 {
    let (A, I, G, k) = (1.0, 1.0 / 12.0, E / 2.0, 5.0 / 6.0);
    P * L.powi(3) / (3.0 * E * I) + P * L / (k * G * A)
}

fn tip_deflection_ratio(kind: CellKind, divisions: [usize; 3]) -> f64 {
    let (model, tip) = cantilever(kind, divisions);
    let P = 1e5;
    let sol = solve_static(&model, &[NodalLoad::force(tip, Vector3::new(0.0, 0.0, -P))]).unwrap();
    // Equilibrium: the clamp takes the whole load.
    let Rz: f64 = sol.reactions.iter().map(|(_, r)| r[2]).sum();
    // Round-off of the solve (relative residual <= 1e-8 is checked by solve_static).
    assert!((Rz - P).abs() <= 1e-6 * P, "{kind:?}: reaction {Rz} vs load {P}");
    -sol.displacements[tip.index()][2] / timoshenko_tip_deflection(P)
}

#[test]
fn cantilever_tip_deflection_hex20_and_tet10_within_one_percent_of_timoshenko() {
    for (kind, divisions) in [(CellKind::Hex20, [10, 2, 2]), (CellKind::Tet10, [10, 2, 2])] {
        let ratio = tip_deflection_ratio(kind, divisions);
        // Discretisation: quadratic elements reproduce the cubic bending field nearly exactly;
        // what remains is the clamp (which also stops the shear warping the beam theory lets
        // free, 0.6 % of the deflection here) and the end load's distribution. 1 % is the
        // required accuracy; measured: hex20 -0.03 %, tet10 -0.07 %.
        assert!(
            (ratio - 1.0).abs() < 0.01,
            "{kind:?}: tip deflection / Timoshenko = {ratio:.5}"
        );
    }
}

#[test]
fn cantilever_tet4_locks_in_bending() {
    // Linear tets cannot bend without spurious shear strain: on a coarse mesh the tip
    // deflection is far below the beam's (this is why tet4 is kept for contrast only).
    // Measured: 24 % of the beam's deflection on this 10 x 1 x 1 mesh (60 tets).
    let ratio = tip_deflection_ratio(CellKind::Tet4, [10, 1, 1]);
    assert!(
        ratio < 0.8,
        "tet4 tip deflection / Timoshenko = {ratio:.3}: expected locking"
    );
    assert!(ratio > 0.0, "tet4 deflects the wrong way: {ratio}");
}

/// First four frequencies (two bending pairs) of a Timoshenko beam model of the cantilever,
/// converged (200 elements; the beam element's own frequencies converge at O(h^2), so the
/// discretisation error is ~1e-6).
fn beam_reference_frequencies() -> Vec<f64> {
    let mut model = FeModel::default();
    let material = model.add_material(cantilever_material());
    let section = model.add_section(BeamSection::rectangle("square", 1.0, 1.0, 0.0).unwrap());
    let props = BeamProperties {
        section,
        material,
        orientation: Vector3::y(),
        theory: BeamTheory::Timoshenko,
        mass: MassKind::Consistent,
    };
    let nodes = straight_beam(
        &mut model,
        Point3::origin(),
        Point3::new(L, 0.0, 0.0),
        200,
        &props,
        None,
    )
    .unwrap();
    model.add_support(nodes[0], DofMask::ALL);
    lowest_frequencies_hz(&model, 4)
}

#[test]
fn cantilever_bending_frequencies_hex20_and_tet10_within_one_percent_of_timoshenko() {
    let reference = beam_reference_frequencies();
    // Sanity: the first is near the Euler-Bernoulli value 1.8751^2/(2 pi) sqrt(EI/(rho A L^4)).
    let f_eb = 1.875_104_f64.powi(2) / (2.0 * std::f64::consts::PI) * (E / 12.0 / RHO / L.powi(4)).sqrt();
    assert!(
        (reference[0] / f_eb - 1.0).abs() < 0.01,
        "beam reference {} vs EB {f_eb}",
        reference[0]
    );
    for (kind, divisions) in [(CellKind::Hex20, [10, 2, 2]), (CellKind::Tet10, [10, 2, 2])] {
        let (model, _) = cantilever(kind, divisions);
        let f = lowest_frequencies_hz(&model, 4);
        for (i, (ours, beam)) in f.iter().zip(&reference).enumerate() {
            // Discretisation and 3D effects (clamp, section warping), as for the deflection;
            // the second bending mode (L/h = 1.8 per half wave) is where they show most.
            // 1 % is the required accuracy; measured: hex20 +0.03 % and +0.2 %, tet10 up to +0.5 %.
            assert!(
                (ours / beam - 1.0).abs() < 0.01,
                "{kind:?} mode {}: {ours:.4} Hz vs beam {beam:.4} Hz",
                i + 1
            );
        }
    }
}

/// A mesh of the element of `kind` (its nodes moved by `at`) twice: cell 11 as it is and cell
/// 42 with its nodes mapped by `second`.
fn two_cell_mesh(kind: SolidKind, second: &dyn Fn(&Point3<f64>) -> Point3<f64>) -> Mesh {
    let X = element_nodes(kind, 0.0);
    let mut mesh = Mesh::default();
    let n = X.len();
    for x in &X {
        mesh.add_node(*x);
    }
    for x in &X {
        mesh.add_node(second(x));
    }
    mesh.cells.push(fe_model::Cell {
        kind: kind.cell_kind(),
        nodes: (0..n as u32).map(NodeId).collect(),
        tag: 11,
    });
    mesh.cells.push(fe_model::Cell {
        kind: kind.cell_kind(),
        nodes: (n as u32..2 * n as u32).map(NodeId).collect(),
        tag: 42,
    });
    mesh
}

/// The mesh check names an inverted or a degenerate element by its label in the file (the
/// cell's tag), not by its position, and refuses exactly what the element matrices refuse.
#[test]
fn inverted_and_degenerate_cells_are_named_by_their_label_in_the_file() {
    use fe_model::mesh::quality::{check_solid_cells, CellGeometryError};
    for kind in SolidKind::ALL {
        let shifted = |p: &Point3<f64>| Point3::new(p.x + 3.0, p.y, p.z);
        assert_eq!(check_solid_cells(&two_cell_mesh(kind, &shifted)), Ok(()), "{kind:?}");
        let mirrored = |p: &Point3<f64>| Point3::new(-p.x, p.y, p.z);
        let e = check_solid_cells(&two_cell_mesh(kind, &mirrored)).unwrap_err();
        assert!(
            matches!(e, CellGeometryError::Inverted { label: 42, det_j, .. } if det_j < 0.0),
            "{kind:?}: {e:?}"
        );
        let message = e.to_string();
        assert!(
            message.starts_with("element 42 (") && message.contains("inverted"),
            "{message}"
        );
        let flat = |p: &Point3<f64>| Point3::new(p.x, p.y, 0.0);
        let e = check_solid_cells(&two_cell_mesh(kind, &flat)).unwrap_err();
        assert!(
            matches!(e, CellGeometryError::Degenerate { label: 42, .. }),
            "{kind:?}: {e:?}"
        );
        assert!(e.to_string().contains("element 42") && e.to_string().contains("degenerate"));
        // The same elements fail their matrices: the check refuses what the assembly would.
        for map in [&mirrored as &dyn Fn(&Point3<f64>) -> Point3<f64>, &flat] {
            let X: Vec<Point3<f64>> = element_nodes(kind, 0.0).iter().map(map).collect();
            assert!(solid::solid_matrices(kind, 1, &X, &material(), MassKind::Consistent).is_err());
        }
    }
}
