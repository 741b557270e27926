//! 2-node 3D beam: axial, torsion and bending in two planes, Euler-Bernoulli or Timoshenko.
//!
//! # Local axes
//!
//! $\mathbf e_x$ points from node 1 to node 2. The orientation vector $\mathbf v$
//! ([`Beam2::orientation`]) lies in the local $x$-$y$ plane:
//! $\mathbf e_z = \mathbf e_x \times \mathbf v / \lVert \mathbf e_x \times \mathbf v \rVert$,
//! $\mathbf e_y = \mathbf e_z \times \mathbf e_x$. Local dofs per node are
//! $[u, v, w, \theta_x, \theta_y, \theta_z]$ along $\mathbf e_x, \mathbf e_y, \mathbf e_z$.
//! Bending in the $x$-$y$ plane ($v$, $\theta_z = +v'$ for Euler-Bernoulli) uses $I_z$ and
//! $k_y$; bending in the $x$-$z$ plane ($w$, $\theta_y = -w'$) uses $I_y$ and $k_z$.
//!
//! # Notation
//!
//! | symbol | Rust | meaning | source |
//! |---|---|---|---|
//! | $L$ | `L` | element length $\lVert \mathbf X_2 - \mathbf X_1 \rVert$ | |
//! | $\mathbf R$ | `R` | columns $\mathbf e_x, \mathbf e_y, \mathbf e_z$ in global components | [`local_axes`] |
//! | $E, G, \rho$ | `E`, `G`, `rho` | material | [`IsotropicMaterial`] |
//! | $A, I_y, I_z, J, k_y, k_z$ | `A`, `Iy`, `Iz`, `J`, `ky`, `kz` | section | [`BeamSection`] |
//! | $I_p$ | `Ip` | polar second moment $I_y + I_z$ (torsional rotary inertia) | [`BeamSection::Ip`] |
//! | $\Phi_y$ | `Phi_y` | $12 E I_z / (k_y G A L^2)$, shear in the $x$-$y$ plane | Przemieniecki (1968) ch. 5 |
//! | $\Phi_z$ | `Phi_z` | $12 E I_y / (k_z G A L^2)$, shear in the $x$-$z$ plane | Przemieniecki (1968) ch. 5 |
//! | $\mathbf K_e^{loc}, \mathbf M_e^{loc}$ | `K_loc`, `M_loc` | 12x12 matrices in local axes | below |
//! | $\mathbf K_e, \mathbf M_e$ | `K_e`, `M_e` | the same in global axes, $\mathbf T \mathbf K_e^{loc} \mathbf T^T$ | |
//!
//! Euler-Bernoulli is the case $\Phi_y = \Phi_z = 0$ of every formula below.
//!
//! # Sources
//!
//! - Stiffness: J. S. Przemieniecki, *Theory of Matrix Structural Analysis* (McGraw-Hill,
//!   1968), ch. 5, the 3D beam with shear deformation. With one element it reproduces the
//!   exact cantilever tip deflection $PL^3/(3EI) + PL/(kGA)$.
//! - Consistent mass with rotary inertia, shear-dependent: Przemieniecki (1968) ch. 11 and
//!   J. S. Archer, "Consistent matrix formulations for structural analysis using
//!   finite-element techniques", AIAA J. 3 (1965) 1910–1918. Our coefficients are re-derived
//!   (see [`bending_mass_translational`]) and checked against quadrature of the shape
//!   functions in `tests/unit/beam2.rs::timoshenko_local_matrices_match_quadrature_of_shape_functions`.
//! - Lumped mass: the HRZ diagonal scaling of E. Hinton, T. Rock, O. C. Zienkiewicz, "A note
//!   on mass lumping and related processes in the finite element method", Earthquake Eng.
//!   Struct. Dyn. 4 (1976) 245–249; see also Cook, Malkus, Plesha & Witt, *Concepts and
//!   Applications of Finite Element Analysis*, 4th ed. (2002) ch. 11, where it gives the
//!   Euler-Bernoulli rotational entry $\rho A L^3/78$.

