//! Dense modal analysis for small models: $\mathbf K \boldsymbol\phi = \omega^2 \mathbf M
//! \boldsymbol\phi$, shift-inverted: with $\mathbf K + s\mathbf M = \mathbf L\mathbf L^T$
//! the symmetric matrix $\mathbf L^{-1}\mathbf M\mathbf L^{-T}$ has eigenvalues
//! $\mu = 1/(\omega^2 + s)$ (faer, dense). Large models use the sparse shift-invert solver of
//! the `reduction` crate.
//!
//! Why shift-invert and not $\mathbf L_M^{-1}\mathbf K\mathbf L_M^{-T}$: the latter's
//! eigenvalues carry an absolute error of about $\varepsilon\|\mathbf K\|/\lambda_{min}(\mathbf M)$,
//! which for beams (tiny rotary inertia next to stiff rotations) reaches $10^{-3}$ relative
//! on the lowest modes. Shift-invert makes the lowest modes the dominant ones, accurate to
//! round-off relative to themselves (found by `reduction`'s Rayleigh-Ritz test).

use crate::assembly::assemble;
use crate::dof::{Dof, DofMap};
use crate::error::FeError;
use crate::model::FeModel;
use crate::pattern::SystemPattern;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Mat, MatRef, Par, Side};
use serde::{Deserialize, Serialize};

/// Largest model (free dofs) the dense path accepts: $O(n^3)$ work and $O(n^2)$ memory.
pub const DENSE_LIMIT: usize = 6000;

/// Eigenpairs of a model, lowest first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModalSolution {
    /// Circular frequencies $\omega_n$ [rad/s] as computed; a (numerically) negative
    /// $\omega^2$ is kept as $-\sqrt{|\omega^2|}$ here. Reports use
    /// [`Self::frequencies_hz`] and [`Self::rigid_body_modes`], which show rigid-body modes
    /// at 0 Hz.
    pub omega: Vec<f64>,
    /// Mode shapes on every node, mass-normalised ($\boldsymbol\phi^T \mathbf M
    /// \boldsymbol\phi = 1$).
    pub shapes: Vec<Vec<[f64; 6]>>,
}

/// Below this fraction of the highest computed frequency a mode is a rigid-body mode: its
/// $\omega^2$ is round-off of the factorisation, about $10^{-16}$ of the largest eigenvalue of
/// the matrices, so its $|\omega|$ is far below $10^{-4}$ of any elastic frequency.
pub const RIGID_BODY_FRACTION: f64 = 1e-4;

impl ModalSolution {
    /// Which modes are rigid-body modes: a negative $\omega^2$ (with $\mathbf K \succeq 0$ and
    /// $\mathbf M \succ 0$ only round-off makes one) or $|\omega|$ below
    /// [`RIGID_BODY_FRACTION`] of the highest computed frequency.
    pub fn rigid_body_modes(&self) -> Vec<bool> {
        let highest = self.omega.iter().fold(0.0f64, |a, w| a.max(*w));
        self.omega
            .iter()
            .map(|&w| w < 0.0 || w.abs() < RIGID_BODY_FRACTION * highest)
            .collect()
    }

    /// Frequencies in Hz; rigid-body modes ([`Self::rigid_body_modes`]) are 0, never negative.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.omega
            .iter()
            .zip(self.rigid_body_modes())
            .map(|(w, rigid)| if rigid { 0.0 } else { w / (2.0 * std::f64::consts::PI) })
            .collect()
    }
}

