//! Stress recovery (`fe_model::stress`): patch tests of the nodal stresses on every solid
//! kind, the exactness of the extrapolation for linear stresses on the quadratic kinds, and
//! beam section forces against the analytic cantilever.

use super::common::{skewed_axes, skewed_beam, steel};
use super::solid::{distort_interior, element_nodes, material, KINDS};
use fe_model::box_mesh::{box_mesh, solid_model};
use fe_model::element::solid::{elasticity_matrix, SolidKind};
use fe_model::stress::{beam_section_forces, nodal_stresses, principal_stresses, solid_nodal_stresses, von_mises};
use fe_model::{solve_static, BeamTheory, DofMask, FeModel, MassKind, NodalLoad, NodeId};
use nalgebra::{Matrix3, Point3, Vector3, Vector6};

/// The displacement gradient of the patch tests' linear field, not symmetric (it carries a
/// rotation too, which must give no stress).
fn gradient() -> Matrix3<f64> {
    Matrix3::new(1.0, 2.0, -3.0, 4.0, -5.0, 6.0, 7.0, 8.0, 10.0) * 1e-4
}

/// $\mathbf D\boldsymbol\varepsilon$ of a displacement gradient, Voigt order of the module.
fn exact_stress(H: &Matrix3<f64>) -> [f64; 6] {
    let eps = 0.5 * (H + H.transpose());
    let e = Vector6::new(
        eps[(0, 0)],
        eps[(1, 1)],
        eps[(2, 2)],
        2.0 * eps[(0, 1)],
        2.0 * eps[(1, 2)],
        2.0 * eps[(2, 0)],
    );
    let s = elasticity_matrix(&material()) * e;
    [s[0], s[1], s[2], s[3], s[4], s[5]]
}