#![allow(non_snake_case)]

use super::{Beam2, BeamTheory, LocalMatrices, MassKind};
use crate::error::ElementError;
use crate::property::IsotropicMaterial;
use crate::section::BeamSection;
use nalgebra::{DMatrix, Matrix3, Matrix4, Point3, Rotation3, SMatrix, Vector3};

type Matrix12 = SMatrix<f64, 12, 12>;

/// Relative length below which the two nodes count as coincident, against the coordinates'
/// magnitude: about 5000 ulps of the coordinates, far below any meaningful element.
const ZERO_LENGTH_RTOL: f64 = 1e-12;
/// $\lVert \mathbf e_x \times \mathbf v \rVert / \lVert \mathbf v \rVert$ below which the
/// orientation vector counts as parallel to the axis (angle below 1e-9 rad: the local $y$
/// axis would be fixed by round-off, not by the user).
const PARALLEL_RTOL: f64 = 1e-9;

/// Local dofs of bending in the $x$-$y$ plane: $[v_1, \theta_{z1}, v_2, \theta_{z2}]$.
const PLANE_XY: [usize; 4] = [1, 5, 7, 11];
/// Local dofs of bending in the $x$-$z$ plane: $[w_1, \theta_{y1}, w_2, \theta_{y2}]$.
const PLANE_XZ: [usize; 4] = [2, 4, 8, 10];
/// Sign that maps the $x$-$y$ plane matrices to the $x$-$z$ plane: $\theta_y = -w'$ where
/// $\theta_z = +v'$, so the rotation dofs change sign.
const XZ_SIGN: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// Stiffness $\mathbf K_e$ and mass $\mathbf M_e$ (12x12, global axes, dofs
/// $[u_{1x}, u_{1y}, u_{1z}, \theta_{1x}, \theta_{1y}, \theta_{1z}, u_{2x}, \dots]$) of a
/// 2-node beam, Przemieniecki (1968) ch. 5 (stiffness) and ch. 11 (consistent mass); see the
/// module docs for the axes and sources.
///
/// `element` is the element's index in the model, used only in errors.
///
/// # Errors
/// - [`ElementError::ZeroLength`] if $L < 10^{-12}\max(1, \lVert\mathbf X_1\rVert,
///   \lVert\mathbf X_2\rVert)$ (also if a coordinate is not finite: there is no length then).
/// - [`ElementError::OrientationParallel`] if the orientation vector is zero, not finite, or
///   within 1e-9 rad of the axis.
pub fn beam2_matrices(
    beam: &Beam2,
    element: usize,
    X: [Point3<f64>; 2],
    section: &BeamSection,
    material: &IsotropicMaterial,
) -> Result<LocalMatrices, ElementError> {
    let (L, R) = local_axes(beam, element, X)?;
    let (Phi_y, Phi_z) = shear_parameters(beam.theory, L, section, material);

    let K_loc = local_stiffness(L, Phi_y, Phi_z, section, material);
    let M_loc = match beam.mass {
        MassKind::Consistent => local_mass_consistent(L, Phi_y, Phi_z, section, material),
        MassKind::Lumped => local_mass_lumped(L, Phi_y, Phi_z, section, material),
    };
    Ok(LocalMatrices {
        K_e: to_global(R.matrix(), &K_loc),
        M_e: to_global(R.matrix(), &M_loc),
    })
}

