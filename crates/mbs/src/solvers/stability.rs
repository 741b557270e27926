//! Whether a static equilibrium is stable: the inertia of its tangent stiffness.
//!
//! At a converged static state the second variation of the potential is
//! $\delta\mathbf q^T\hat{\mathbf K}\,\delta\mathbf q$; the equilibrium is stable when the symmetric
//! part $\hat{\mathbf K}_s = \frac12(\hat{\mathbf K} + \hat{\mathbf K}^T)$ is positive definite, and every
//! negative eigenvalue is a direction in which the structure has passed a limit or bifurcation
//! point on its way from the unloaded state (Bathe §6.8; a follower load's non-symmetric part
//! is left out). By Sylvester's law of inertia the count is that of the congruent matrix
//! $\mathbf D^{-1/2}\hat{\mathbf K}_s\mathbf D^{-1/2}$, $\mathbf D = \mathrm{diag}|\hat{K}_{s,ii}|$, which
//! puts lengths, angles and modal coordinates on one scale before the dense symmetric
//! eigensolver (faer's is not scale-invariant).

use crate::assembly::system::System;
use crate::error::SolveError;
use crate::state::State;
use faer::{Mat, Side};

/// The inertia of the tangent stiffness at a static state.
#[derive(Clone, Debug, PartialEq)]
pub struct Stability {
    /// Eigenvalues of the scaled $\hat{\mathbf K}_s$ below $-10^{-9}$ of the largest: directions of
    /// instability.
    pub negative: usize,
    /// Eigenvalues within $\pm10^{-9}$ of the largest: mechanisms or critical points.
    pub zero: usize,
    /// The lowest eigenvalue of the scaled $\hat{\mathbf K}_s$ over the largest.
    pub lowest: f64,
}

impl Stability {
    /// The equilibrium is past a limit or bifurcation point (it is unstable).
    pub fn past_critical_point(&self) -> bool {
        self.negative > 0
    }
}

/// The inertia of $\hat{\mathbf K}_s$ at `state` with loads scaled by `lambda` (module docs).
pub fn stability(system: &System, state: &State, lambda: f64) -> Result<Stability, SolveError> {
    let K = system.matrices(&mut state.clone(), lambda)?.K;
    let n = K.nrows();
    if n == 0 {
        return Ok(Stability {
            negative: 0,
            zero: 0,
            lowest: 0.0,
        });
    }
    let d: Vec<f64> = (0..n)
        .map(|i| {
            let a = K[(i, i)].abs();
            if a > 0.0 {
                1.0 / a.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let Ks = Mat::from_fn(n, n, |i, j| 0.5 * (K[(i, j)] + K[(j, i)]) * d[i] * d[j]);
    let ev = Ks
        .self_adjoint_eigenvalues(Side::Lower)
        .map_err(|_| SolveError::Singular {
            at: crate::error::At::LoadFactor(lambda),
            step: 0,
            what: "eigenvalues of the tangent stiffness did not converge (stability)".into(),
        })?;
    let big = ev.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let tol = 1e-9 * big;
    Ok(Stability {
        negative: ev.iter().filter(|&&x| x < -tol).count(),
        zero: ev.iter().filter(|&&x| x.abs() <= tol).count(),
        lowest: if big > 0.0 { ev[0] / big } else { 0.0 },
    })
}
