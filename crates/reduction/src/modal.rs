//! Full-model modal analysis of an FE model, clamped or free, by the sparse shift-invert
//! eigensolver (theory guide §3; [`crate::eigen`]). The dense path `fe_model::modal_dense` serves
//! only small models.

use crate::eigen::{EigenSettings, FactorSettings, Shift, ShiftInvert};
use crate::error::ReductionError;
use fe_model::{assemble, dof_points, DofMap, FeModel, FillOrdering, ModalSolution, SystemPattern};

/// The `n_modes` lowest modes of `model`, mass-normalised, on every node.
///
/// `shift`: [`Shift::Zero`] for a supported model; [`Shift::Auto`] (or a negative value)
/// when the model may have rigid-body modes. Each pair's relative residual is checked by the
/// eigensolver; the residuals are returned beside the modes.
pub fn modal_sparse(
    model: &FeModel,
    n_modes: usize,
    shift: Shift,
) -> Result<(ModalSolution, Vec<f64>), ReductionError> {
    let dofs = DofMap::new(model)?;
    let pattern = SystemPattern::new(model, &dofs);
    let a = assemble(model, &pattern)?;
    let (K, M) = (a.K.as_ref(), a.M.as_ref());
    // Nested dissection on the node positions for large models (fe_model::ordering).
    let points = dof_points(model, &dofs);
    let factor = ShiftInvert::with_settings(
        K,
        M,
        shift.resolve(K, M)?,
        Some(&points),
        FillOrdering::Auto,
        &FactorSettings::DOUBLE,
    )?;
    let solution = factor.lowest_modes(K, M, &EigenSettings::new(n_modes, shift))?;
    let n = dofs.n_free();
    let omega = solution
        .eigenvalues
        .iter()
        .map(|&l| if l >= 0.0 { l.sqrt() } else { -(-l).sqrt() })
        .collect();
    let shapes = (0..solution.eigenvalues.len())
        .map(|j| dofs.expand(&(0..n).map(|i| solution.vectors[(i, j)]).collect::<Vec<_>>()))
        .collect();
    Ok((ModalSolution { omega, shapes }, solution.residuals))
}
