//! Dense modal analysis for small models: $\mathbf K \boldsymbol\phi = \omega^2 \mathbf M
//! \boldsymbol\phi$ by a Cholesky of $\mathbf M$ and the symmetric eigenproblem of
//! $\mathbf L^{-1} \mathbf K \mathbf L^{-T}$ (faer, dense). Large models use the sparse
//! shift-invert solver of the `reduction` crate.

use crate::assembly::assemble;
use crate::dof::{Dof, DofMap};
use crate::error::FeError;
use crate::model::FeModel;
use crate::pattern::SystemPattern;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::{Mat, Par, Side};
use serde::{Deserialize, Serialize};

/// Largest model (free dofs) the dense path accepts: $O(n^3)$ work and $O(n^2)$ memory.
pub const DENSE_LIMIT: usize = 6000;

/// Eigenpairs of a model, lowest first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModalSolution {
    /// Circular frequencies $\omega_n$ [rad/s]; a (numerically) negative $\omega^2$ is
    /// reported as $-\sqrt{|\omega^2|}$ so that rigid modes stay visible.
    pub omega: Vec<f64>,
    /// Mode shapes on every node, mass-normalised ($\boldsymbol\phi^T \mathbf M
    /// \boldsymbol\phi = 1$).
    pub shapes: Vec<Vec<[f64; 6]>>,
}

impl ModalSolution {
    /// Frequencies in Hz.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.omega.iter().map(|w| w / (2.0 * std::f64::consts::PI)).collect()
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
    let llt = M.llt(Side::Lower).map_err(|e| {
        let index = match e {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => index,
        };
        let (node_tag, dof) = dofs.describe(Dof(index.min(n.saturating_sub(1)) as u32));
        FeError::MasslessDof { node_tag, dof }
    })?;
    let L = llt.L();
    // C = L^{-1} K L^{-T}
    let mut C = K.clone();
    solve_lower_triangular_in_place(L, C.as_mut(), Par::rayon(0));
    let mut Ct = C.transpose().to_owned();
    solve_lower_triangular_in_place(L, Ct.as_mut(), Par::rayon(0));
    let C = Mat::from_fn(n, n, |i, j| 0.5 * (Ct[(i, j)] + Ct[(j, i)]));
    let evd = C
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| FeError::LinearAlgebra(format!("dense eigen: {e:?}")))?;
    let m = n_modes.min(n);
    let S = evd.S();
    let mut Y = evd.U().subcols(0, m).to_owned();
    // phi = L^{-T} y
    solve_upper_triangular_in_place(L.transpose(), Y.as_mut(), Par::rayon(0));
    let omega = (0..m)
        .map(|i| {
            let w2 = S[i];
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