/// Length $L$ and local axes $\mathbf R = [\mathbf e_x\ \mathbf e_y\ \mathbf e_z]$ (columns in
/// global components, so $\mathbf a = \mathbf R \mathbf a^{loc}$) of a beam with reference
/// coordinates `X`.
///
/// $\mathbf e_x = (\mathbf X_2 - \mathbf X_1)/L$,
/// $\mathbf e_z = \mathbf e_x \times \mathbf v / \lVert \mathbf e_x \times \mathbf v \rVert$,
/// $\mathbf e_y = \mathbf e_z \times \mathbf e_x$.
///
/// # Errors
/// As [`beam2_matrices`].
pub fn local_axes(beam: &Beam2, element: usize, X: [Point3<f64>; 2]) -> Result<(f64, Rotation3<f64>), ElementError> {
    let d = X[1] - X[0];
    let L = d.norm();
    let scale = 1.0_f64.max(X[0].coords.norm()).max(X[1].coords.norm());
    // A non-finite coordinate gives a non-finite length: refused too, rather than NaN matrices.
    if !L.is_finite() || L < ZERO_LENGTH_RTOL * scale {
        return Err(ElementError::ZeroLength {
            element,
            n1: u64::from(beam.nodes[0].0),
            n2: u64::from(beam.nodes[1].0),
        });
    }
    let e_x = d / L;
    let v = beam.orientation;
    let parallel = || ElementError::OrientationParallel {
        element,
        v: [v.x, v.y, v.z],
    };
    let v_norm = v.norm();
    if !(v_norm > 0.0 && v_norm.is_finite()) {
        return Err(parallel());
    }
    let z = e_x.cross(&v);
    let z_norm = z.norm();
    if z_norm < PARALLEL_RTOL * v_norm {
        return Err(parallel());
    }
    let e_z: Vector3<f64> = z / z_norm;
    let e_y = e_z.cross(&e_x);
    // Orthonormal by construction (e_y is the cross product of two orthogonal unit vectors).
    let R = Rotation3::from_matrix_unchecked(Matrix3::from_columns(&[e_x, e_y, e_z]));
    Ok((L, R))
}

/// Shear parameters $(\Phi_y, \Phi_z)$ of Przemieniecki (1968) ch. 5:
/// $\Phi_y = 12 E I_z / (k_y G A L^2)$ for bending in the $x$-$y$ plane (shear along $y$),
/// $\Phi_z = 12 E I_y / (k_z G A L^2)$ for the $x$-$z$ plane; both zero for Euler-Bernoulli.
fn shear_parameters(theory: BeamTheory, L: f64, s: &BeamSection, m: &IsotropicMaterial) -> (f64, f64) {
    match theory {
        BeamTheory::EulerBernoulli => (0.0, 0.0),
        BeamTheory::Timoshenko => {
            let GA_L2 = m.G() * s.A() * L * L;
            (
                12.0 * m.E() * s.Iz() / (s.ky() * GA_L2),
                12.0 * m.E() * s.Iy() / (s.kz() * GA_L2),
            )
        }
    }
}

/// Bending stiffness of one plane in the dofs $[v_1, \theta_1, v_2, \theta_2]$ with
/// $\theta = +v'$ (the $x$-$y$ plane convention), Przemieniecki (1968) ch. 5:
///
/// ```text
///   EI / ((1 + Phi) L^3) * [  12      6L          -12     6L
///                             6L    (4 + Phi)L^2  -6L   (2 - Phi)L^2
///                            -12     -6L           12    -6L
///                             6L    (2 - Phi)L^2  -6L   (4 + Phi)L^2 ]
/// ```
pub fn bending_stiffness(EI: f64, L: f64, Phi: f64) -> Matrix4<f64> {
    let c = EI / ((1.0 + Phi) * L * L * L);
    let (a, b) = ((4.0 + Phi) * L * L, (2.0 - Phi) * L * L);
    let s = 6.0 * L;
    c * Matrix4::new(
        12.0, s, -12.0, s, //
        s, a, -s, b, //
        -12.0, -s, 12.0, -s, //
        s, b, -s, a,
    )
}

