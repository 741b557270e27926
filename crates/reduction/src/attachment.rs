//! Static correction for loads inside a body: attachment modes of named load points.
//!
//! A force on a node that is not an interface excites the fixed-interface modes through
//! $\boldsymbol\Phi_i^T\mathbf f$, and the quasi-static response $\mathbf K_{ii}^{-1}\mathbf f$
//! converges slowly in the number of modes (the local stress under the load needs the high
//! modes). The residual-flexibility remedy (modal truncation augmentation \[Dickens1997\];
//! \[CraigKurdila2006\] §14.5 on residual flexibility; theory guide, point loads inside a
//! body, (6.10)) adds
//! the static response to a unit load on each dof of the load point, with the interfaces held
//! (the attachment modes $\mathbf X = \mathbf K_{ii}^{-1}\mathbf F$), made $\mathbf M$-orthogonal
//! to the kept modes:
//! $$\hat{\mathbf X} = (\mathbf I - \boldsymbol\Phi_i\boldsymbol\Phi_i^T\mathbf M_{ii})\mathbf X,$$
//! and then orthogonal among themselves by the small eigenproblem
//! $\hat{\mathbf X}^T\mathbf K_{ii}\hat{\mathbf X}\mathbf y = \hat\omega^2\hat{\mathbf X}^T
//! \mathbf M_{ii}\hat{\mathbf X}\mathbf y$. Since $\mathbf K_{ii}\boldsymbol\Phi_i =
//! \mathbf M_{ii}\boldsymbol\Phi_i\boldsymbol\Omega^2$, $\mathbf M$-orthogonality to the modes is
//! also $\mathbf K$-orthogonality, so the augmented basis keeps $\mathbf K_{CB}$ and
//! $\mathbf M_{CB}$ diagonal in the modal block, and the vectors enter the body as further
//! "modes" with Rayleigh frequencies $\hat\omega$. The span of the basis then holds
//! $\mathbf K_{ii}^{-1}\mathbf F$ exactly: the static response to any load at the points,
//! hence its stress, is exact whatever the number of modes.
//!
//! The same correction serves the interfaces' own inertia ([`CbSettings::inertia_correction`](crate::CbSettings)):
//! when the interfaces accelerate, the interior carries the inertia load
//! $-(\mathbf M_{ii}\boldsymbol\Psi + \mathbf M_{ib})\ddot{\mathbf u}_b$ of the constraint modes,
//! whose quasi-static response (the axial force of a rod under its own distributed inertia)
//! the fixed-interface modes represent only as a slowly converging series (theory guide,
//! static correction for the interfaces' inertia, (3.10)). With
//! $\mathbf F = \mathbf M_{ii}\boldsymbol\Psi + \mathbf M_{ib}$ the span holds that response
//! exactly.
//!
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\mathbf F$ | `loads` | unit loads on the load points' internal dofs and the constraint modes' inertia loads, $n_i \times k$ |
//! | $\mathbf X$, $\hat{\mathbf X}$ | `X` | attachment modes, then made orthogonal |
//! | $\hat\omega$ | `omega` | their Rayleigh frequencies |

#![allow(non_snake_case)]

use crate::eigen::{symmetric_times, ShiftInvert};
use crate::error::ReductionError;
use faer::sparse::SparseColMatRef;
use faer::Mat;

/// The static correction vectors of the interior loads `loads` (columns: unit loads on
/// load-point dofs, inertia loads of the constraint modes), $\mathbf X = \mathbf K_{ii}^{-1}\mathbf F$,
/// orthogonalised against the $\mathbf M$-orthonormal modes `Phi_i` and among themselves
/// (module docs): returned $\mathbf M$-orthonormal with their circular frequencies,
/// ascending. Directions already in the span of the modes (to $10^{-10}$ of their mass norm)
/// are dropped, so fewer than `loads.ncols()` vectors may come back.
///
/// # Errors
/// [`ReductionError::InvalidSettings`] if the small eigenproblem fails (non-finite values);
/// [`ReductionError::RefinementFailed`] from the refined solves of a single-precision factor.
pub fn static_correction(
    factor: &ShiftInvert,
    K_ii: SparseColMatRef<'_, usize, f64>,
    M_ii: SparseColMatRef<'_, usize, f64>,
    Phi_i: &Mat<f64>,
    loads: Mat<f64>,
) -> Result<(Mat<f64>, Vec<f64>), ReductionError> {
    let (ni, k) = loads.shape();
    if k == 0 {
        return Ok((Mat::zeros(ni, 0), Vec::new()));
    }
    let par = faer::get_global_parallelism();
    let mut X = loads;
    factor.solve_refined(K_ii, M_ii, X.as_mut(), &|| {
        "the static correction vectors (attachment modes)".into()
    })?;
    // Gram-Schmidt against the modes, twice (Kahan's "twice is enough") for round-off.
    for _ in 0..2 {
        if Phi_i.ncols() > 0 {
            let MX = symmetric_times(M_ii, X.as_ref(), par);
            let C = Phi_i.transpose() * &MX;
            X -= Phi_i * &C;
        }
    }
    let KX = symmetric_times(K_ii, X.as_ref(), par);
    let MX = symmetric_times(M_ii, X.as_ref(), par);
    let Kr = X.transpose() * &KX;
    let Mr = X.transpose() * &MX;
    let sym = |A: &Mat<f64>| Mat::from_fn(k, k, |i, j| 0.5 * (A[(i, j)] + A[(j, i)]));
    let fail = |what: String| ReductionError::InvalidSettings {
        what: format!("static correction vectors (attachment modes): {what}"),
    };
    // Whiten M_r, dropping directions the modes already span.
    let (mu, Q) = fe_model::scaled_self_adjoint_eigen(sym(&Mr).as_ref()).map_err(|e| fail(e.to_string()))?;
    let largest = mu.iter().copied().fold(0.0f64, f64::max);
    // 1e-10 of the largest mass norm: a direction whose residual after the projection is that
    // small is in the span of the modes up to round-off of the solve.
    let keep: Vec<usize> = (0..k).filter(|&i| mu[i] > 1e-10 * largest).collect();
    let W = Mat::from_fn(k, keep.len(), |i, j| Q[(i, keep[j])] / mu[keep[j]].sqrt());
    let Kw = W.transpose() * sym(&Kr) * &W;
    let r = keep.len();
    let Kw = Mat::from_fn(r, r, |i, j| 0.5 * (Kw[(i, j)] + Kw[(j, i)]));
    let (lambda, R) = fe_model::scaled_self_adjoint_eigen(Kw.as_ref()).map_err(|e| fail(e.to_string()))?;
    let mut order: Vec<usize> = (0..r).collect();
    order.sort_by(|&a, &b| lambda[a].total_cmp(&lambda[b]));
    let Y = X * W * R;
    let vectors = Mat::from_fn(ni, r, |i, j| Y[(i, order[j])]);
    let omega = order.iter().map(|&j| lambda[j].max(0.0).sqrt()).collect();
    Ok((vectors, omega))
}
