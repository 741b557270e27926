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
//! | symbol | Rust | meaning |
//! |---|---|---|
//! | $\mathbf F$ | `unit` | unit loads on the load points' internal dofs, $n_i \times k$ |
//! | $\mathbf X$, $\hat{\mathbf X}$ | `X` | attachment modes, then made orthogonal |
//! | $\hat\omega$ | `omega` | their Rayleigh frequencies |

#![allow(non_snake_case)]

use crate::eigen::{symmetric_times, ShiftInvert};
use crate::error::ReductionError;
use faer::sparse::SparseColMatRef;
use faer::Mat;

/// The attachment modes for unit loads on the internal dofs `load_dofs` (positions in the
/// internal numbering), orthogonalised against the $\mathbf M$-orthonormal modes `Phi_i` and
/// among themselves (module docs): returned $\mathbf M$-orthonormal with their circular
/// frequencies, ascending. Directions already in the span of the modes (to $10^{-10}$ of
/// their mass norm) are dropped, so fewer than `load_dofs.len()` vectors may come back.
///
/// # Errors
/// [`ReductionError::InvalidSettings`] if the small eigenproblem fails (non-finite values);
/// [`ReductionError::RefinementFailed`] from the refined solves of a single-precision factor.
pub fn attachment_modes(
    factor: &ShiftInvert,
    K_ii: SparseColMatRef<'_, usize, f64>,
    M_ii: SparseColMatRef<'_, usize, f64>,
    Phi_i: &Mat<f64>,
    load_dofs: &[usize],
) -> Result<(Mat<f64>, Vec<f64>), ReductionError> {
    let ni = K_ii.nrows();
    let k = load_dofs.len();
    if k == 0 {
        return Ok((Mat::zeros(ni, 0), Vec::new()));
    }
    let par = faer::get_global_parallelism();
    let mut X = Mat::<f64>::zeros(ni, k);
    for (j, &d) in load_dofs.iter().enumerate() {
        X[(d, j)] = 1.0;
    }
    factor.solve_refined(K_ii, M_ii, X.as_mut(), &|| {
        "the attachment modes of the load points".into()
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
        what: format!("load-point attachment modes: {what}"),
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
