//! The isoparametric kernel shared by all solid elements: stiffness
//! $\mathbf K_e = \int_{V_e} \mathbf B^T \mathbf D \mathbf B \, dV$ and mass
//! $\mathbf M_e = \int_{V_e} \rho\, \mathbf N^T \mathbf N \, dV$ by quadrature on the reference
//! element (Hughes, *The Finite Element Method*, 2000, §3.8-3.9; Zienkiewicz, Taylor & Zhu, 7th
//! ed., ch. 6).
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\boldsymbol\xi = (\xi, \eta, \zeta)$ | `xi` | reference coordinates |
//! | $N_a$, $\partial N_a / \partial \boldsymbol\xi$ | `N[a]`, `dN[a]` | shape function of node $a$ and its reference gradient |
//! | $\mathbf J$ | `J` | $J_{ij} = \partial x_i / \partial \xi_j = \sum_a X_{a,i}\, \partial N_a/\partial\xi_j$ |
//! | $\mathbf g_a$ | `g[a]` | $\partial N_a / \partial \mathbf x = \mathbf J^{-T} \partial N_a/\partial\boldsymbol\xi$ |
//! | $\mathbf D$ | `D` | isotropic elasticity, Voigt order $[xx, yy, zz, xy, yz, zx]$, engineering shear strains |
//! | $\lambda, \mu$ | `lambda`, `mu` | Lamé constants, $\mu = G$ |
//!
//! Local dofs are ordered node by node, $[u_x, u_y, u_z]$ per node (the element's
//! [`super::Element::node_dofs`] is [`super::DOFS_3`]).

#![allow(non_snake_case)]

use super::{hex20, hex8, tet10, tet4, wedge6, LocalMatrices, MassKind};
use crate::error::ElementError;
use crate::mesh::{CellKind, NodeId};
use crate::property::{IsotropicMaterial, MaterialId};
use crate::quadrature::Rule;
use nalgebra::{DMatrix, Matrix3, Matrix6, Point3, Vector3};
use serde::{Deserialize, Serialize};

/// A solid element: its nodes (in the ordering of its kind's module), material and mass
/// kind. The kind is the [`super::Element`] variant that holds it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Solid {
    pub nodes: Vec<NodeId>,
    pub material: MaterialId,
    pub mass: MassKind,
}

/// The solid element kinds, with their shape functions, node orderings and quadrature rules.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SolidKind {
    /// See [`tet4`].
    Tet4,
    /// See [`tet10`].
    Tet10,
    /// See [`hex8`].
    Hex8,
    /// See [`hex20`].
    Hex20,
    /// See [`wedge6`].
    Wedge6,
}

impl SolidKind {
    /// All kinds, for tests and tables.
    pub const ALL: [SolidKind; 5] = [
        SolidKind::Tet4,
        SolidKind::Tet10,
        SolidKind::Hex8,
        SolidKind::Hex20,
        SolidKind::Wedge6,
    ];

    /// The solid kind of a mesh cell kind, or `None` for lines and faces.
    pub fn from_cell_kind(kind: CellKind) -> Option<SolidKind> {
        match kind {
            CellKind::Tet4 => Some(SolidKind::Tet4),
            CellKind::Tet10 => Some(SolidKind::Tet10),
            CellKind::Hex8 => Some(SolidKind::Hex8),
            CellKind::Hex20 => Some(SolidKind::Hex20),
            CellKind::Wedge6 => Some(SolidKind::Wedge6),
            CellKind::Line2 | CellKind::Tri3 | CellKind::Quad4 | CellKind::Tri6 | CellKind::Quad8 => None,
        }
    }

    /// The mesh cell kind with the same topology and node ordering.
    pub fn cell_kind(self) -> CellKind {
        match self {
            SolidKind::Tet4 => CellKind::Tet4,
            SolidKind::Tet10 => CellKind::Tet10,
            SolidKind::Hex8 => CellKind::Hex8,
            SolidKind::Hex20 => CellKind::Hex20,
            SolidKind::Wedge6 => CellKind::Wedge6,
        }
    }