/// Translational part of the consistent bending mass of one plane, dofs and convention as
/// [`bending_stiffness`], divided by $\rho A L$ (Przemieniecki (1968) ch. 11; Archer 1965):
///
/// ```text
///   1 / (1 + Phi)^2 * [ m1    m2 L     m3    -m4 L
///                             m5 L^2   m4 L  -m6 L^2
///                                      m1    -m2 L
///                       sym.                  m5 L^2 ]
/// ```
///
/// with
/// $m_1 = \tfrac{13}{35} + \tfrac{7}{10}\Phi + \tfrac13\Phi^2$,
/// $m_2 = \tfrac{11}{210} + \tfrac{11}{120}\Phi + \tfrac1{24}\Phi^2$,
/// $m_3 = \tfrac{9}{70} + \tfrac{3}{10}\Phi + \tfrac16\Phi^2$,
/// $m_4 = \tfrac{13}{420} + \tfrac{3}{40}\Phi + \tfrac1{24}\Phi^2$,
/// $m_5 = \tfrac{1}{105} + \tfrac{1}{60}\Phi + \tfrac1{120}\Phi^2$,
/// $m_6 = \tfrac{1}{140} + \tfrac{1}{60}\Phi + \tfrac1{120}\Phi^2$.
/// For $\Phi = 0$ this is the classic $\frac{1}{420}[156, 22L, 54, -13L; \dots]$.
///
/// # Derivation
/// $\int_0^L \mathbf N_v^T \mathbf N_v\ dx / L$ with the interdependent (exact static)
/// Timoshenko shape functions of Friedman & Kosmatka, "An improved two-node Timoshenko beam
/// finite element", Comput. Struct. 47 (1993) 473–481, with $\xi = x/L$:
/// $N_{v1} = (2\xi^3 - 3\xi^2 - \Phi\xi + 1 + \Phi)/(1+\Phi)$,
/// $N_{v2} = L(\xi^3 - (2+\Phi/2)\xi^2 + (1+\Phi/2)\xi)/(1+\Phi)$,
/// $N_{v3} = -(2\xi^3 - 3\xi^2 - \Phi\xi)/(1+\Phi)$,
/// $N_{v4} = L(\xi^3 - (1-\Phi/2)\xi^2 - \Phi\xi/2)/(1+\Phi)$.
/// Integrated symbolically (sympy); the same integral by Gauss quadrature is
/// `tests/unit/beam2.rs::timoshenko_local_matrices_match_quadrature_of_shape_functions`.
pub fn bending_mass_translational(L: f64, Phi: f64) -> Matrix4<f64> {
    let (P, P2) = (Phi, Phi * Phi);
    let m1 = 13.0 / 35.0 + 7.0 / 10.0 * P + P2 / 3.0;
    let m2 = (11.0 / 210.0 + 11.0 / 120.0 * P + P2 / 24.0) * L;
    let m3 = 9.0 / 70.0 + 3.0 / 10.0 * P + P2 / 6.0;
    let m4 = (13.0 / 420.0 + 3.0 / 40.0 * P + P2 / 24.0) * L;
    let m5 = (1.0 / 105.0 + P / 60.0 + P2 / 120.0) * L * L;
    let m6 = (1.0 / 140.0 + P / 60.0 + P2 / 120.0) * L * L;
    let c = 1.0 / ((1.0 + P) * (1.0 + P));
    c * Matrix4::new(
        m1, m2, m3, -m4, //
        m2, m5, m4, -m6, //
        m3, m4, m1, -m2, //
        -m4, -m6, -m2, m5,
    )
}

