//! Geometric (initial-stress) stiffness: the stiffness a stress field adds through the
//! second-order part of the Green-Lagrange strain, for linearised buckling and for the
//! geometric stiffening of reduced bodies.
//!
//! For a displacement field $\mathbf w$ with linear stress $\boldsymbol\sigma(\mathbf w)$,
//! $$\tfrac12\,\mathbf u^T\mathbf K_G(\boldsymbol\sigma(\mathbf w))\,\mathbf u
//! = \int_V \boldsymbol\sigma(\mathbf w) : \tfrac12 (\nabla\mathbf u)^T(\nabla\mathbf u)\, dV,$$
//! element by element: solids [`solid::geometric_stiffness`], beams
//! [`beam2::beam2_geometric_stiffness`] under the axial force [`beam2::beam2_axial_force`]
//! (the Timoshenko beam uses the Euler-Bernoulli matrix, see there).
//!
//! - [`assemble_geometric_stiffness`]: $\mathbf K_G(\boldsymbol\sigma(\mathbf u))$ on the free
//!   dofs for a free-dof displacement $\mathbf u$, on the [`SystemPattern`] of $\mathbf K$.
//! - [`element_geometric_tensor_into`]: for a basis $\mathbf V_e$ of element displacements,
//!   all $\mathbf V_e^T\mathbf K_G^e(\boldsymbol\sigma(\mathbf V_e\mathbf e_k))\mathbf V_e$ at
//!   once, each basis vector's stress computed once per quadrature point (what the reduction
//!   needs for geometric stiffening, without a global $\mathbf K_G$ per basis vector).
//! - [`linear_buckling`]: $\mathbf K\boldsymbol\phi = \lambda\,(-\mathbf K_G(\boldsymbol
//!   \sigma_{ref}))\boldsymbol\phi$ with $\boldsymbol\sigma_{ref}$ the linear stress of a
//!   reference load: the load factors at which the structure buckles.
//!
//! # Notation
//!
//! | symbol | Rust | meaning | source |
//! |---|---|---|---|
//! | $\mathbf H$ | `H` | displacement gradient $\partial\mathbf u/\partial\mathbf x$ | [`solid::displacement_gradient`] |
//! | $\boldsymbol\sigma$ | `sigma` | linear stress $\mathbf D\boldsymbol\varepsilon$ | [`solid::linear_stress`] |
//! | $N$ | `N` | beam axial force, tension positive | [`beam2::beam2_axial_force`] |
//! | $\mathbf K_G^e,\ \mathbf K_G$ | `K_G` | element and assembled geometric stiffness | this module |
//! | $\mathbf V_e$ | `V_e` | element rows of a displacement basis (element dof order) | [`element_geometric_tensor_into`] |
//! | $c_{k,lp}$ | `out[(pair(l, p), k)]` | $(\mathbf V_e^T\mathbf K_G^e(\boldsymbol\sigma(\mathbf V_e\mathbf e_k))\mathbf V_e)_{lp}$, $l \le p$ | [`packed_pair`] |
//! | $\lambda$ | `load_factors` | buckling load factor of the reference load | [`linear_buckling`] |

#![allow(non_snake_case)]

use crate::assembly::{assemble, element_coordinates, fill_values};
use crate::dof::DofMap;
use crate::element::{beam2, solid, Element, SolidKind};
use crate::error::{ElementError, FeError};
use crate::model::{FeModel, NodalLoad};
use crate::ordering::{dof_points, FillOrdering};
use crate::pattern::{element_slots, SystemPattern};
use crate::statics::{cholesky, load_vector};
use faer::sparse::SparseColMat;
use faer::Mat;
use nalgebra::{DMatrix, Matrix3, Point3};
use serde::{Deserialize, Serialize};

/// The full dof slots (`6 node + k`) of an element's local dofs, in its local order: the rows
/// of a full-slot basis that make $\mathbf V_e$.
pub fn element_dof_slots(element: &Element) -> Vec<usize> {
    element_slots(element)
}