    /// A short name for messages ("hex20").
    pub fn name(self) -> &'static str {
        match self {
            SolidKind::Tet4 => "tet4",
            SolidKind::Tet10 => "tet10",
            SolidKind::Hex8 => "hex8",
            SolidKind::Hex20 => "hex20",
            SolidKind::Wedge6 => "wedge6",
        }
    }

    /// Number of nodes.
    pub fn node_count(self) -> usize {
        self.reference_nodes().len()
    }

    /// Reference coordinates of the nodes, in node order.
    pub fn reference_nodes(self) -> &'static [[f64; 3]] {
        match self {
            SolidKind::Tet4 => &tet4::REFERENCE_NODES,
            SolidKind::Tet10 => &tet10::REFERENCE_NODES,
            SolidKind::Hex8 => &hex8::REFERENCE_NODES,
            SolidKind::Hex20 => &hex20::REFERENCE_NODES,
            SolidKind::Wedge6 => &wedge6::REFERENCE_NODES,
        }
    }

    /// Faces as local node lists: corners anticlockwise seen from outside, then (for
    /// quadratic kinds) the edge nodes of the face's edges in corner order. The length says
    /// the face kind: 3 tri3, 4 quad4, 6 tri6, 8 quad8.
    pub fn faces(self) -> &'static [&'static [usize]] {
        match self {
            SolidKind::Tet4 => &tet4::FACES,
            SolidKind::Tet10 => &tet10::FACES,
            SolidKind::Hex8 => &hex8::FACES,
            SolidKind::Hex20 => &hex20::FACES,
            SolidKind::Wedge6 => &wedge6::FACES,
        }
    }

    /// Shape functions and reference derivatives at `xi`; `N` and `dN` must have
    /// [`SolidKind::node_count`] entries.
    pub fn shape_functions(self, xi: &[f64; 3], N: &mut [f64], dN: &mut [[f64; 3]]) {
        match self {
            SolidKind::Tet4 => tet4::shape_functions(xi, N, dN),
            SolidKind::Tet10 => tet10::shape_functions(xi, N, dN),
            SolidKind::Hex8 => hex8::shape_functions(xi, N, dN),
            SolidKind::Hex20 => hex20::shape_functions(xi, N, dN),
            SolidKind::Wedge6 => wedge6::shape_functions(xi, N, dN),
        }
    }

    /// The quadrature rule for the stiffness.
    pub fn stiffness_rule(self) -> &'static Rule<3> {
        match self {
            SolidKind::Tet4 => tet4::stiffness_rule(),
            SolidKind::Tet10 => tet10::stiffness_rule(),
            SolidKind::Hex8 => hex8::stiffness_rule(),
            SolidKind::Hex20 => hex20::stiffness_rule(),
            SolidKind::Wedge6 => wedge6::stiffness_rule(),
        }
    }

    /// The quadrature rule for the mass.
    pub fn mass_rule(self) -> &'static Rule<3> {
        match self {
            SolidKind::Tet4 => tet4::mass_rule(),
            SolidKind::Tet10 => tet10::mass_rule(),
            SolidKind::Hex8 => hex8::mass_rule(),
            SolidKind::Hex20 => hex20::mass_rule(),
            SolidKind::Wedge6 => wedge6::mass_rule(),
        }
    }
}

/// Isotropic elasticity matrix $\mathbf D$ (6 x 6, Voigt order $[xx, yy, zz, xy, yz, zx]$,
/// engineering shear strains $\gamma_{xy} = 2\varepsilon_{xy}$):
/// $\mathbf D = \lambda\, \mathbf m \mathbf m^T + \mu\, \mathrm{diag}(2, 2, 2, 1, 1, 1)$ with
/// $\mathbf m = [1, 1, 1, 0, 0, 0]^T$, $\lambda = E\nu / ((1 + \nu)(1 - 2\nu))$, $\mu = G$
/// (Hughes 2000, (2.7.32)).
pub fn elasticity_matrix(material: &IsotropicMaterial) -> Matrix6<f64> {
    let (lambda, mu) = lame(material);
    let mut D = Matrix6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            D[(i, j)] = lambda;
        }
        D[(i, i)] += 2.0 * mu;
        D[(i + 3, i + 3)] = mu;
    }
    D
}

/// Lamé constants $(\lambda, \mu)$.
fn lame(material: &IsotropicMaterial) -> (f64, f64) {
    let (E, nu) = (material.E(), material.nu());
    (E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), material.G())
}