/// Rotary-inertia part of the consistent bending mass of one plane, dofs and convention as
/// [`bending_stiffness`], divided by $\rho I$ (Przemieniecki (1968) ch. 11; Archer 1965):
///
/// ```text
///   1 / ((1 + Phi)^2 L) * [ 6/5   r1 L     -6/5   r1 L
///                                 r2 L^2   -r1 L  r3 L^2
///                                           6/5  -r1 L
///                           sym.                  r2 L^2 ]
/// ```
///
/// with
/// $r_1 = \tfrac1{10} - \tfrac12\Phi$, $r_2 = \tfrac{2}{15} + \tfrac16\Phi + \tfrac13\Phi^2$,
/// $r_3 = -\tfrac1{30} - \tfrac16\Phi + \tfrac16\Phi^2$.
/// For $\Phi = 0$ this is the classic $\frac{1}{30L}[36, 3L, -36, 3L; \dots]$.
///
/// # Derivation
/// $L\int_0^L \mathbf N_\theta^T \mathbf N_\theta\ dx$ with the rotation shape functions of
/// Friedman & Kosmatka (1993):
/// $N_{\theta1} = 6(\xi^2 - \xi)/((1+\Phi)L)$,
/// $N_{\theta2} = (3\xi^2 - (4+\Phi)\xi + 1 + \Phi)/(1+\Phi)$,
/// $N_{\theta3} = -N_{\theta1}$,
/// $N_{\theta4} = (3\xi^2 - (2-\Phi)\xi)/(1+\Phi)$; checked as for
/// [`bending_mass_translational`].
pub fn bending_mass_rotary(L: f64, Phi: f64) -> Matrix4<f64> {
    let (P, P2) = (Phi, Phi * Phi);
    let r0 = 6.0 / 5.0;
    let r1 = (1.0 / 10.0 - P / 2.0) * L;
    let r2 = (2.0 / 15.0 + P / 6.0 + P2 / 3.0) * L * L;
    let r3 = (-1.0 / 30.0 - P / 6.0 + P2 / 6.0) * L * L;
    let c = 1.0 / ((1.0 + P) * (1.0 + P) * L);
    c * Matrix4::new(
        r0, r1, -r0, r1, //
        r1, r2, -r1, r3, //
        -r0, -r1, r0, -r1, //
        r1, r3, -r1, r2,
    )
}

/// Adds `c * B` (a 2-node bar matrix $[1, -1; -1, 1]$ or $[2, 1; 1, 2]$ pattern) on dofs
/// `(i, i + 6)`.
fn add_bar(M: &mut Matrix12, i: usize, B: [[f64; 2]; 2]) {
    let idx = [i, i + 6];
    for a in 0..2 {
        for b in 0..2 {
            M[(idx[a], idx[b])] += B[a][b];
        }
    }
}

/// Adds a plane matrix in the $x$-$y$ convention to the local 12x12 matrix: as is on the
/// $x$-$y$ dofs (`xz = false`), or with the rotation dofs' sign flipped on the $x$-$z$ dofs,
/// since there $\theta_y = -w'$.
fn add_plane(M: &mut Matrix12, P: &Matrix4<f64>, xz: bool) {
    let (idx, sign) = if xz { (PLANE_XZ, XZ_SIGN) } else { (PLANE_XY, [1.0; 4]) };
    for a in 0..4 {
        for b in 0..4 {
            M[(idx[a], idx[b])] += sign[a] * sign[b] * P[(a, b)];
        }
    }
}

/// Local stiffness: axial $\frac{EA}{L}[1,-1;-1,1]$, torsion $\frac{GJ}{L}[1,-1;-1,1]$, and
/// [`bending_stiffness`] in both planes (Przemieniecki (1968) ch. 5).
fn local_stiffness(L: f64, Phi_y: f64, Phi_z: f64, s: &BeamSection, m: &IsotropicMaterial) -> Matrix12 {
    let mut K = Matrix12::zeros();
    let (ka, kt) = (m.E() * s.A() / L, m.G() * s.J() / L);
    add_bar(&mut K, 0, [[ka, -ka], [-ka, ka]]);
    add_bar(&mut K, 3, [[kt, -kt], [-kt, kt]]);
    add_plane(&mut K, &bending_stiffness(m.E() * s.Iz(), L, Phi_y), false);
    add_plane(&mut K, &bending_stiffness(m.E() * s.Iy(), L, Phi_z), true);
    K
}

