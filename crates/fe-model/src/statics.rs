//! Linear statics: $\mathbf K \mathbf u_f = \mathbf T^T \mathbf f$ by sparse Cholesky (faer),
//! then displacements of every node and reactions at the supports.

use crate::assembly::{assemble, element_matrices};
use crate::dof::{DofMap, DofStatus};
use crate::error::{FeError, DOF_NAMES};
use crate::mesh::NodeId;
use crate::model::{FeModel, NodalLoad};
use crate::ordering::{dof_points, FillOrdering};
use crate::pattern::{element_slots, SystemPattern};
use crate::sparse_cholesky::{CholeskyError, SparseCholesky};
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::Mat;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Result of a linear static analysis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StaticSolution {
    /// Displacements and rotations of every node, $[u_x, u_y, u_z, \theta_x, \theta_y, \theta_z]$.
    pub displacements: Vec<[f64; 6]>,
    /// Support reactions (force, moment on the structure from the support), one entry per
    /// node with at least one supported dof; unsupported components are zero.
    pub reactions: Vec<(NodeId, [f64; 6])>,
    /// Relative residual $\|\mathbf K \mathbf u_f - \mathbf f\| / \|\mathbf f\|$ of the solve.
    pub relative_residual: f64,
}

/// Sparse Cholesky factor of a symmetric positive definite matrix on the free dofs of `dofs`,
/// with the fill-reducing `ordering` ([`FillOrdering::Auto`]: nested dissection on the dof
/// positions `points` for large models, see [`crate::ordering`]).
///
/// A non-positive pivot means the structure can move without straining; the error names
/// the node and dof where the factorisation broke down (mapped back through the
/// fill-reducing permutation).
pub fn cholesky(
    A: SparseColMatRef<'_, usize, f64>,
    dofs: &DofMap,
    points: Option<&[[f64; 3]]>,
    ordering: FillOrdering,
) -> Result<SparseCholesky, FeError> {
    SparseCholesky::new(A, points, ordering).map_err(|e| match e {
        CholeskyError::NonPositivePivot { dof } => {
            let (node_tag, dof) = dofs.describe(crate::dof::Dof(dof as u32));
            FeError::Mechanism { node_tag, dof }
        }
        other => FeError::LinearAlgebra(other.to_string()),
    })
}

/// One element's full slots and its forces at them.
type SlotForces = (Vec<usize>, Vec<f64>);

/// Internal forces $\sum_e \mathbf K_e \mathbf u_e$ at every node's six dofs, for
/// displacements `u` of every node.
pub fn internal_forces(model: &FeModel, u: &[[f64; 6]]) -> Result<Vec<[f64; 6]>, FeError> {
    let per_element: Vec<Result<SlotForces, FeError>> = (0..model.elements.len())
        .into_par_iter()
        .map(|e| {
            let m = element_matrices(model, e)?;
            let slots = element_slots(&model.elements[e]);
            let u_e = nalgebra::DVector::from_iterator(slots.len(), slots.iter().map(|&s| u[s / 6][s % 6]));
            let f_e = &m.K_e * u_e;
            Ok((slots, f_e.as_slice().to_vec()))
        })
        .collect();
    let mut f = vec![[0.0; 6]; model.node_count()];
    for item in per_element {
        let (slots, f_e) = item?;
        for (s, v) in slots.into_iter().zip(f_e) {
            f[s / 6][s % 6] += v;
        }
    }
    Ok(f)
}

/// Collects nodal loads into one `[f64; 6]` per node, checking the nodes exist.
pub fn load_vector(model: &FeModel, loads: &[NodalLoad]) -> Result<Vec<[f64; 6]>, FeError> {
    let mut f = vec![[0.0; 6]; model.node_count()];
    for (i, load) in loads.iter().enumerate() {
        model.check_node(load.node, &format!("load {i}"))?;
        let entry = &mut f[load.node.index()];
        for k in 0..3 {
            entry[k] += load.force[k];
            entry[k + 3] += load.moment[k];
        }
    }
    Ok(f)
}