/// Strain-displacement matrix $\mathbf B$ (6 x 3n) from the physical gradients
/// $\mathbf g_a = \partial N_a / \partial \mathbf x$: $\boldsymbol\varepsilon = \mathbf B \mathbf u_e$
/// in the Voigt order of [`elasticity_matrix`] (Hughes 2000, (2.8.9)). The kernel does not build
/// it (see [`stiffness`]); it is here for stress recovery and as an independent check.
pub fn strain_displacement(g: &[Vector3<f64>]) -> DMatrix<f64> {
    let mut B = DMatrix::zeros(6, 3 * g.len());
    for (a, ga) in g.iter().enumerate() {
        let c = 3 * a;
        B[(0, c)] = ga.x;
        B[(1, c + 1)] = ga.y;
        B[(2, c + 2)] = ga.z;
        B[(3, c)] = ga.y;
        B[(3, c + 1)] = ga.x;
        B[(4, c + 1)] = ga.z;
        B[(4, c + 2)] = ga.y;
        B[(5, c)] = ga.z;
        B[(5, c + 2)] = ga.x;
    }
    B
}

/// Shape functions, physical gradients and $\det\mathbf J$ of one element at one point.
#[derive(Clone, Debug)]
pub struct PointValues {
    pub N: Vec<f64>,
    /// $\mathbf g_a = \partial N_a / \partial \mathbf x$.
    pub g: Vec<Vector3<f64>>,
    pub det_J: f64,
}

/// Values at reference point `xi` of the element with reference coordinates `X_e`.
///
/// Returns [`ElementError::NonPositiveJacobian`] naming `element` and `point` (the caller's
/// numbering of `xi`) when $\det\mathbf J$ is not above $10^{-12}\,h^3$, $h$ the largest node
/// distance from node 0: an inverted element, or a degenerate one whose volume is at round-off
/// level.
pub fn point_values(
    kind: SolidKind,
    element: usize,
    point: usize,
    X_e: &[Point3<f64>],
    xi: &[f64; 3],
) -> Result<PointValues, ElementError> {
    let n = kind.node_count();
    let mut N = vec![0.0; n];
    let mut dN = vec![[0.0; 3]; n];
    let (J, det_J) = jacobian(kind, element, point, X_e, xi, &mut N, &mut dN)?;
    // g_a = J^{-T} dN_a: solve J^T g = dN (J is 3x3 and nonsingular here).
    let J_inv_T = J
        .try_inverse()
        .ok_or(ElementError::NonPositiveJacobian {
            element,
            point,
            det_j: det_J,
        })?
        .transpose();
    let g = dN.iter().map(|d| J_inv_T * Vector3::new(d[0], d[1], d[2])).collect();
    Ok(PointValues { N, g, det_J })
}

/// The shape functions `N` and their reference derivatives `dN` at `xi` (written into the
/// caller's buffers, [`SolidKind::node_count`] long), the Jacobian $\mathbf J$ and its
/// determinant, checked as [`point_values`] says. For callers that need no gradients (the
/// mass matrix) and reuse their buffers over the points of a rule.
fn jacobian(
    kind: SolidKind,
    element: usize,
    point: usize,
    X_e: &[Point3<f64>],
    xi: &[f64; 3],
    N: &mut [f64],
    dN: &mut [[f64; 3]],
) -> Result<(Matrix3<f64>, f64), ElementError> {
    kind.shape_functions(xi, N, dN);
    let mut J = Matrix3::zeros();
    for a in 0..kind.node_count() {
        for i in 0..3 {
            for j in 0..3 {
                J[(i, j)] += X_e[a][i] * dN[a][j];
            }
        }
    }
    let det_J = J.determinant();
    let h = X_e.iter().map(|x| (x - X_e[0]).norm()).fold(0.0, f64::max);
    // Relative threshold: det J scales as h^3; 1e-12 is far below any usable element and far
    // above round-off of a collapsed one.
    if !(det_J > 1e-12 * h * h * h) {
        return Err(ElementError::NonPositiveJacobian {
            element,
            point,
            det_j: det_J,
        });
    }
    Ok((J, det_J))
}

/// Checks $\det\mathbf J$ as [`solid_matrices`] will, at every point of the stiffness rule
/// and then of the mass rule, without computing any matrix: for a check of a whole mesh
/// before it is assembled.
///
/// # Errors
/// [`ElementError::NonPositiveJacobian`] and [`ElementError::WrongNodeCount`], as
/// [`solid_matrices`] gives them.
pub fn check_jacobians(kind: SolidKind, element: usize, X_e: &[Point3<f64>]) -> Result<(), ElementError> {
    check_node_count(kind, element, X_e)?;
    let n = kind.node_count();
    let mut N = vec![0.0; n];
    let mut dN = vec![[0.0; 3]; n];
    for rule in [kind.stiffness_rule(), kind.mass_rule()] {
        for (q, xi) in rule.points.iter().enumerate() {
            jacobian(kind, element, q, X_e, xi, &mut N, &mut dN)?;
        }
    }
    Ok(())
}