/// Local consistent mass: axial $\frac{\rho A L}{6}[2, 1; 1, 2]$, torsion
/// $\frac{\rho I_p L}{6}[2, 1; 1, 2]$, and in each plane $\rho A L$ [`bending_mass_translational`]
/// $+\ \rho I$ [`bending_mass_rotary`] with $I = I_z$ for the $x$-$y$ plane and $I_y$ for the
/// $x$-$z$ plane (Przemieniecki (1968) ch. 11).
fn local_mass_consistent(L: f64, Phi_y: f64, Phi_z: f64, s: &BeamSection, m: &IsotropicMaterial) -> Matrix12 {
    let rho = m.rho();
    let mut M = Matrix12::zeros();
    let (ma, mt) = (rho * s.A() * L / 6.0, rho * s.Ip() * L / 6.0);
    add_bar(&mut M, 0, [[2.0 * ma, ma], [ma, 2.0 * ma]]);
    add_bar(&mut M, 3, [[2.0 * mt, mt], [mt, 2.0 * mt]]);
    let plane =
        |I: f64, Phi: f64| rho * s.A() * L * bending_mass_translational(L, Phi) + rho * I * bending_mass_rotary(L, Phi);
    add_plane(&mut M, &plane(s.Iz(), Phi_y), false);
    add_plane(&mut M, &plane(s.Iy(), Phi_z), true);
    M
}

/// Local lumped mass, diagonal: $\rho A L/2$ on each translation, $\rho I_p L/2$ on each
/// torsional rotation, and on each bending rotation the HRZ value (Hinton, Rock & Zienkiewicz
/// 1976): the consistent diagonal entry scaled by the factor that makes the translational
/// diagonal sum to $\rho A L$,
/// $$m_\theta = \frac{\rho A L}{2}\frac{M_{\theta\theta}^{cons}}{M_{vv}^{cons}}.$$
/// For Euler-Bernoulli without rotary inertia this is $\rho A L^3 / 78$ (Cook et al. 2002
/// ch. 11); with it and with shear the same rule uses the full consistent diagonal, so the
/// value stays positive and follows the theory. In global axes each node's rotational 3x3
/// block is $\mathbf R \mathrm{diag}(m_{\theta x}, m_{\theta y}, m_{\theta z})\mathbf R^T$,
/// which is diagonal only when the beam is aligned with the global axes; translations stay
/// diagonal, and there is no coupling between nodes or between translations and rotations.
fn local_mass_lumped(L: f64, Phi_y: f64, Phi_z: f64, s: &BeamSection, m: &IsotropicMaterial) -> Matrix12 {
    let half = m.rho() * s.A() * L / 2.0;
    // Ratio of consistent diagonal entries, rotation over translation. Computed without rho so
    // that a massless material (rho = 0) gives zeros, not 0/0.
    let hrz_ratio = |I: f64, Phi: f64| {
        let C = s.A() * L * bending_mass_translational(L, Phi) + I * bending_mass_rotary(L, Phi);
        C[(1, 1)] / C[(0, 0)]
    };
    let m_theta_z = half * hrz_ratio(s.Iz(), Phi_y);
    let m_theta_y = half * hrz_ratio(s.Iy(), Phi_z);
    let m_theta_x = m.rho() * s.Ip() * L / 2.0;
    let node = [half, half, half, m_theta_x, m_theta_y, m_theta_z];
    let mut M = Matrix12::zeros();
    for (i, value) in node.iter().enumerate() {
        M[(i, i)] = *value;
        M[(i + 6, i + 6)] = *value;
    }
    M
}