fn max_difference(a: &[f64; 6], b: &[f64; 6]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

#[test]
fn uniform_stress_is_recovered_exactly_at_the_nodes_of_one_distorted_element_of_every_kind() {
    let H = gradient();
    let exact = exact_stress(&H);
    let scale = exact.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for kind in SolidKind::ALL {
        let X = element_nodes(kind, 0.08);
        let u: Vec<f64> = X
            .iter()
            .flat_map(|x| (H * x.coords).iter().copied().collect::<Vec<_>>())
            .collect();
        let nodal = solid_nodal_stresses(kind, 0, &X, &material(), &u).unwrap();
        assert_eq!(nodal.len(), kind.node_count());
        for (a, s) in nodal.iter().enumerate() {
            // Round-off: the Jacobian inverse and the extrapolation (a few hundred flops on
            // numbers of order one) times the stress scale.
            assert!(
                max_difference(s, &exact) <= 1e-10 * scale,
                "{}: node {a} has {s:?}, exact {exact:?}",
                kind.name()
            );
        }
    }
}

#[test]
fn uniform_stress_is_recovered_exactly_at_every_node_of_a_distorted_mesh_of_every_kind() {
    let H = gradient();
    let b = Vector3::new(1e-3, -2e-3, 5e-4);
    let exact = exact_stress(&H);
    let scale = exact.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for cell_kind in KINDS {
        let mut mesh = box_mesh(cell_kind, [1.0, 1.2, 0.9], [3, 3, 3]).unwrap();
        distort_interior(&mut mesh, 0.2, 0.3);
        let model = solid_model(mesh, material(), MassKind::Consistent).unwrap();
        let u: Vec<[f64; 6]> = model
            .mesh
            .nodes
            .iter()
            .map(|x| {
                let v = H * x.coords + b;
                [v.x, v.y, v.z, 0.0, 0.0, 0.0]
            })
            .collect();
        let sigma = nodal_stresses(&model, &u).unwrap();
        for (i, s) in sigma.iter().enumerate() {
            let s = s.expect("every node of a solid mesh has a stress");
            // As above: round-off only.
            assert!(
                max_difference(&s, &exact) <= 1e-10 * scale,
                "{cell_kind:?}: node {i} has {s:?}, exact {exact:?}"
            );
        }
    }
}

#[test]
fn a_linear_stress_is_extrapolated_exactly_on_the_quadratic_kinds() {
    // u = quadratic in x on an affine (undistorted) element: the strain and stress are linear,
    // exact at the integration points, and the linear fit carries them to the nodes exactly.
    let mat = material();
    for kind in [SolidKind::Tet10, SolidKind::Hex20] {
        let X = element_nodes(kind, 0.0);
        let field = |x: &Point3<f64>| {
            Vector3::new(
                1e-4 * x.x * x.y + 2e-4 * x.z * x.z,
                -3e-4 * x.x * x.x + 1e-4 * x.y * x.z,
                2e-4 * x.y * x.y - 1e-4 * x.x * x.z,
            )
        };
        let grad = |x: &Point3<f64>| {
            Matrix3::new(
                1e-4 * x.y,
                1e-4 * x.x,
                4e-4 * x.z,
                -6e-4 * x.x,
                1e-4 * x.z,
                1e-4 * x.y,
                -1e-4 * x.z,
                4e-4 * x.y,
                -1e-4 * x.x,
            )
        };
        let u: Vec<f64> = X
            .iter()
            .flat_map(|x| field(x).iter().copied().collect::<Vec<_>>())
            .collect();
        let nodal = solid_nodal_stresses(kind, 0, &X, &mat, &u).unwrap();
        for (a, s) in nodal.iter().enumerate() {
            let exact = exact_stress(&grad(&X[a]));
            let scale = exact.iter().map(|v| v.abs()).fold(1e3, f64::max);
            // Round-off of the least-squares fit (normal equations of an 8 x 8 system with
            // condition ~1e2) times the stress scale.
            assert!(
                max_difference(s, &exact) <= 1e-9 * scale,
                "{}: node {a} has {s:?}, exact {exact:?}",
                kind.name()
            );
        }
    }
}

#[test]
fn von_mises_and_principal_stresses_of_simple_states() {
    // Uniaxial: von Mises = |sigma|; pure shear tau: sqrt(3) tau, principal +-tau.
    let uni = [100.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert!((von_mises(&uni) - 100.0).abs() < 1e-12);
    let shear = [0.0, 0.0, 0.0, 50.0, 0.0, 0.0];
    assert!((von_mises(&shear) - 50.0 * 3f64.sqrt()).abs() < 1e-12);
    let p = principal_stresses(&shear);
    // Eigenvalues of a 3x3 symmetric matrix to round-off of its entries.
    assert!((p[0] - 50.0).abs() < 1e-12 && p[1].abs() < 1e-12 && (p[2] + 50.0).abs() < 1e-12);
    // Hydrostatic: no von Mises stress.
    assert!(von_mises(&[7.0, 7.0, 7.0, 0.0, 0.0, 0.0]).abs() < 1e-12);
}

#[test]
fn closed_form_principal_stresses_equal_the_iterative_eigenvalues() {
    // General, repeated (uniaxial in rotated axes, hydrostatic plus tiny shear), and
    // sign-mixed tensors against nalgebra's iterative symmetric eigensolver.
    let R = nalgebra::Rotation3::from_scaled_axis(Vector3::new(0.3, -0.7, 1.1));
    let rotated = |d: [f64; 3]| {
        let S = R * Matrix3::from_diagonal(&Vector3::from(d)) * R.transpose();
        [S[(0, 0)], S[(1, 1)], S[(2, 2)], S[(0, 1)], S[(1, 2)], S[(2, 0)]]
    };
    let cases = [
        [120e6, -30e6, 45e6, 17e6, -8e6, 23e6],
        rotated([250e6, 0.0, 0.0]),
        rotated([-80e6, -80e6, 40e6]),
        rotated([5e6, 5e6, 5e6]),
        [1e8, 1e8, 1e8, 1e-3, 0.0, 2e-3],
        [-3.0, 2.0, 7.0, 0.0, 0.0, 0.0],
        [0.0; 6],
    ];
    for s in cases {
        let mut e: Vec<f64> = nalgebra::SymmetricEigen::new(fe_model::stress::tensor(&s))
            .eigenvalues
            .iter()
            .copied()
            .collect();
        e.sort_by(|a, b| b.total_cmp(a));
        let p = principal_stresses(&s);
        let scale = s.iter().fold(1.0f64, |m, x| m.max(x.abs()));
        // The largest to a few ulps of the largest component; the other two lose up to
        // sqrt(machine epsilon) at a double root (the arccos at its end point).
        assert!((p[0] - e[0]).abs() <= 1e-13 * scale, "{s:?}: {p:?} against {e:?}");
        for k in 1..3 {
            assert!((p[k] - e[k]).abs() <= 1e-8 * scale, "{s:?}: {p:?} against {e:?}");
        }
    }
}

/// Clamps node 0 of a beam model.
fn clamp(model: &mut FeModel, node: NodeId) {
    model.add_support(node, DofMask::ALL);
}

/// Section forces at both ends of every element, local axes.
fn all_section_forces(model: &FeModel, u: &[[f64; 6]], loads: Option<&[Vec<f64>]>) -> Vec<[[f64; 6]; 2]> {
    (0..model.elements.len())
        .map(|e| {
            let nodes = model.elements[e].nodes();
            let u_e: Vec<f64> = nodes.iter().flat_map(|n| u[n.index()]).collect();
            beam_section_forces(model, e, &u_e, loads.map(|l| l[e].as_slice())).unwrap()
        })
        .collect()
}

/// The analytic section forces of a cantilever along `e_x` from the origin, length `L`, at
/// distance `x` from the clamp, for a tip force `P` and a distributed force `q` per length:
/// $\mathbf s = \mathbf P + (L - x)\mathbf q$, $\mathbf M = (L-x)\mathbf e_x\times\mathbf P +
/// \tfrac12(L-x)^2\mathbf e_x\times\mathbf q$, in local components $[N, V_y, V_z, T, M_y, M_z]$.
fn analytic(x: f64, L: f64, P: Vector3<f64>, q: Vector3<f64>) -> [f64; 6] {
    let (ex, ey, ez) = skewed_axes();
    let s = P + (L - x) * q;
    let M = (L - x) * ex.cross(&P) + 0.5 * (L - x).powi(2) * ex.cross(&q);
    [s.dot(&ex), s.dot(&ey), s.dot(&ez), M.dot(&ex), M.dot(&ey), M.dot(&ez)]
}

#[test]
fn beam_section_forces_of_a_cantilever_under_tip_load_and_gravity_are_analytic() {
    let (L, n) = (2.0, 8);
    let (ex, ey, ez) = skewed_axes();
    // A tip force with every component, and gravity oblique to the beam (axial, both shears).
    let P = 300.0 * ez - 120.0 * ey + 50.0 * ex;
    let g = Vector3::new(0.0, 0.0, -9.81) + 2.0 * ey;
    for theory in [BeamTheory::EulerBernoulli, BeamTheory::Timoshenko] {
        let (mut model, nodes, section) = skewed_beam(L, 0.04, 0.06, n, theory, MassKind::Consistent);
        clamp(&mut model, nodes[0]);
        // Tip load.
        let tip = solve_static(&model, &[NodalLoad::force(nodes[n], P)]).unwrap();
        let forces = all_section_forces(&model, &tip.displacements, None);
        let h = L / n as f64;
        let scale = P.norm() * L;
        for (e, f) in forces.iter().enumerate() {
            for (end, s) in f.iter().enumerate() {
                let x = h * (e + end) as f64;
                let exact = analytic(x, L, P, Vector3::zeros());
                // The element is nodally exact for end loads: round-off of the solve
                // (relative residual 1e-12 or so) times the moment scale; 1e-6 is the bound
                // the recovery promises.
                assert!(
                    max_difference(s, &exact) <= 1e-6 * scale,
                    "{theory:?} tip load, element {e} end {end}: {s:?} vs {exact:?}"
                );
            }
        }
        // Gravity: the consistent load M_e g of every element, which the recovery subtracts.
        let mut loads = Vec::new();
        let mut nodal = vec![[0.0; 6]; model.node_count()];
        for e in 0..model.elements.len() {
            let m = fe_model::assembly::element_matrices(&model, e).unwrap();
            let acc: Vec<f64> = (0..12).map(|k| if k % 6 < 3 { g[k % 6] } else { 0.0 }).collect();
            let f_e: Vec<f64> = (0..12).map(|r| (0..12).map(|c| m.M_e[(r, c)] * acc[c]).sum()).collect();
            for (a, node) in model.elements[e].nodes().iter().enumerate() {
                for k in 0..6 {
                    nodal[node.index()][k] += f_e[6 * a + k];
                }
            }
            loads.push(f_e);
        }
        let nodal_loads: Vec<NodalLoad> = nodal
            .iter()
            .enumerate()
            .map(|(i, f)| NodalLoad {
                node: NodeId(i as u32),
                force: Vector3::new(f[0], f[1], f[2]),
                moment: Vector3::new(f[3], f[4], f[5]),
            })
            .collect();
        let grav = solve_static(&model, &nodal_loads).unwrap();
        let forces = all_section_forces(&model, &grav.displacements, Some(&loads));
        let q = steel().rho() * section.A() * g;
        let scale = q.norm() * L * L;
        for (e, f) in forces.iter().enumerate() {
            for (end, s) in f.iter().enumerate() {
                let x = h * (e + end) as f64;
                let exact = analytic(x, L, Vector3::zeros(), q);
                // Consistent loads make the elements nodally exact for a uniform load (the
                // Timoshenko element too: its end forces balance the load exactly); round-off.
                assert!(
                    max_difference(s, &exact) <= 1e-6 * scale,
                    "{theory:?} gravity, element {e} end {end}: {s:?} vs {exact:?}"
                );
            }
        }
        // Extreme fibres of the root section under the tip load: N/A +- the two bending terms.
        let root = forces_root(&model, &tip.displacements);
        let (b, hgt) = (0.04, 0.06);
        let expected = root[0] / section.A()
            + 0.5 * hgt * (root[4] / section.Iy()).abs()
            + 0.5 * b * (root[5] / section.Iz()).abs();
        let range = section.fibre_stress_range(&root).unwrap();
        assert!((range[0] - expected).abs() <= 1e-12 * expected.abs());
    }
}

fn forces_root(model: &FeModel, u: &[[f64; 6]]) -> [f64; 6] {
    all_section_forces(model, u, None)[0][0]
}