fn check_node_count(kind: SolidKind, element: usize, X_e: &[Point3<f64>]) -> Result<(), ElementError> {
    if X_e.len() != kind.node_count() {
        return Err(ElementError::WrongNodeCount {
            element,
            kind: kind.name(),
            expected: kind.node_count(),
            got: X_e.len(),
        });
    }
    Ok(())
}

/// Stiffness $\mathbf K_e = \sum_q w_q \det\mathbf J_q\, \mathbf B_q^T \mathbf D \mathbf B_q$ over
/// the kind's stiffness rule (Hughes 2000, (3.9.3)), assembled node block by node block.
///
/// # Derivation
/// For isotropic $\mathbf D$ the $3 \times 3$ block of nodes $a, b$ is, with
/// $\mathbf g = \partial N / \partial \mathbf x$,
/// $\mathbf K_{ab} = \int \big(\lambda\, \mathbf g_a \mathbf g_b^T + \mu\, \mathbf g_b \mathbf g_a^T +
/// \mu\, (\mathbf g_a \cdot \mathbf g_b)\, \mathbf I\big)\, dV$,
/// from $K_{ai,bj} = \int \partial_k N_a\, C_{ikjl}\, \partial_l N_b$ with
/// $C_{ikjl} = \lambda \delta_{ik}\delta_{jl} + \mu(\delta_{ij}\delta_{kl} + \delta_{il}\delta_{kj})$.
/// It equals $\mathbf B^T \mathbf D \mathbf B$ entry by entry at a sixth of the cost; the test
/// `unit::solid::stiffness_equals_BtDB` checks it against [`strain_displacement`] and
/// [`elasticity_matrix`].
///
/// # Errors
/// [`ElementError::NonPositiveJacobian`] with the index of the failing stiffness-rule point;
/// [`ElementError::WrongNodeCount`].
pub fn stiffness(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    material: &IsotropicMaterial,
) -> Result<DMatrix<f64>, ElementError> {
    check_node_count(kind, element, X_e)?;
    let n = kind.node_count();
    let (lambda, mu) = lame(material);
    let mut K_e = DMatrix::zeros(3 * n, 3 * n);
    let rule = kind.stiffness_rule();
    for (q, (xi, w)) in rule.points.iter().zip(&rule.weights).enumerate() {
        let p = point_values(kind, element, q, X_e, xi)?;
        let f = w * p.det_J;
        for a in 0..n {
            for b in a..n {
                let (ga, gb) = (&p.g[a], &p.g[b]);
                let dot = ga.dot(gb);
                for i in 0..3 {
                    for j in 0..3 {
                        let mut k = lambda * ga[i] * gb[j] + mu * gb[i] * ga[j];
                        if i == j {
                            k += mu * dot;
                        }
                        K_e[(3 * a + i, 3 * b + j)] += f * k;
                    }
                }
            }
        }
    }
    // Only the blocks b >= a were summed. Mirror the upper triangle (diagonal blocks
    // included) so that K_e is symmetric bit for bit: inside a diagonal block, lambda g_i g_j
    // and lambda g_j g_i round differently.
    mirror_upper(&mut K_e);
    Ok(K_e)
}

