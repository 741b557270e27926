//! `Beam2` element-level tests (tier 1: the element alone), plus its one-element analytic checks and
//! the shape constructors of `BeamSection`.
//!
//! Covered: symmetry; the six rigid motions as the exact null space of $\mathbf K_e$; mass
//! and rotational inertia of rigid motions; Timoshenko → Euler-Bernoulli as $G \to \infty$;
//! the local matrices against an independent quadrature of the shape functions; one-element
//! cantilevers (exact for this element) in both bending planes, axial and torsion; section
//! values; errors. All geometry is skewed (axis and orientation along no global axis) except
//! where a test needs local = global axes, and says so.

#![allow(non_snake_case)]

use fe_model::element::beam2::beam2_matrices;
use fe_model::{
    Beam2, BeamSection, BeamTheory, ElementError, IsotropicMaterial, LocalMatrices, MassKind, MaterialId, NodeId,
    PropertyError, SectionId,
};
use nalgebra::{DMatrix, DVector, Matrix3, Point3, Vector3};

const EPS: f64 = f64::EPSILON;
const THEORIES: [BeamTheory; 2] = [BeamTheory::EulerBernoulli, BeamTheory::Timoshenko];
const MASSES: [MassKind; 2] = [MassKind::Consistent, MassKind::Lumped];

// ---------------------------------------------------------------------------------------
// Fixtures
// ---------------------------------------------------------------------------------------

/// Steel.
fn steel() -> IsotropicMaterial {
    IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap()
}

/// A section with every value distinct (Iy != Iz, ky != kz) so that a swapped plane or shear
/// factor changes the answer. Values of a 80 x 150 mm rectangle, shear factors made up.
fn section() -> BeamSection {
    let (b, h) = (0.08, 0.15);
    BeamSection::from_values(
        "test",
        b * h,
        b * h.powi(3) / 12.0,
        h * b.powi(3) / 12.0,
        2.1e-5,
        0.85,
        0.8,
    )
    .unwrap()
}

/// A stocky skewed element: L = 0.6 m gives Phi_z ~ 0.2, so shear is far from negligible.
const L_SKEW: f64 = 0.6;

fn skew_geometry() -> ([Point3<f64>; 2], Vector3<f64>) {
    let X1 = Point3::new(0.3, -0.2, 0.5);
    let axis = Vector3::new(1.0, 2.0, -0.7).normalize();
    let v = Vector3::new(0.3, -1.0, 0.4);
    ([X1, X1 + L_SKEW * axis], v)
}

fn beam(theory: BeamTheory, mass: MassKind, orientation: Vector3<f64>) -> Beam2 {
    Beam2 {
        nodes: [NodeId(3), NodeId(4)],
        section: SectionId(0),
        material: MaterialId(0),
        orientation,
        theory,
        mass,
    }
}

fn skew_matrices(theory: BeamTheory, mass: MassKind) -> LocalMatrices {
    let (X, v) = skew_geometry();
    beam2_matrices(&beam(theory, mass, v), 0, X, &section(), &steel()).unwrap()
}

/// Local axes as the element docs define them, re-derived here: columns e_x, e_y, e_z.
fn axes(X: [Point3<f64>; 2], v: Vector3<f64>) -> Matrix3<f64> {
    let e_x = (X[1] - X[0]).normalize();
    let e_z = e_x.cross(&v).normalize();
    Matrix3::from_columns(&[e_x, e_z.cross(&e_x), e_z])
}

/// Dofs of a rigid motion: translation `t` plus infinitesimal rotation `theta` about `x0`.
fn rigid_motion(X: [Point3<f64>; 2], t: Vector3<f64>, theta: Vector3<f64>, x0: Point3<f64>) -> DVector<f64> {
    let mut r = DVector::zeros(12);
    for (i, Xi) in X.iter().enumerate() {
        let u = t + theta.cross(&(Xi - x0));
        r.fixed_rows_mut::<3>(6 * i).copy_from(&u);
        r.fixed_rows_mut::<3>(6 * i + 3).copy_from(&theta);
    }
    r
}

fn max_abs(A: &DMatrix<f64>) -> f64 {
    A.amax()
}

// ---------------------------------------------------------------------------------------
// 1. Symmetry
// ---------------------------------------------------------------------------------------