/// The `n_modes` lowest modes of `model` by the dense path.
pub fn modal_dense(model: &FeModel, n_modes: usize) -> Result<ModalSolution, FeError> {
    let dofs = DofMap::new(model)?;
    let pattern = SystemPattern::new(model, &dofs);
    let a = assemble(model, &pattern)?;
    let n = dofs.n_free();
    if n > DENSE_LIMIT {
        return Err(FeError::TooLargeForDense { n, limit: DENSE_LIMIT });
    }
    let K = a.K.to_dense();
    let M = a.M.to_dense();
    // The shift s > 0 makes K + sM positive definite for free bodies too. Its size only
    // needs to be neither tiny nor huge against the spectrum: a thousandth of the mean
    // diagonal ratio.
    let (trK, trM) = (0..n).fold((0.0, 0.0), |(a, b), i| (a + K[(i, i)], b + M[(i, i)]));
    if !(trM > 0.0) {
        return Err(FeError::LinearAlgebra(format!(
            "the mass matrix has trace {trM:.3e}: the model has no mass"
        )));
    }
    let s = 1e-3 * (trK / trM).max(f64::MIN_POSITIVE);
    let A = Mat::from_fn(n, n, |i, j| K[(i, j)] + s * M[(i, j)]);
    let llt = A.llt(Side::Lower).map_err(|e| {
        let index = match e {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => index,
        };
        let (node_tag, dof) = dofs.describe(Dof(index.min(n.saturating_sub(1)) as u32));
        FeError::MasslessDof { node_tag, dof }
    })?;
    let L = llt.L();
    // C = L^{-1} M L^{-T}
    let mut C = M.clone();
    solve_lower_triangular_in_place(L, C.as_mut(), Par::rayon(0));
    let mut Ct = C.transpose().to_owned();
    solve_lower_triangular_in_place(L, Ct.as_mut(), Par::rayon(0));
    let C = Mat::from_fn(n, n, |i, j| 0.5 * (Ct[(i, j)] + Ct[(j, i)]));
    // Scaled: C has norm 1/(lambda_1 + s), far from 1 (see `scaled_self_adjoint_eigen`).
    let (S, U) = scaled_self_adjoint_eigen(C.as_ref())?;
    let m = n_modes.min(n);
    // The largest mu are the lowest modes; faer sorts ascending.
    let order: Vec<usize> = (0..m).map(|k| n - 1 - k).collect();
    let mut Y = Mat::from_fn(n, m, |i, k| U[(i, order[k])]);
    // phi = L^{-T} y has phi^T M phi = mu: divide by sqrt(mu) to mass-normalise.
    solve_upper_triangular_in_place(L.transpose(), Y.as_mut(), Par::rayon(0));
    for (k, &j) in order.iter().enumerate() {
        let scale = 1.0 / S[j].max(f64::MIN_POSITIVE).sqrt();
        for i in 0..n {
            Y[(i, k)] *= scale;
        }
    }
    let omega = order
        .iter()
        .map(|&j| {
            let w2 = 1.0 / S[j] - s;
            if w2 >= 0.0 {
                w2.sqrt()
            } else {
                -(-w2).sqrt()
            }
        })
        .collect();
    let shapes = (0..m)
        .map(|j| dofs.expand(&(0..n).map(|i| Y[(i, j)]).collect::<Vec<_>>()))
        .collect();
    Ok(ModalSolution { omega, shapes })
}

/// Eigenvalues (ascending) and eigenvectors of the dense symmetric `A` (lower triangle read)
/// by faer's `self_adjoint_eigen`, computed on $2^{-e}\mathbf A$ with $2^e$ the power of two
/// nearest $\max_{ij}|a_{ij}|$ (exact scaling), eigenvalues scaled back.
///
/// Why: from dimension 128 faer 0.24 uses divide and conquer on the tridiagonal matrix, whose
/// deflation test (`tridiag_evd.rs`, as LAPACK's `dlaed2`) is $8\varepsilon\max(\max_i|d_i|,
/// \max_i|z_i|)$ with $\mathbf z$ a unit vector: absolute unless $\|\mathbf A\| \gtrsim 1$.
/// LAPACK's `dstedc` scales the matrix to unit norm before it; faer does not. Our matrices
/// are far from unit norm: `reduction`'s Lanczos matrix of $\mathbf C$ has norm $\mu_1 = 1/(\lambda_1 -
/// \sigma)$, $10^{-6}$ for a clamped 1 m aluminium beam in SI units, so every eigenvector came
/// out with an error of order $\varepsilon$ *absolute*, $\|\mathbf T\mathbf s -
/// \theta\mathbf s\| \approx 10^{-6}\theta$ for the Ritz values near $10^{-11}$: Lanczos
/// reported converged pairs (its estimate $\|\mathbf B\mathbf s_{k-b+1:k}\|$ assumes an
/// exact $\mathbf s$) whose true residuals failed the check on $(\mathbf K, \mathbf M)$,
/// whatever the restarts (`reduction`'s `tests/unit/eigen.rs::clamped_beam_with_many_modes_matches_dense_reference`).
/// Large norms suffer too, for a reason not traced in faer's secular-equation solver: on
/// $\mathbf L_M^{-1}\mathbf K\mathbf L_M^{-T}$ of the same beam (norm $3\cdot 10^{12}$, the
/// test's dense reference) it gave $\lambda_1$ 0.4 % off at $n = 354$ and a negative
/// eigenvalue at $n = 1194$; scaled, the residuals are $10^{-14}$. The Rayleigh-Ritz matrix
/// (norm $\lambda_m$) meets it from $m = 128$. Below dimension 128 faer's QR algorithm is
/// used, which is scale-invariant.
pub fn scaled_self_adjoint_eigen(A: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>), FeError> {
    let n = A.nrows();
    let largest = A.norm_max();
    if !largest.is_finite() {
        return Err(FeError::LinearAlgebra(format!("dense eigen: an entry is {largest}")));
    }
    // A power of two: the scaling and its inverse are exact.
    let exponent = if largest > 0.0 {
        largest.log2().round() as i32
    } else {
        0
    };
    let scale = 2f64.powi(exponent);
    let scaled = Mat::<f64>::from_fn(n, n, |i, j| A[(i, j)] / scale);
    let evd = scaled
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| FeError::LinearAlgebra(format!("dense eigen: {e:?}")))?;
    Ok(((0..n).map(|k| evd.S()[k] * scale).collect(), evd.U().to_owned()))
}