/// Scalar mass matrix $m_{ab} = \int \rho N_a N_b\, dV$ ($n \times n$) over the kind's mass rule;
/// `Lumped` is HRZ lumping (Hinton, Rock & Zienkiewicz, "A note on mass lumping and related
/// processes in the finite element method", Earthq. Eng. Struct. Dyn. 4 (1976) 245-249): the
/// consistent diagonal scaled so that it sums to the element mass $\rho V$. Unlike row sums,
/// HRZ keeps every entry positive for quadratic elements (row sums give negative corner
/// masses on tet10).
///
/// # Errors
/// [`ElementError::NonPositiveJacobian`] with the index of the failing mass-rule point;
/// [`ElementError::WrongNodeCount`].
pub fn scalar_mass(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    rho: f64,
    mass: MassKind,
) -> Result<DMatrix<f64>, ElementError> {
    check_node_count(kind, element, X_e)?;
    let n = kind.node_count();
    let mut m = DMatrix::zeros(n, n);
    let rule = kind.mass_rule();
    // The mass needs no gradients: shape functions and det J only, in buffers reused over
    // the rule's points (a large model's centre of mass runs this for every element).
    let mut N = vec![0.0; n];
    let mut dN = vec![[0.0; 3]; n];
    for (q, (xi, w)) in rule.points.iter().zip(&rule.weights).enumerate() {
        let (_, det_J) = jacobian(kind, element, q, X_e, xi, &mut N, &mut dN)?;
        let f = rho * w * det_J;
        for a in 0..n {
            for b in a..n {
                m[(a, b)] += f * N[a] * N[b];
            }
        }
    }
    mirror_upper(&mut m);
    if mass == MassKind::Lumped {
        let total: f64 = m.iter().sum();
        let diagonal: f64 = m.diagonal().iter().sum();
        let mut lumped = DMatrix::zeros(n, n);
        if diagonal > 0.0 {
            for a in 0..n {
                lumped[(a, a)] = m[(a, a)] * total / diagonal;
            }
        }
        m = lumped;
    }
    Ok(m)
}

/// Copies the strict upper triangle onto the lower one.
fn mirror_upper(A: &mut DMatrix<f64>) {
    for c in 0..A.ncols() {
        for r in 0..c {
            A[(c, r)] = A[(r, c)];
        }
    }
}

/// Element volume $\int dV$ by the mass rule (exact for the geometries the mass rule is exact
/// for, see each kind's module).
pub fn volume(kind: SolidKind, element: usize, X_e: &[Point3<f64>]) -> Result<f64, ElementError> {
    check_node_count(kind, element, X_e)?;
    let rule = kind.mass_rule();
    let mut v = 0.0;
    for (q, (xi, w)) in rule.points.iter().zip(&rule.weights).enumerate() {
        v += w * point_values(kind, element, q, X_e, xi)?.det_J;
    }
    Ok(v)
}

/// Stiffness and mass of a solid element, in global axes, dofs $[u_x, u_y, u_z]$ node by node:
/// $\mathbf K_e$ by [`stiffness`], $\mathbf M_e = \mathbf m \otimes \mathbf I_3$ with
/// $\mathbf m$ from [`scalar_mass`].
///
/// # Errors
/// [`ElementError::NonPositiveJacobian`] naming `element` and the quadrature point: checked first
/// at every point of the stiffness rule (the point index is the stiffness rule's), then of the
/// mass rule (the index is the mass rule's). [`ElementError::WrongNodeCount`] if `X_e` does not
/// have the kind's node count.
pub fn solid_matrices(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    material: &IsotropicMaterial,
    mass: MassKind,
) -> Result<LocalMatrices, ElementError> {
    let K_e = stiffness(kind, element, X_e, material)?;
    let M_e = solid_mass(kind, element, X_e, material, mass)?;
    Ok(LocalMatrices { K_e, M_e })
}

/// The mass matrix of [`solid_matrices`] alone ($3n \times 3n$, the scalar mass in each
/// direction), without the stiffness's cost: for the mass data of a reduced body.
///
/// # Errors
/// [`ElementError::NonPositiveJacobian`] at a point of the mass rule;
/// [`ElementError::WrongNodeCount`] if `X_e` does not have the kind's node count.
pub fn solid_mass(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    material: &IsotropicMaterial,
    mass: MassKind,
) -> Result<DMatrix<f64>, ElementError> {
    let m = scalar_mass(kind, element, X_e, material.rho(), mass)?;
    Ok(times_identity3(&m))
}

/// The $3n \times 3n$ matrix $\mathbf m \otimes \mathbf 1_3$ of a scalar $n \times n$ matrix
/// `m`: block $(a, b)$ is $m_{ab}\mathbf 1_3$ (the same for each displacement component).
fn times_identity3(m: &DMatrix<f64>) -> DMatrix<f64> {
    let n = m.nrows();
    let mut out = DMatrix::zeros(3 * n, 3 * n);
    for b in 0..n {
        for a in 0..n {
            for i in 0..3 {
                out[(3 * a + i, 3 * b + i)] = m[(a, b)];
            }
        }
    }
    out
}