/// Geometric stiffness $\mathbf K_G^e$ (global axes, local dofs as the element's stiffness)
/// of element `index` under the linear stress of its displacements `u_e` (module docs).
///
/// # Errors
/// The element's geometry and property errors, as for its stiffness.
pub fn element_geometric_stiffness(model: &FeModel, index: usize, u_e: &[f64]) -> Result<DMatrix<f64>, ElementError> {
    let X_e = element_coordinates(model, index)?;
    let props = model.properties();
    match &model.elements[index] {
        Element::Beam2(b) => {
            let section = props.section(index, b.section)?;
            let material = props.material(index, b.material)?;
            let X = [X_e[0], X_e[1]];
            let N = beam2::beam2_axial_force(b, index, X, material.E() * section.A(), u_e)?;
            beam2::beam2_geometric_stiffness(b, index, X, section, N)
        }
        element => {
            let (kind, s) = element.solid().expect("every other kind is a solid");
            let material = props.material(index, s.material)?;
            solid::geometric_stiffness(kind, index, &X_e, material, u_e)
        }
    }
}

/// $\mathbf K_G(\boldsymbol\sigma(\mathbf u)) = \mathbf T^T\big(\sum_e \mathbf K_G^e\big)
/// \mathbf T$ on the free dofs of `dofs`, for the free-dof displacement `u`, with the
/// structure of `pattern` (the pattern of $\mathbf K$ and $\mathbf M$). Elements in parallel.
///
/// # Errors
/// Element errors ([`FeError::Element`]).
///
/// # Panics
/// If `u` does not have `dofs.n_free()` entries or `pattern` was built for another model.
pub fn assemble_geometric_stiffness(
    model: &FeModel,
    dofs: &DofMap,
    pattern: &SystemPattern,
    u: &[f64],
) -> Result<SparseColMat<usize, f64>, FeError> {
    assert_eq!(u.len(), dofs.n_free(), "u must have one entry per free dof");
    assert_eq!(
        pattern.elements.len(),
        model.elements.len(),
        "pattern built for another model"
    );
    let u_full: Vec<f64> = dofs.expand(u).into_iter().flatten().collect();
    // The parallel element loop of the assembly: each entry summed in element order.
    let mut values = vec![0.0; pattern.nnz()];
    fill_values(model, pattern, [&mut values], |e| {
        let u_e: Vec<f64> = element_slots(&model.elements[e]).iter().map(|&s| u_full[s]).collect();
        Ok([element_geometric_stiffness(model, e, &u_e)?])
    })?;
    Ok(SparseColMat::new(pattern.symbolic.clone(), values))
}

/// Position of the pair $(l, p)$, $l \le p$, in the packed upper triangle (column by column):
/// $l + p(p+1)/2$. The rows of [`element_geometric_tensor_into`]'s output.
pub fn packed_pair(l: usize, p: usize) -> usize {
    debug_assert!(l <= p);
    l + p * (p + 1) / 2
}

/// The Voigt pairs $(i, j)$ of a symmetric $3 \times 3$ tensor, in the order of
/// [`solid::elasticity_matrix`]: $xx, yy, zz, xy, yz, zx$.
const VOIGT: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