/// $\mathbf T \mathbf A^{loc} \mathbf T^T$ with $\mathbf T = \mathrm{diag}(\mathbf R, \mathbf R,
/// \mathbf R, \mathbf R)$, computed 3x3 block by block.
fn to_global(R: &Matrix3<f64>, A_loc: &Matrix12) -> DMatrix<f64> {
    let mut A = DMatrix::zeros(12, 12);
    for I in 0..4 {
        for J in 0..4 {
            let block = A_loc.fixed_view::<3, 3>(3 * I, 3 * J);
            let rotated = R * block * R.transpose();
            A.fixed_view_mut::<3, 3>(3 * I, 3 * J).copy_from(&rotated);
        }
    }
    A
}

/// Geometric (initial-stress) bending stiffness of one plane under a unit axial force, dofs and
/// convention as [`bending_stiffness`], from the cubic Hermite shapes (McGuire, Gallagher &
/// Ziemian, *Matrix Structural Analysis*, 2nd ed. (2000), (9.18); Przemieniecki (1968), the
/// chapter on stability analysis):
///
/// ```text
///   1 / (30 L) * [  36    3L    -36    3L
///                   3L   4L^2   -3L   -L^2
///                  -36   -3L     36   -3L
///                   3L   -L^2   -3L   4L^2 ]
/// ```
///
/// $= \int_0^L \mathbf N_v'^T \mathbf N_v'\, dx$, the second-order strain $\tfrac12 v'^2$ under
/// a unit force.
pub fn bending_geometric_stiffness(L: f64) -> Matrix4<f64> {
    let c = 1.0 / (30.0 * L);
    let (s, a, b) = (3.0 * L, 4.0 * L * L, -L * L);
    c * Matrix4::new(
        36.0, s, -36.0, s, //
        s, a, -s, b, //
        -36.0, -s, 36.0, -s, //
        s, b, -s, a,
    )
}

/// Geometric stiffness $\mathbf K_G^e$ (12x12, global axes, dofs as [`beam2_matrices`]) of a
/// beam carrying the axial force `N` (tension positive): McGuire, Gallagher & Ziemian (2000)
/// (9.18) with the axial force only (the terms of the end moments are left out), i.e. the
/// energy $\tfrac12\int_0^L N\,(u'^2 + v'^2 + w'^2 + \tfrac{I_p}{A}\theta_x'^2)\,dx$ of the
/// second-order Green-Lagrange strain:
/// - axial: $\frac{N}{L}[1, -1; -1, 1]$ on $u$;
/// - torsion: $\frac{N I_p}{A L}[1, -1; -1, 1]$ on $\theta_x$ (a fibre at distance $r$ from
///   the axis moves $r\theta_x$ sideways; $\int_A r^2 dA = I_p$);
/// - bending in both planes: $N$ [`bending_geometric_stiffness`].
///
/// The Timoshenko element uses the same matrix: its cubic Hermite shapes are the
/// Euler-Bernoulli ones, not the shear-dependent shapes of its stiffness. With the shear
/// flexibility in the stiffness this is the energy of Engesser's column, and the buckling load
/// converges to $P_E/(1 + P_E/(kGA))$ to about $10^{-7}$ (Timoshenko & Gere, *Theory of
/// Elastic Stability*, 2nd ed. (1961) ch. 2, the effect of shear on the critical load):
/// `tests/unit/geometric.rs::timoshenko_beam_buckling_converges_to_engessers_shear_reduced_load`.
///
/// # Errors
/// As [`beam2_matrices`] (zero length, orientation along the axis).
pub fn beam2_geometric_stiffness(
    beam: &Beam2,
    element: usize,
    X: [Point3<f64>; 2],
    section: &BeamSection,
    N: f64,
) -> Result<DMatrix<f64>, ElementError> {
    let (L, R) = local_axes(beam, element, X)?;
    let mut K_loc = Matrix12::zeros();
    let (ka, kt) = (N / L, N * section.Ip() / (section.A() * L));
    add_bar(&mut K_loc, 0, [[ka, -ka], [-ka, ka]]);
    add_bar(&mut K_loc, 3, [[kt, -kt], [-kt, kt]]);
    let bending = N * bending_geometric_stiffness(L);
    add_plane(&mut K_loc, &bending, false);
    add_plane(&mut K_loc, &bending, true);
    Ok(to_global(R.matrix(), &K_loc))
}