/// Displacement gradient $\mathbf H = \partial\mathbf u/\partial\mathbf x = \sum_a \mathbf u_a
/// \mathbf g_a^T$ ($H_{mj} = \partial u_m/\partial x_j$) at a point with physical shape-function
/// gradients `g`, for element displacements `u_e` ($[u_x, u_y, u_z]$ node by node).
pub fn displacement_gradient(g: &[Vector3<f64>], u_e: &[f64]) -> Matrix3<f64> {
    let mut H = Matrix3::zeros();
    for (a, ga) in g.iter().enumerate() {
        let u_a = Vector3::new(u_e[3 * a], u_e[3 * a + 1], u_e[3 * a + 2]);
        H += u_a * ga.transpose();
    }
    H
}

/// Linear stress $\boldsymbol\sigma = \lambda\,\mathrm{tr}(\boldsymbol\varepsilon)\,\mathbf 1 +
/// 2\mu\,\boldsymbol\varepsilon$ of the displacement gradient $\mathbf H$, with
/// $\boldsymbol\varepsilon = \tfrac12(\mathbf H + \mathbf H^T)$: the tensor form of
/// $\mathbf D\boldsymbol\varepsilon$ with [`elasticity_matrix`] (the same $\lambda$, $\mu$ the
/// stiffness uses; `tests/unit/geometric.rs` checks the two against each other).
pub fn linear_stress(material: &IsotropicMaterial, H: &Matrix3<f64>) -> Matrix3<f64> {
    let (lambda, mu) = lame(material);
    let eps = 0.5 * (H + H.transpose());
    Matrix3::identity() * (lambda * eps.trace()) + eps * (2.0 * mu)
}

/// Geometric (initial-stress) stiffness $\mathbf K_G^e = \int \mathbf G^T \mathbf S
/// \mathbf G\, dV$ of a solid element under the linear stress of the element displacements
/// `u_e`: $\mathbf G$ ($9 \times 3n$) maps $\mathbf u_e$ to the displacement gradient,
/// $\mathbf S = \mathrm{blockdiag}(\boldsymbol\sigma, \boldsymbol\sigma, \boldsymbol\sigma)$,
/// $\boldsymbol\sigma = \mathbf D\boldsymbol\varepsilon(\mathbf u_e)$ at each point of the
/// stiffness rule (the $\mathbf B_{NL}^T\boldsymbol\tau\mathbf B_{NL}$ term of Bathe, *Finite
/// Element Procedures* (1996) ch. 6; Cook, Malkus, Plesha & Witt (2002) ch. 18).
///
/// # Derivation
/// $\tfrac12\mathbf v^T\mathbf K_G\mathbf v = \int \boldsymbol\sigma : \tfrac12
/// \mathbf H_v^T\mathbf H_v\, dV$, the second-order part of the Green-Lagrange strain under
/// $\boldsymbol\sigma$. With $\mathbf H_v = \sum_a \mathbf v_a\mathbf g_a^T$,
/// $\boldsymbol\sigma : \mathbf H_v^T\mathbf H_v = \sum_m \sum_{a,b} v_{am}\,
/// \mathbf g_a^T\boldsymbol\sigma\mathbf g_b\, v_{bm}$, so the block of nodes $a, b$ is
/// $k_{ab}\mathbf 1_3$ with $k_{ab} = \int \mathbf g_a^T\boldsymbol\sigma\mathbf g_b\, dV$.
///
/// # Errors
/// As [`stiffness`].
///
/// # Panics
/// If `u_e` does not have $3n$ entries (a caller's bug, not input).
pub fn geometric_stiffness(
    kind: SolidKind,
    element: usize,
    X_e: &[Point3<f64>],
    material: &IsotropicMaterial,
    u_e: &[f64],
) -> Result<DMatrix<f64>, ElementError> {
    check_node_count(kind, element, X_e)?;
    let n = kind.node_count();
    assert_eq!(u_e.len(), 3 * n, "a solid's element displacements have 3 per node");
    let mut k = DMatrix::zeros(n, n);
    let rule = kind.stiffness_rule();
    for (q, (xi, w)) in rule.points.iter().zip(&rule.weights).enumerate() {
        let p = point_values(kind, element, q, X_e, xi)?;
        let sigma = linear_stress(material, &displacement_gradient(&p.g, u_e));
        let f = w * p.det_J;
        for b in 0..n {
            let s_gb = sigma * p.g[b];
            for a in 0..=b {
                k[(a, b)] += f * p.g[a].dot(&s_gb);
            }
        }
    }
    mirror_upper(&mut k);
    Ok(times_identity3(&k))
}
