//! Geometric stiffening of a reduced body: the reduced geometric stiffness matrices
//! $\mathbf G_k = \mathbf V^T\mathbf K_G(\boldsymbol\sigma(\mathbf V\mathbf e_k))\mathbf V$,
//! $k = 1 \dots n$, stored as [`ReducedBody::geometric_stiffness`](crate::ReducedBody).
//!
//! With them the strain energy of the body in its floating frame gains the cubic term
//! $$U_3 = \tfrac12\sum_k q_k\,\mathbf q^T\mathbf G_k\mathbf q
//! = \int_V \boldsymbol\sigma(\mathbf V\mathbf q) : \tfrac12(\nabla\mathbf V\mathbf q)^T
//! (\nabla\mathbf V\mathbf q)\, dV,$$
//! the second-order part of the Green-Lagrange strain under the linear stress: the axial
//! force of a rod changes its bending stiffness (the "geometric stiffening" of Simpack's SID
//! and Adams Flex; Wallrapp, "Standardization of flexible body modeling in multibody system
//! codes, Part I", Mech. Struct. Mach. 22 (1994) 283-304, the geometric stiffness terms of
//! the SID).
//!
//! # Cost
//! One pass over the elements (rayon), each element's basis rows $\mathbf V_e$ gathered once;
//! each basis vector's stress at each quadrature point is computed once, and the element's
//! share of all $\mathbf G_k$ is one matrix product
//! ([`fe_model::element_geometric_tensor_into`]): about $6Qn^2(n+1)$ flops per solid element
//! with $Q$ quadrature points. No global $\mathbf K_G$ is formed.

#![allow(non_snake_case)]

use crate::error::ReductionError;
use crate::reduced_body::DenseMatrix;
use faer::MatRef;
use fe_model::{element_dof_slots, element_geometric_tensor_into, packed_pair, FeError, FeModel};
use nalgebra::DMatrix;
use rayon::prelude::*;

/// The $n$ reduced geometric stiffness matrices $\mathbf G_k$ ($n \times n$, symmetric) of the
/// basis `S_full` ($6 n_{nodes} \times n$: the CB basis on every node's six dof slots,
/// $\mathbf T\mathbf V$, dependent slots following their spiders), module docs.
///
/// Each $\mathbf G_k$ is assembled from its upper triangle, so it is symmetric exactly; the
/// check is that every entry is finite.
///
/// # Errors
/// [`ReductionError::Fe`] or [`ReductionError::InvalidFeModel`] for an element whose geometry or properties give no geometric
/// stiffness (naming the element), or a non-finite entry (naming $k$, $l$, $p$).
pub fn reduced_geometric_stiffness(
    model: &FeModel,
    S_full: MatRef<'_, f64>,
) -> Result<Vec<DenseMatrix>, ReductionError> {
    let n = S_full.ncols();
    assert_eq!(S_full.nrows(), 6 * model.node_count(), "S_full has six rows per node");
    let n_pairs = n * (n + 1) / 2;
    // Each piece of elements accumulates into its own n(n+1)/2 x n buffer (4 MB at n = 100):
    // a few pieces per thread balance the load without a buffer per element.
    let n_elements = model.elements.len();
    let piece = n_elements.div_ceil(4 * rayon::current_num_threads().max(1)).max(1);
    let packed = (0..n_elements)
        .into_par_iter()
        .with_min_len(piece)
        .try_fold(
            || DMatrix::<f64>::zeros(n_pairs, n),
            |mut out, e| -> Result<DMatrix<f64>, ReductionError> {
                let slots = element_dof_slots(&model.elements[e]);
                let V_e = DMatrix::from_fn(slots.len(), n, |r, c| S_full[(slots[r], c)]);
                element_geometric_tensor_into(model, e, &V_e, &mut out)
                    .map_err(|err| ReductionError::Fe(FeError::Element(err)))?;
                Ok(out)
            },
        )
        .try_reduce(|| DMatrix::<f64>::zeros(n_pairs, n), |a, b| Ok(a + b))?;
    (0..n)
        .map(|k| {
            let mut G_k = DenseMatrix::zeros(n, n);
            for p in 0..n {
                for l in 0..=p {
                    let value = packed[(packed_pair(l, p), k)];
                    if !value.is_finite() {
                        return Err(ReductionError::InvalidFeModel {
                            what: format!(
                                "geometric stiffness: entry ({l}, {p}) of G_{k} is {value} (a non-finite basis or material value)"
                            ),
                        });
                    }
                    G_k.data[l + p * n] = value;
                    G_k.data[p + l * n] = value;
                }
            }
            Ok(G_k)
        })
        .collect()
}