/// Axial force $N = \frac{EA}{L}(\mathbf u_2 - \mathbf u_1)\cdot\mathbf e_x$ of a beam of
/// axial stiffness `EA` with element displacements `u_e` (12 values, global axes, dofs as
/// [`beam2_matrices`]): the linear stress resultant that [`beam2_geometric_stiffness`] takes.
/// From the end displacements alone, not from the local stiffness as
/// [`beam2_section_forces`] (equal to round-off).
///
/// # Errors
/// As [`beam2_matrices`].
///
/// # Panics
/// If `u_e` does not have 12 entries (a caller's bug, not input).
pub fn beam2_axial_force(
    beam: &Beam2,
    element: usize,
    X: [Point3<f64>; 2],
    EA: f64,
    u_e: &[f64],
) -> Result<f64, ElementError> {
    assert_eq!(u_e.len(), 12, "a beam's element displacements have 12 entries");
    let (L, R) = local_axes(beam, element, X)?;
    let e_x = R.matrix().column(0).into_owned();
    let du = Vector3::new(u_e[6] - u_e[0], u_e[7] - u_e[1], u_e[8] - u_e[2]);
    Ok(EA / L * e_x.dot(&du))
}

/// Section forces $[N, V_y, V_z, T, M_y, M_z]$ (local axes) at both ends of a beam with
/// element displacements `u_e` (12 values, global axes, dofs as [`beam2_matrices`]), minus
/// the equivalent nodal loads `load_e` of a load along the element when given (global axes):
/// with $\mathbf f = \mathbf K_e^{loc}\mathbf T^T(\mathbf u_e) - \mathbf T^T\mathbf f_{load}$,
/// $\mathbf s(0) = -\mathbf f_{1..6}$ and $\mathbf s(L) = \mathbf f_{7..12}$, the internal
/// force and moment on the cut face with outward normal $+\mathbf e_x$ (tension and the
/// right-hand moments about $\mathbf e_y$, $\mathbf e_z$ positive). The element is nodally
/// exact for end loads and, with consistent equivalent loads, for uniform ones
/// (Przemieniecki 1968 ch. 5), so these are the exact section forces of a mesh whose nodal
/// displacements are exact.
///
/// # Errors
/// As [`beam2_matrices`].
///
/// # Panics
/// If `u_e` or `load_e` does not have 12 entries (a caller's bug, not input).
pub fn beam2_section_forces(
    beam: &Beam2,
    element: usize,
    X: [Point3<f64>; 2],
    section: &BeamSection,
    material: &IsotropicMaterial,
    u_e: &[f64],
    load_e: Option<&[f64]>,
) -> Result<[[f64; 6]; 2], ElementError> {
    assert_eq!(u_e.len(), 12, "a beam's element displacements have 12 entries");
    let (L, R) = local_axes(beam, element, X)?;
    let (Phi_y, Phi_z) = shear_parameters(beam.theory, L, section, material);
    let K_loc = local_stiffness(L, Phi_y, Phi_z, section, material);
    let to_local = |v: &[f64]| {
        let mut w = nalgebra::SVector::<f64, 12>::zeros();
        for block in 0..4 {
            let g = Vector3::new(v[3 * block], v[3 * block + 1], v[3 * block + 2]);
            w.fixed_rows_mut::<3>(3 * block)
                .copy_from(&(R.matrix().transpose() * g));
        }
        w
    };
    let mut f = K_loc * to_local(u_e);
    if let Some(load) = load_e {
        assert_eq!(load.len(), 12, "a beam's element loads have 12 entries");
        f -= to_local(load);
    }
    let mut s = [[0.0; 6]; 2];
    for k in 0..6 {
        s[0][k] = -f[k];
        s[1][k] = f[6 + k];
    }
    Ok(s)
}