/// Adds to `out` ($n(n+1)/2 \times n$) the projected geometric stiffness of element `index`
/// for every column of the basis `V_e` (element dofs x $n$, rows in the element's dof order
/// [`element_dof_slots`]): entry $(\text{[`packed_pair`]}(l, p), k)$ gains
/// $(\mathbf V_e^T\mathbf K_G^e(\boldsymbol\sigma(\mathbf V_e\mathbf e_k))\mathbf V_e)_{lp}$.
///
/// # Derivation
/// Beams: $\mathbf K_G^e$ is linear in the axial force, $\mathbf K_G^e = N\hat{\mathbf K}_G^e$,
/// so the entry is $N_k\,(\mathbf V_e^T\hat{\mathbf K}_G^e\mathbf V_e)_{lp}$ with $N_k$ the
/// axial force of basis vector $k$.
/// Solids: with $\mathbf H_l$ the displacement gradient of basis vector $l$ at a quadrature
/// point (weight $f = w\det\mathbf J$), [`solid::geometric_stiffness`] gives
/// $f\sum_m (\mathbf H_l)_{m\cdot}\,\boldsymbol\sigma_k\,(\mathbf H_p)_{m\cdot}^T
/// = f\sum_{ij}\sigma_{k,ij}T_{ij,lp}$, $T_{ij,lp} = \sum_m (\mathbf H_l)_{mi}(\mathbf H_p)_{mj}$.
/// Grouping the symmetric $\boldsymbol\sigma_k$ by Voigt pairs,
/// $T'_{ij,lp} = T_{ij,lp} + T_{ji,lp}$ ($i \ne j$), the sum over the element's points is one
/// product $\mathbf T'\boldsymbol\Sigma$ of the $n(n+1)/2 \times 6Q$ matrix of $T'$ and the
/// $6Q \times n$ matrix of the weighted stresses of all basis vectors: each stress is
/// computed once per point, and the work is $6Qn^2(n+1)$ flops per element.
///
/// # Errors
/// The element's geometry and property errors.
///
/// # Panics
/// If `V_e` does not have the element's dof count as rows or `out` is not
/// $n(n+1)/2 \times n$.
pub fn element_geometric_tensor_into(
    model: &FeModel,
    index: usize,
    V_e: &DMatrix<f64>,
    out: &mut DMatrix<f64>,
) -> Result<(), ElementError> {
    let n = V_e.ncols();
    assert_eq!(out.shape(), (n * (n + 1) / 2, n), "out must be n(n+1)/2 x n");
    let X_e = element_coordinates(model, index)?;
    let props = model.properties();
    match &model.elements[index] {
        Element::Beam2(b) => {
            assert_eq!(V_e.nrows(), 12, "a beam's V_e has 12 rows");
            let section = props.section(index, b.section)?;
            let material = props.material(index, b.material)?;
            let X = [X_e[0], X_e[1]];
            let K_hat = beam2::beam2_geometric_stiffness(b, index, X, section, 1.0)?;
            let B = V_e.transpose() * &K_hat * V_e;
            for k in 0..n {
                let column: Vec<f64> = V_e.column(k).iter().copied().collect();
                let N_k = beam2::beam2_axial_force(b, index, X, material.E() * section.A(), &column)?;
                if N_k == 0.0 {
                    continue;
                }
                for p in 0..n {
                    for l in 0..=p {
                        out[(packed_pair(l, p), k)] += N_k * B[(l, p)];
                    }
                }
            }
            Ok(())
        }
        element => {
            let (kind, s) = element.solid().expect("every other kind is a solid");
            let material = props.material(index, s.material)?;
            solid_geometric_tensor_into(kind, index, &X_e, material, V_e, out)
        }
    }
}

/// The solid case of [`element_geometric_tensor_into`] (its derivation).
fn solid_geometric_tensor_into(
    kind: SolidKind,
    index: usize,
    X_e: &[Point3<f64>],
    material: &crate::property::IsotropicMaterial,
    V_e: &DMatrix<f64>,
    out: &mut DMatrix<f64>,
) -> Result<(), ElementError> {
    let n = V_e.ncols();
    let n_nodes = kind.node_count();
    assert_eq!(V_e.nrows(), 3 * n_nodes, "a solid's V_e has 3 rows per node");
    let rule = kind.stiffness_rule();
    let Q = rule.points.len();
    let mut T = DMatrix::<f64>::zeros(n * (n + 1) / 2, 6 * Q);
    let mut Sigma = DMatrix::<f64>::zeros(6 * Q, n);
    // P[(3m + j, l)] = (H_l)_{mj}: the gradients of all basis vectors at one point.
    let mut P = DMatrix::<f64>::zeros(9, n);
    for (q, (xi, w)) in rule.points.iter().zip(&rule.weights).enumerate() {
        let pv = solid::point_values(kind, index, q, X_e, xi)?;
        let f = w * pv.det_J;
        P.fill(0.0);
        for l in 0..n {
            for (a, g) in pv.g.iter().enumerate() {
                for m in 0..3 {
                    let v = V_e[(3 * a + m, l)];
                    for j in 0..3 {
                        P[(3 * m + j, l)] += v * g[j];
                    }
                }
            }
            let H = Matrix3::from_fn(|m, j| P[(3 * m + j, l)]);
            let sigma = solid::linear_stress(material, &H);
            for (v, &(i, j)) in VOIGT.iter().enumerate() {
                Sigma[(6 * q + v, l)] = f * sigma[(i, j)];
            }
        }
        for p in 0..n {
            for l in 0..=p {
                let row = packed_pair(l, p);
                for (v, &(i, j)) in VOIGT.iter().enumerate() {
                    let mut t = 0.0;
                    for m in 0..3 {
                        t += P[(3 * m + i, l)] * P[(3 * m + j, p)];
                        if i != j {
                            t += P[(3 * m + j, l)] * P[(3 * m + i, p)];
                        }
                    }
                    T[(row, 6 * q + v)] = t;
                }
            }
        }
    }
    out.gemm(1.0, &T, &Sigma, 1.0);
    Ok(())
}