#[test]
fn matrices_are_symmetric_on_a_skewed_beam() {
    for theory in THEORIES {
        for mass in MASSES {
            let LocalMatrices { K_e, M_e } = skew_matrices(theory, mass);
            for (name, A) in [("K_e", &K_e), ("M_e", &M_e)] {
                let asym = (A - A.transpose()).amax();
                // Round-off only: the local matrices are symmetric by construction, and each
                // global entry is R A_loc R^T over one 3x3 block (9 products, 2 sums of 3),
                // so entries (i,j) and (j,i) differ by a few dozen ulps of the largest entry.
                let tol = 64.0 * EPS * max_abs(A);
                assert!(
                    asym <= tol,
                    "{theory:?} {mass:?}: {name} asymmetry {asym:.3e} > {tol:.3e}"
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// 2. Rigid motions are the null space
// ---------------------------------------------------------------------------------------

#[test]
fn rigid_motions_are_exactly_the_null_space_of_K() {
    let (X, _) = skew_geometry();
    let x0 = Point3::new(-1.0, 0.4, 2.0); // rotations about a point off the element
    let mut motions = Vec::new();
    for k in 0..3 {
        motions.push(rigid_motion(X, Vector3::ith(k, 1.0), Vector3::zeros(), x0));
        motions.push(rigid_motion(X, Vector3::zeros(), Vector3::ith(k, 1.0), x0));
    }
    for theory in THEORIES {
        let K = skew_matrices(theory, MassKind::Consistent).K_e;
        let K_norm = K.norm();
        for (m, r) in motions.iter().enumerate() {
            let residual = (&K * r).norm();
            // Round-off only: K r = 0 exactly in exact arithmetic; each entry of K r sums 12
            // products, so the residual is a modest multiple of eps ||K|| ||r||.
            let tol = 64.0 * EPS * K_norm * r.norm();
            assert!(
                residual <= tol,
                "{theory:?} rigid motion {m}: ||K r|| = {residual:.3e} > {tol:.3e}"
            );
        }

        let K_sym = (&K + K.transpose()) * 0.5;
        let mut lambda: Vec<f64> = K_sym.symmetric_eigenvalues().iter().copied().collect();
        lambda.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
        let lambda_max = lambda[11].abs();
        // Round-off level of a symmetric eigensolver: O(n eps ||K||_2).
        let zero_tol = 12.0 * 64.0 * EPS * lambda_max;
        for (i, l) in lambda.iter().enumerate().take(6) {
            assert!(
                l.abs() <= zero_tol,
                "{theory:?}: eigenvalue {i} = {l:.3e} not zero (tol {zero_tol:.3e})"
            );
        }
        for (i, l) in lambda.iter().enumerate().skip(6) {
            // The smallest deformation eigenvalue here is ~5e-4 of the largest (axial, 2EA/L);
            // 1e-6 lambda_max sits orders of magnitude above the zero tolerance and below it.
            assert!(
                *l > 1e-6 * lambda_max,
                "{theory:?}: eigenvalue {i} = {l:.3e} is not clearly positive"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// 3. Mass and inertia of rigid motions
// ---------------------------------------------------------------------------------------

#[test]
fn rigid_translation_carries_the_element_mass() {
    let (X, _) = skew_geometry();
    let (s, mat) = (section(), steel());
    let mass = mat.rho() * s.A() * L_SKEW;
    let directions = [
        Vector3::x(),
        Vector3::y(),
        Vector3::z(),
        Vector3::new(0.3, -0.8, 0.5).normalize(),
        (X[1] - X[0]).normalize(),
    ];
    for theory in THEORIES {
        for kind in MASSES {
            let M = skew_matrices(theory, kind).M_e;
            for d in directions {
                let r = rigid_motion(X, d, Vector3::zeros(), X[0]);
                let m = r.dot(&(&M * &r));
                // Round-off only: the translational coefficients sum to exactly 1 (e.g.
                // 2 (13/35 + 9/70) = 1), up to a few ulps per term.
                assert!(
                    (m - mass).abs() <= 64.0 * EPS * mass,
                    "{theory:?} {kind:?} d = {d:?}: r^T M r = {m} != rho A L = {mass}"
                );
            }
        }
    }
}

#[test]
fn consistent_mass_gives_the_rigid_rotational_inertia_about_the_centre() {
    let (X, v) = skew_geometry();
    let (s, mat) = (section(), steel());
    let R = axes(X, v);
    let centre = Point3::from((X[0].coords + X[1].coords) / 2.0);
    let rho = mat.rho();
    for theory in THEORIES {
        let M = skew_matrices(theory, MassKind::Consistent).M_e;
        for theta in [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            R.column(0).into(),
            Vector3::new(0.2, 0.7, -0.4),
        ] {
            let r = rigid_motion(X, Vector3::zeros(), theta, centre);
            // The shape functions of both theories contain rigid rotation, so the consistent
            // mass gives the exact inertia: rho A L^3/12 for the axis swinging about the
            // centre, plus the sections' rotary inertia rho L diag(Ip, Iy, Iz) in local axes.
            let t = R.transpose() * theta;
            let perp2 = theta.norm_squared() - t.x * t.x;
            let expected = rho
                * L_SKEW
                * (s.A() * L_SKEW * L_SKEW / 12.0 * perp2
                    + s.Ip() * t.x * t.x
                    + s.Iy() * t.y * t.y
                    + s.Iz() * t.z * t.z);
            let got = r.dot(&(&M * &r));
            // Round-off only (as for the translation), relative to the inertia itself.
            assert!(
                (got - expected).abs() <= 64.0 * EPS * expected,
                "{theory:?} theta = {theta:?}: {got} != {expected}"
            );
        }
    }
}

#[test]
fn lumped_mass_spin_about_the_axis_gives_rho_Ip_L() {
    let (X, v) = skew_geometry();
    let (s, mat) = (section(), steel());
    let axis: Vector3<f64> = axes(X, v).column(0).into();
    for theory in THEORIES {
        let M = skew_matrices(theory, MassKind::Lumped).M_e;
        let r = rigid_motion(X, Vector3::zeros(), axis, X[0]);
        let got = r.dot(&(&M * &r));
        let expected = mat.rho() * s.Ip() * L_SKEW;
        // Round-off only: the spin's translations, axis x (X2 - X1), are O(eps L), and weigh
        // O(eps^2) in r^T M r; what remains is the round-off of R diag R^T.
        assert!(
            (got - expected).abs() <= 64.0 * EPS * expected,
            "{theory:?}: {got} != {expected}"
        );
    }
}

#[test]
fn lumped_mass_is_block_diagonal_and_both_kinds_are_positive_definite() {
    let (s, mat) = (section(), steel());
    let half = mat.rho() * s.A() * L_SKEW / 2.0;
    for theory in THEORIES {
        let M = skew_matrices(theory, MassKind::Lumped).M_e;
        for i in 0..12 {
            for j in 0..12 {
                let same_block = i / 3 == j / 3;
                if !same_block {
                    // Exactly zero: the rotation R acts block by block on a diagonal matrix.
                    assert_eq!(M[(i, j)], 0.0, "{theory:?}: lumped M[{i},{j}] couples different blocks");
                }
                if i / 3 % 2 == 0 && same_block {
                    // Translational blocks are (rho A L/2) R I R^T: round-off of R R^T = I.
                    let expected = if i == j { half } else { 0.0 };
                    assert!(
                        (M[(i, j)] - expected).abs() <= 16.0 * EPS * half,
                        "{theory:?}: M[{i},{j}]"
                    );
                }
            }
        }
        for kind in MASSES {
            let M = skew_matrices(theory, kind).M_e;
            let M_sym = (&M + M.transpose()) * 0.5;
            assert!(
                M_sym.cholesky().is_some(),
                "{theory:?} {kind:?}: M_e is not positive definite"
            );
        }
    }
}

/// HRZ lumping of the Euler-Bernoulli beam without rotary inertia gives rho A L^3/78
/// (Cook et al. 2002). Our rule includes rotary inertia, so check the limit of a thin section.
#[test]
fn lumped_bending_rotation_is_hrz_value() {
    let mat = steel();
    let L = 2.0;
    // Thin section: I/(A L^2) = 2.5e-14, so the rotary part is negligible.
    let s = BeamSection::from_values("thin", 1e-2, 1e-15, 1e-15, 2e-15, 0.9, 0.9).unwrap();
    let X = [Point3::origin(), Point3::new(L, 0.0, 0.0)];
    let b = beam(BeamTheory::EulerBernoulli, MassKind::Lumped, Vector3::y());
    let M = beam2_matrices(&b, 0, X, &s, &mat).unwrap().M_e;
    let expected = mat.rho() * s.A() * L.powi(3) / 78.0;
    for i in [4, 5, 10, 11] {
        // Relative size of the rotary-inertia term, (2/15)/(1/105) I/(A L^2) = 3.5e-13, which
        // is also above round-off.
        assert!(
            (M[(i, i)] - expected).abs() <= 1e-12 * expected,
            "M[{i},{i}] = {} != {expected}",
            M[(i, i)]
        );
    }
}

// ---------------------------------------------------------------------------------------
// 4. Timoshenko -> Euler-Bernoulli
// ---------------------------------------------------------------------------------------

#[test]
fn timoshenko_tends_to_euler_bernoulli_as_G_grows() {
    let (X, v) = skew_geometry();
    let s = section();
    let (E, rho) = (210e9, 7850.0);
    let G0 = E / 2.6;
    let matrices = |theory, kind, m: &IsotropicMaterial| beam2_matrices(&beam(theory, kind, v), 0, X, &s, m).unwrap();
    // Scale for the final check, independent of G (the torsion stiffness GJ/L grows with G
    // in both theories and cancels in the difference, so it must not set the scale).
    let base = IsotropicMaterial::from_E_G("base", E, G0, rho).unwrap();
    for kind in MASSES {
        let reference = matrices(BeamTheory::EulerBernoulli, kind, &base);
        let (K_scale, M_scale) = (reference.K_e.norm(), reference.M_e.norm());
        let mut previous: Option<(f64, f64)> = None;
        for scale in [1e2, 1e4, 1e6] {
            let m = IsotropicMaterial::from_E_G("stiff in shear", E, G0 * scale, rho).unwrap();
            let (T, B) = (
                matrices(BeamTheory::Timoshenko, kind, &m),
                matrices(BeamTheory::EulerBernoulli, kind, &m),
            );
            let (dK, dM) = ((&T.K_e - &B.K_e).norm(), (&T.M_e - &B.M_e).norm());
            if let Some((dK0, dM0)) = previous {
                // The difference is Phi/(1+Phi) times O(1) terms plus O(Phi^2): scaling G by
                // 100 scales it by (1+Phi)/(100+Phi) ~ 1/100 (1 + O(Phi)), and Phi <= 2e-3
                // here; 1% allows that and the 1e-10 round-off of nu = E/(2G) - 1 near -1.
                for (name, ratio) in [("K", dK / dK0), ("M", dM / dM0)] {
                    assert!(
                        (ratio / 1e-2 - 1.0).abs() < 1e-2,
                        "{kind:?} {name}: ratio {ratio:.6e} at G x {scale:e}"
                    );
                }
            }
            previous = Some((dK, dM));
        }
        // Phi_z(G x 1e6) ~ 2e-7: the relative difference is of that order.
        let (dK, dM) = previous.unwrap();
        let (dK, dM) = (dK / K_scale, dM / M_scale);
        assert!(
            dK < 1e-6 && dM < 1e-6,
            "{kind:?}: Timoshenko did not reach EB: {dK:.3e}, {dM:.3e}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// 5. Independent reference: quadrature of the shape functions (local = global axes)
// ---------------------------------------------------------------------------------------

/// Friedman & Kosmatka (1993) interdependent Timoshenko shape functions of one bending plane
/// with theta = +v' convention, and their x-derivatives: (N_v, N_v', N_theta, N_theta').
fn plane_shape(xi: f64, L: f64, P: f64) -> ([f64; 4], [f64; 4], [f64; 4], [f64; 4]) {
    let d = 1.0 + P;
    let Nv = [
        (2.0 * xi.powi(3) - 3.0 * xi * xi - P * xi + 1.0 + P) / d,
        L * (xi.powi(3) - (2.0 + P / 2.0) * xi * xi + (1.0 + P / 2.0) * xi) / d,
        -(2.0 * xi.powi(3) - 3.0 * xi * xi - P * xi) / d,
        L * (xi.powi(3) - (1.0 - P / 2.0) * xi * xi - P / 2.0 * xi) / d,
    ];
    let dNv = [
        (6.0 * xi * xi - 6.0 * xi - P) / d / L,
        (3.0 * xi * xi - 2.0 * (2.0 + P / 2.0) * xi + 1.0 + P / 2.0) / d,
        -(6.0 * xi * xi - 6.0 * xi - P) / d / L,
        (3.0 * xi * xi - 2.0 * (1.0 - P / 2.0) * xi - P / 2.0) / d,
    ];
    let Nt = [
        6.0 * (xi * xi - xi) / (d * L),
        (3.0 * xi * xi - (4.0 + P) * xi + 1.0 + P) / d,
        -6.0 * (xi * xi - xi) / (d * L),
        (3.0 * xi * xi - (2.0 - P) * xi) / d,
    ];
    let dNt = [
        6.0 * (2.0 * xi - 1.0) / (d * L * L),
        (6.0 * xi - (4.0 + P)) / (d * L),
        -6.0 * (2.0 * xi - 1.0) / (d * L * L),
        (6.0 * xi - (2.0 - P)) / (d * L),
    ];
    (Nv, dNv, Nt, dNt)
}

/// K and M of a beam along global x (orientation global y, so local = global) by 4-point
/// Gauss quadrature (exact for the degree-6 products) of
/// K = int B^T D B, M = int N^T diag(rho A, rho A, rho A, rho Ip, rho Iy, rho Iz) N,
/// with strains [u', theta_x', theta_z', theta_y', v' - theta_z, w' + theta_y].
fn quadrature_matrices(
    L: f64,
    theory: BeamTheory,
    s: &BeamSection,
    m: &IsotropicMaterial,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let (E, G, rho) = (m.E(), m.G(), m.rho());
    let (Py, Pz) = match theory {
        BeamTheory::EulerBernoulli => (0.0, 0.0),
        BeamTheory::Timoshenko => (
            12.0 * E * s.Iz() / (s.ky() * G * s.A() * L * L),
            12.0 * E * s.Iy() / (s.kz() * G * s.A() * L * L),
        ),
    };
    // Euler-Bernoulli: Phi = 0 makes the shear strains vanish identically, so their (finite)
    // stiffness does not matter.
    let D = [
        E * s.A(),
        G * s.J(),
        E * s.Iz(),
        E * s.Iy(),
        s.ky() * G * s.A(),
        s.kz() * G * s.A(),
    ];
    let inertia = [
        rho * s.A(),
        rho * s.A(),
        rho * s.A(),
        rho * s.Ip(),
        rho * s.Iy(),
        rho * s.Iz(),
    ];
    let a = 0.339_981_043_584_856_3;
    let b = 0.861_136_311_594_052_6;
    let wa = 0.652_145_154_862_546_1;
    let wb = 0.347_854_845_137_453_9;
    let rule = [(-b, wb), (-a, wa), (a, wa), (b, wb)];
    let (mut K, mut M) = (DMatrix::zeros(12, 12), DMatrix::zeros(12, 12));
    for (g, w) in rule {
        let xi = (g + 1.0) / 2.0;
        let weight = w * L / 2.0;
        let mut N = DMatrix::<f64>::zeros(6, 12); // rows u, v, w, tx, ty, tz
        let mut B = DMatrix::<f64>::zeros(6, 12);
        // Axial and torsion: linear.
        for (row, dof) in [(0, 0), (3, 3)] {
            N[(row, dof)] = 1.0 - xi;
            N[(row, dof + 6)] = xi;
        }
        B[(0, 0)] = -1.0 / L;
        B[(0, 6)] = 1.0 / L;
        B[(1, 3)] = -1.0 / L;
        B[(1, 9)] = 1.0 / L;
        // x-y plane, dofs [v1, tz1, v2, tz2], theta_z = +v' convention.
        let (Nv, dNv, Nt, dNt) = plane_shape(xi, L, Py);
        for (k, dof) in [1, 5, 7, 11].into_iter().enumerate() {
            N[(1, dof)] = Nv[k];
            N[(5, dof)] = Nt[k];
            B[(2, dof)] = dNt[k];
            B[(4, dof)] = dNv[k] - Nt[k];
        }
        // x-z plane with psi = -theta_y playing theta: dofs [w1, -ty1, w2, -ty2].
        let (Nv, dNv, Nt, dNt) = plane_shape(xi, L, Pz);
        for (k, (dof, sign)) in [(2, 1.0), (4, -1.0), (8, 1.0), (10, -1.0)].into_iter().enumerate() {
            N[(2, dof)] = sign * Nv[k];
            N[(4, dof)] = -sign * Nt[k];
            B[(3, dof)] = -sign * dNt[k];
            B[(5, dof)] = sign * (dNv[k] - Nt[k]);
        }
        K += weight * B.transpose() * DMatrix::from_diagonal(&DVector::from_row_slice(&D)) * &B;
        M += weight * N.transpose() * DMatrix::from_diagonal(&DVector::from_row_slice(&inertia)) * &N;
    }
    (K, M)
}

#[test]
fn timoshenko_local_matrices_match_quadrature_of_shape_functions() {
    let (s, mat) = (section(), steel());
    let X = [Point3::origin(), Point3::new(L_SKEW, 0.0, 0.0)];
    for theory in THEORIES {
        let b = beam(theory, MassKind::Consistent, Vector3::y());
        let LocalMatrices { K_e, M_e } = beam2_matrices(&b, 0, X, &s, &mat).unwrap();
        let (K_q, M_q) = quadrature_matrices(L_SKEW, theory, &s, &mat);
        for (name, A, A_q) in [("K", &K_e, &K_q), ("M", &M_e, &M_q)] {
            for i in 0..12 {
                for j in 0..12 {
                    // Scale of entry (i,j) of a positive semi-definite matrix: sqrt(A_ii A_jj)
                    // (dofs mix metres and radians, so one global scale would hide errors in
                    // the small entries). Round-off of a 4-point sum of a few dozen products.
                    let scale = (A_q[(i, i)] * A_q[(j, j)]).sqrt();
                    let err = (A[(i, j)] - A_q[(i, j)]).abs();
                    assert!(
                        err <= 256.0 * EPS * scale,
                        "{theory:?} {name}[{i},{j}] = {:e}, quadrature {:e}",
                        A[(i, j)],
                        A_q[(i, j)]
                    );
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------
// 6. One-element cantilevers (exact for this element)
// ---------------------------------------------------------------------------------------

/// Tip displacement and rotation in local axes of a skewed one-element cantilever clamped at
/// node 1, under a tip force `F_loc` and moment `C_loc` given in local axes.
fn cantilever_tip(theory: BeamTheory, F_loc: Vector3<f64>, C_loc: Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let (X, v) = skew_geometry();
    let R = axes(X, v);
    let K = skew_matrices(theory, MassKind::Consistent).K_e;
    let K22 = K.view((6, 6), (6, 6)).into_owned();
    let sv = K22.singular_values();
    let cond = sv.max() / sv.min();
    // Keeps the 1e-10 tolerance of the callers honest: the solve's relative error is about
    // cond * eps, so cond < 1e5 leaves it below ~2e-11.
    assert!(cond < 1e5, "cond(K22) = {cond:.3e}");
    let mut f = DVector::zeros(6);
    f.fixed_rows_mut::<3>(0).copy_from(&(R * F_loc));
    f.fixed_rows_mut::<3>(3).copy_from(&(R * C_loc));
    let u = K22.lu().solve(&f).expect("clamped K is regular");
    (
        R.transpose() * u.fixed_rows::<3>(0),
        R.transpose() * u.fixed_rows::<3>(3),
    )
}

/// Compares the tip's [displacement; rotation] with the expected pair, relative to the whole
/// solution vector: that is what the solve's error is relative to.
fn assert_tip(what: &str, got: (Vector3<f64>, Vector3<f64>), expected: (Vector3<f64>, Vector3<f64>)) {
    let stack = |(u, th): (Vector3<f64>, Vector3<f64>)| DVector::from_iterator(6, u.iter().chain(th.iter()).copied());
    let (got, expected) = (stack(got), stack(expected));
    // Round-off of the solve, bounded by cond(K22) * eps < 2e-11 (checked in cantilever_tip),
    // plus the rotations to and from local axes.
    let tol = 1e-10 * expected.norm();
    assert!(
        (&got - &expected).norm() <= tol,
        "{what}: got {:?}, expected {:?}",
        got.as_slice(),
        expected.as_slice()
    );
}

#[test]
fn one_element_cantilever_is_exact_in_both_planes_axial_and_torsion() {
    let (s, m) = (section(), steel());
    let (E, G, A, L) = (m.E(), m.G(), s.A(), L_SKEW);
    let (P, C) = (1.3e4, 2.1e3);
    let zero = Vector3::zeros();
    for theory in THEORIES {
        let shear = |k: f64| match theory {
            BeamTheory::EulerBernoulli => 0.0,
            BeamTheory::Timoshenko => P * L / (k * G * A),
        };
        // Force along local y: bending in the x-y plane about z (Iz, ky); theta_z = +v'.
        let v = P * L.powi(3) / (3.0 * E * s.Iz()) + shear(s.ky());
        assert_tip(
            &format!("{theory:?} F_y"),
            cantilever_tip(theory, P * Vector3::y(), zero),
            (
                Vector3::new(0.0, v, 0.0),
                Vector3::new(0.0, 0.0, P * L * L / (2.0 * E * s.Iz())),
            ),
        );
        // Force along local z: the x-z plane (Iy, kz); theta_y = -w'.
        let w = P * L.powi(3) / (3.0 * E * s.Iy()) + shear(s.kz());
        assert_tip(
            &format!("{theory:?} F_z"),
            cantilever_tip(theory, P * Vector3::z(), zero),
            (
                Vector3::new(0.0, 0.0, w),
                Vector3::new(0.0, -P * L * L / (2.0 * E * s.Iy()), 0.0),
            ),
        );
        // Tip moments: pure bending, no shear force, so the same for both theories.
        assert_tip(
            &format!("{theory:?} M_z"),
            cantilever_tip(theory, zero, C * Vector3::z()),
            (
                Vector3::new(0.0, C * L * L / (2.0 * E * s.Iz()), 0.0),
                Vector3::new(0.0, 0.0, C * L / (E * s.Iz())),
            ),
        );
        assert_tip(
            &format!("{theory:?} M_y"),
            cantilever_tip(theory, zero, C * Vector3::y()),
            (
                Vector3::new(0.0, 0.0, -C * L * L / (2.0 * E * s.Iy())),
                Vector3::new(0.0, C * L / (E * s.Iy()), 0.0),
            ),
        );
        // Axial force and torque.
        assert_tip(
            &format!("{theory:?} axial"),
            cantilever_tip(theory, P * Vector3::x(), zero),
            (Vector3::new(P * L / (E * A), 0.0, 0.0), zero),
        );
        assert_tip(
            &format!("{theory:?} torque"),
            cantilever_tip(theory, zero, C * Vector3::x()),
            (zero, Vector3::new(C * L / (G * s.J()), 0.0, 0.0)),
        );
    }
}

// ---------------------------------------------------------------------------------------
// 7. Sections
// ---------------------------------------------------------------------------------------

/// Relative comparison for closed-form section values: only the round-off of a few
/// multiplications separates the constructor from the hand formula.
fn assert_rel(what: &str, got: f64, expected: f64) {
    assert!(
        (got - expected).abs() <= 16.0 * EPS * expected.abs(),
        "{what}: {got} != {expected}"
    );
}

#[test]
fn circle_and_tube_match_hand_formulas() {
    let pi = std::f64::consts::PI;
    let (d, nu) = (0.05, 0.3);
    let c = BeamSection::circle("rod", d, nu).unwrap();
    assert_rel("A", c.A(), pi * d * d / 4.0);
    assert_rel("Iy", c.Iy(), pi * d.powi(4) / 64.0);
    assert_rel("Iz", c.Iz(), pi * d.powi(4) / 64.0);
    assert_rel("J", c.J(), pi * d.powi(4) / 32.0);
    assert_rel("ky", c.ky(), 6.0 * 1.3 / (7.0 + 1.8));
    assert_rel("kz", c.kz(), c.ky());

    let (di, m) = (0.04, 0.8);
    let t = BeamSection::tube("pipe", d, di, nu).unwrap();
    assert_rel("tube A", t.A(), pi * (d * d - di * di) / 4.0);
    assert_rel("tube I", t.Iy(), pi * (d.powi(4) - di.powi(4)) / 64.0);
    assert_rel("tube J", t.J(), pi * (d.powi(4) - di.powi(4)) / 32.0);
    let q: f64 = (1.0 + m * m) * (1.0 + m * m);
    assert_rel(
        "tube k",
        t.ky(),
        6.0 * 1.3 * q / ((7.0 + 1.8) * q + (20.0 + 3.6) * m * m),
    );
    // Thin-walled limit of Cowper's hollow circle: k -> 2(1+nu)/(4+3nu) as m -> 1.
    let thin = BeamSection::tube("thin", 1.0, 1.0 - 1e-6, nu).unwrap();
    // O(1 - m) = 1e-6 from the limit.
    assert!((thin.ky() - 2.6 / 4.9).abs() < 1e-5, "thin tube k = {}", thin.ky());
    // d_inner = 0 is the solid circle.
    assert_eq!(BeamSection::tube("rod", d, 0.0, nu).unwrap(), c);
}

#[test]
fn rectangle_matches_hand_formulas_and_tabulated_torsion() {
    let (b, h, nu) = (0.08, 0.15, 0.3);
    let r = BeamSection::rectangle("rect", b, h, nu).unwrap();
    assert_rel("A", r.A(), b * h);
    assert_rel("Iy (h along z)", r.Iy(), b * h.powi(3) / 12.0);
    assert_rel("Iz (b along y)", r.Iz(), h * b.powi(3) / 12.0);
    assert_rel("ky", r.ky(), 10.0 * 1.3 / (12.0 + 3.3));
    assert_rel("kz", r.kz(), r.ky());

    // J / (a t^3) against Timoshenko & Goodier's table (3 digits) for a/t = 1, 2, 10, and
    // Roark's approximation, accurate to about 0.2%.
    for (ratio, tabulated) in [(1.0, 0.141), (2.0, 0.229), (10.0, 0.312)] {
        let J = BeamSection::rectangle("r", 1.0, ratio, nu).unwrap().J() / ratio;
        // The table has 3 significant digits: half a unit in the last place.
        assert!(
            (J - tabulated).abs() <= 0.0005,
            "a/t = {ratio}: J/(a t^3) = {J}, table {tabulated}"
        );
        let roark = 1.0 / 3.0 - 0.21 / ratio * (1.0 - 1.0 / (12.0 * ratio.powi(4)));
        // Roark's formula's own accuracy.
        assert!(
            (J - roark).abs() <= 2e-3 * roark,
            "a/t = {ratio}: J = {J}, Roark {roark}"
        );
    }
    // The square: 0.1406 b^4 (the usual 4-digit value of the series).
    let square = BeamSection::rectangle("square", 0.1, 0.1, nu).unwrap();
    assert!((square.J() / 1e-4 - 0.1406).abs() < 5e-5, "square J = {}", square.J());
    // b and h swapped: same J, Iy and Iz swapped.
    let swapped = BeamSection::rectangle("rect", h, b, nu).unwrap();
    assert_rel("J symmetric in b, h", swapped.J(), r.J());
    assert_rel("swapped Iy", swapped.Iy(), r.Iz());
    // Very thin strip: J -> a t^3 / 3 with error O(t/a).
    let strip = BeamSection::rectangle("strip", 1.0, 1e-4, nu).unwrap();
    // The relative correction is about 0.63 t/a = 6.3e-5.
    assert!(
        (strip.J() / (1e-12 / 3.0) - 1.0).abs() < 1e-4,
        "strip J = {}",
        strip.J()
    );
}

#[test]
fn section_constructors_refuse_bad_dimensions() {
    let is_section_error = |r: Result<BeamSection, PropertyError>, what: &str| match r {
        Err(PropertyError::Section { name, what: msg, .. }) => {
            assert_eq!(name, "bad");
            assert!(msg.contains(what), "message '{msg}' does not mention '{what}'");
        }
        other => panic!("expected a section error about {what}, got {other:?}"),
    };
    is_section_error(BeamSection::rectangle("bad", -0.1, 0.2, 0.3), "width");
    is_section_error(BeamSection::rectangle("bad", 0.1, 0.0, 0.3), "height");
    is_section_error(BeamSection::rectangle("bad", 0.1, f64::NAN, 0.3), "height");
    is_section_error(BeamSection::rectangle("bad", 0.1, 0.2, 0.5), "Poisson");
    is_section_error(BeamSection::circle("bad", 0.0, 0.3), "diameter");
    is_section_error(BeamSection::circle("bad", f64::INFINITY, 0.3), "diameter");
    is_section_error(BeamSection::tube("bad", 0.1, 0.1, 0.3), "inner diameter");
    is_section_error(BeamSection::tube("bad", 0.1, 0.2, 0.3), "inner diameter");
    is_section_error(BeamSection::tube("bad", 0.1, -0.01, 0.3), "inner diameter");
    is_section_error(BeamSection::tube("bad", 0.1, 0.05, -1.0), "Poisson");
}

// ---------------------------------------------------------------------------------------
// 8. Errors
// ---------------------------------------------------------------------------------------

#[test]
fn zero_length_beam_is_refused_naming_element_and_nodes() {
    let b = beam(BeamTheory::Timoshenko, MassKind::Consistent, Vector3::y());
    let X0 = Point3::new(1e3, 2.0, -3.0);
    // Coincident, and 1e-10 apart at coordinates of 1e3 (below 1e-12 * 1e3).
    for X1 in [X0, X0 + Vector3::new(0.0, 1e-10, 0.0)] {
        let err = beam2_matrices(&b, 7, [X0, X1], &section(), &steel()).unwrap_err();
        assert_eq!(
            err,
            ElementError::ZeroLength {
                element: 7,
                n1: 3,
                n2: 4
            }
        );
        let text = err.to_string();
        assert!(text.contains("element 7") && text.contains("zero length"), "{text}");
    }
    // A short but real element (1e-6 m at coordinates of 1e3) is accepted.
    assert!(beam2_matrices(&b, 7, [X0, X0 + Vector3::new(1e-6, 0.0, 0.0)], &section(), &steel()).is_ok());
}

#[test]
fn orientation_parallel_zero_or_nan_is_refused() {
    let (X, _) = skew_geometry();
    let axis = (X[1] - X[0]).normalize();
    let perp = axis.cross(&Vector3::z()).normalize();
    for v in [
        3.0 * axis,
        -axis,
        axis + 1e-12 * perp,
        Vector3::zeros(),
        Vector3::new(f64::NAN, 1.0, 0.0),
    ] {
        let b = beam(BeamTheory::EulerBernoulli, MassKind::Lumped, v);
        let err = beam2_matrices(&b, 7, X, &section(), &steel()).unwrap_err();
        assert!(
            matches!(err, ElementError::OrientationParallel { element: 7, .. }),
            "v = {v:?}: {err:?}"
        );
        let text = err.to_string();
        assert!(text.contains("element 7") && text.contains("parallel"), "{text}");
    }
    // 1e-6 rad off the axis is still a (poorly chosen but) valid orientation.
    let b = beam(BeamTheory::EulerBernoulli, MassKind::Lumped, axis + 1e-6 * perp);
    assert!(beam2_matrices(&b, 7, X, &section(), &steel()).is_ok());
}