/// Solves the linear static problem for nodal loads.
pub fn solve_static(model: &FeModel, loads: &[NodalLoad]) -> Result<StaticSolution, FeError> {
    let dofs = DofMap::new(model)?;
    let pattern = SystemPattern::new(model, &dofs);
    let assembled = assemble(model, &pattern)?;
    let f_full = load_vector(model, loads)?;
    let f = dofs.restrict(&f_full, "load")?;
    let points = dof_points(model, &dofs);
    let u_f = solve_with(&assembled.K, &dofs, &f, Some(&points), FillOrdering::Auto)?;
    let relative_residual = relative_residual(&assembled.K, &u_f, &f);
    // A singular K can pass the factorisation with a tiny positive pivot; the solve then
    // has a large residual. 1e-8 is far above the round-off of a well-posed solve (~1e-14
    // times the condition number for the models this path serves).
    if !(relative_residual <= 1e-8) {
        return Err(FeError::LinearAlgebra(format!(
            "the static solve has relative residual {relative_residual:.3e}: the stiffness is singular or nearly so (check supports)"
        )));
    }
    let displacements = dofs.expand(&u_f);
    let f_int = internal_forces(model, &displacements)?;
    let reactions = support_reactions(model, &dofs, &f_int, &f_full);
    Ok(StaticSolution {
        displacements,
        reactions,
        relative_residual,
    })
}

/// Reactions at the supported dofs: the out-of-balance force $\mathbf f_{int} - \mathbf f_{ext}$
/// of every slot, with the residual of each dependent slot carried to the dofs its
/// constraint names ($\mathbf T^T$ applied to the residual, supported dofs kept). A support
/// on a spider's interface node thus receives the force its spider carries.
pub fn support_reactions(
    model: &FeModel,
    dofs: &DofMap,
    f_int: &[[f64; 6]],
    f_ext: &[[f64; 6]],
) -> Vec<(NodeId, [f64; 6])> {
    let mut residual: Vec<[f64; 6]> = f_int
        .iter()
        .zip(f_ext)
        .map(|(a, b)| std::array::from_fn(|k| a[k] - b[k]))
        .collect();
    for c in &model.constraints {
        let (node, k) = (c.dependent.0.index(), c.dependent.1 as usize);
        let r = residual[node][k];
        for &(term_node, term_k, coef) in &c.terms {
            residual[term_node.index()][term_k as usize] += coef * r;
        }
    }
    let mut reactions = Vec::new();
    for (node, r_node) in residual.iter().enumerate() {
        let id = NodeId(node as u32);
        let mut r = [0.0; 6];
        let mut any = false;
        for k in 0..6 {
            if dofs.status(id, k) == DofStatus::Supported {
                r[k] = r_node[k];
                any = true;
            }
        }
        if any {
            reactions.push((id, r));
        }
    }
    reactions
}

/// Solves $\mathbf K \mathbf u = \mathbf f$ on the free dofs ([`cholesky`] says what
/// `points` and `ordering` choose).
pub fn solve_with(
    K: &SparseColMat<usize, f64>,
    dofs: &DofMap,
    f: &[f64],
    points: Option<&[[f64; 3]]>,
    ordering: FillOrdering,
) -> Result<Vec<f64>, FeError> {
    let llt = cholesky(K.as_ref(), dofs, points, ordering)?;
    let mut rhs = Mat::from_fn(f.len(), 1, |i, _| f[i]);
    llt.solve_in_place(rhs.as_mut());
    let u: Vec<f64> = (0..f.len()).map(|i| rhs[(i, 0)]).collect();
    if u.iter().any(|v| !v.is_finite()) {
        return Err(FeError::LinearAlgebra(
            "the static solve produced non-finite displacements".into(),
        ));
    }
    Ok(u)
}

/// $\|\mathbf K \mathbf u - \mathbf f\| / \|\mathbf f\|$ (or the absolute residual when
/// $\mathbf f = 0$).
pub fn relative_residual(K: &SparseColMat<usize, f64>, u: &[f64], f: &[f64]) -> f64 {
    let u_mat = Mat::from_fn(u.len(), 1, |i, _| u[i]);
    let Ku = K * &u_mat;
    let r: f64 = (0..f.len()).map(|i| (Ku[(i, 0)] - f[i]).powi(2)).sum::<f64>().sqrt();
    let nf: f64 = f.iter().map(|v| v * v).sum::<f64>().sqrt();
    if nf > 0.0 {
        r / nf
    } else {
        r
    }
}

/// Name of dof `k`, re-exported for callers that print results.
pub fn dof_name(k: usize) -> &'static str {
    DOF_NAMES[k]
}