/// Settings of [`linear_buckling`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BucklingSettings {
    /// Number of load factors wanted (the lowest positive ones).
    pub n_modes: usize,
    /// Convergence: the relative change of every wanted load factor between two iterations.
    pub tolerance: f64,
    /// Iteration limit.
    pub max_iterations: usize,
}

impl BucklingSettings {
    /// `n_modes` load factors to a relative change of $10^{-10}$ between iterations (a Ritz
    /// value's error is the square of its vector's, so the factors are then near round-off;
    /// a tighter value can stall on round-off noise for large models), at most 200
    /// iterations.
    pub fn new(n_modes: usize) -> Self {
        Self {
            n_modes,
            tolerance: 1e-10,
            max_iterations: 200,
        }
    }
}

/// Result of [`linear_buckling`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BucklingSolution {
    /// Load factors $\lambda$, ascending: the structure buckles under $\lambda$ times the
    /// reference load.
    pub load_factors: Vec<f64>,
    /// Buckling modes on every node, largest component 1.
    pub shapes: Vec<Vec<[f64; 6]>>,
    /// The reference static displacements whose stress makes $\mathbf K_G$.
    pub reference: Vec<[f64; 6]>,
}

/// Linearised buckling of the FE model under the reference `loads`:
/// $\mathbf K\boldsymbol\phi = \lambda\,(-\mathbf K_G(\boldsymbol\sigma(\mathbf u_{ref})))
/// \boldsymbol\phi$ with $\mathbf K\mathbf u_{ref} = \mathbf f$, by subspace iteration on
/// $\mathbf K^{-1}(-\mathbf K_G)$ (Bathe, *Finite Element Procedures* (1996) §11.6) with
/// $\max(2m, m + 8)$ vectors and a Rayleigh-Ritz step each iteration.
///
/// The iteration finds the factors of largest $1/|\lambda|$, so the lowest positive factors
/// are found when they dominate the negative ones (buckling under the reversed load), as for
/// compressed columns and frames; the result lists the positive factors only.
///
/// # Errors
/// Those of [`crate::solve_static`]; [`FeError::LinearAlgebra`] when the iteration does not
/// converge, finds fewer than `n_modes` positive factors (the load does not compress enough
/// of the structure), or when $\mathbf K_G$ has rank below the $\max(2m, m + 8)$ vectors (a
/// load that stresses only a few elements: the Ritz stiffness is then singular).
pub fn linear_buckling(
    model: &FeModel,
    loads: &[NodalLoad],
    settings: &BucklingSettings,
) -> Result<BucklingSolution, FeError> {
    let dofs = DofMap::new(model)?;
    let pattern = SystemPattern::new(model, &dofs);
    let K = assemble(model, &pattern)?.K;
    let f = dofs.restrict(&load_vector(model, loads)?, "buckling reference load")?;
    let points = dof_points(model, &dofs);
    let llt = cholesky(K.as_ref(), &dofs, Some(&points), FillOrdering::Auto)?;
    let n = dofs.n_free();
    let mut u = Mat::from_fn(n, 1, |i, _| f[i]);
    llt.solve_in_place(u.as_mut());
    let u_ref: Vec<f64> = (0..n).map(|i| u[(i, 0)]).collect();
    let K_G = assemble_geometric_stiffness(model, &dofs, &pattern, &u_ref)?;
    let m = settings.n_modes;
    let p = (2 * m).max(m + 8).min(n);
    if m == 0 || m > p {
        return Err(FeError::LinearAlgebra(format!(
            "linear buckling: {m} modes requested from a model with {n} free dofs"
        )));
    }
    // Deterministic start: a pseudo-random block (a linear congruential sequence), so runs
    // repeat exactly.
    let mut seed = 0x2545_F491_4F6C_DD1Du64;
    let mut X = Mat::from_fn(n, p, |_, _| {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let mut previous = vec![f64::INFINITY; m];
    for _ in 0..settings.max_iterations {
        // Y = K^{-1} A X with A = -K_G.
        let mut Y = -(&K_G * &X);
        llt.solve_in_place(Y.as_mut());
        let KY = &K * &Y;
        let AY = -(&K_G * &Y);
        let K_r = to_nalgebra(&(Y.transpose() * &KY));
        let A_r = to_nalgebra(&(Y.transpose() * &AY));
        // A_r z = mu K_r z, mu = 1/lambda: Cholesky of K_r, symmetric eigenproblem.
        let L = nalgebra::Cholesky::new(0.5 * (&K_r + K_r.transpose()))
            .ok_or_else(|| {
                FeError::LinearAlgebra("linear buckling: the Ritz stiffness is not positive definite".into())
            })?
            .l();
        let L_inv = L
            .clone()
            .try_inverse()
            .ok_or_else(|| FeError::LinearAlgebra("linear buckling: singular Ritz stiffness".into()))?;
        let C = &L_inv * &A_r * L_inv.transpose();
        let eig = nalgebra::SymmetricEigen::new(0.5 * (&C + C.transpose()));
        let mut order: Vec<usize> = (0..p).collect();
        order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let Z = L_inv.transpose() * DMatrix::from_fn(p, p, |i, j| eig.eigenvectors[(i, order[j])]);
        let Z = Mat::from_fn(p, p, |i, j| Z[(i, j)]);
        X = &Y * &Z;
        let mu: Vec<f64> = order.iter().map(|&k| eig.eigenvalues[k]).collect();
        let converged = mu[..m]
            .iter()
            .zip(&previous)
            .all(|(a, b)| (a - b).abs() <= settings.tolerance * a.abs());
        previous = mu[..m].to_vec();
        if converged {
            if mu[m - 1] <= 0.0 {
                return Err(FeError::LinearAlgebra(format!(
                    "linear buckling: only {} positive load factors: the reference load does not compress the structure enough",
                    mu.iter().filter(|&&x| x > 0.0).count()
                )));
            }
            let shapes = (0..m)
                .map(|j| {
                    let phi: Vec<f64> = (0..n).map(|i| X[(i, j)]).collect();
                    let scale = phi.iter().fold(0.0f64, |s, v| if v.abs() > s.abs() { *v } else { s });
                    let phi: Vec<f64> = phi.iter().map(|v| v / scale).collect();
                    dofs.expand(&phi)
                })
                .collect();
            return Ok(BucklingSolution {
                load_factors: mu[..m].iter().map(|x| 1.0 / x).collect(),
                shapes,
                reference: dofs.expand(&u_ref),
            });
        }
    }
    Err(FeError::LinearAlgebra(format!(
        "linear buckling: no convergence in {} iterations (load factors {:?})",
        settings.max_iterations,
        previous.iter().map(|x| 1.0 / x).collect::<Vec<_>>()
    )))
}

fn to_nalgebra(A: &Mat<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(A.nrows(), A.ncols(), |i, j| A[(i, j)])
}
