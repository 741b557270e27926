//! Rigid-body inertia and mass-field invariants of a reduced body (theory guide §3; Shabana,
//! *Dynamics of Multibody Systems*, ch. 5), and the mass-weighted rigid fit that evaluates
//! the CB modes at the centre of mass (theory guide §4).
//!
//! Everything is computed from the consistent mass matrix $\mathbf M_f$ of the body without
//! supports or spiders, on every element-active dof slot, and from the CB basis on those
//! slots $\mathbf S_f$: for fields interpolated by the shape functions,
//! $\int\rho\,\mathbf a\cdot\mathbf b\,dV = \mathbf a^T\mathbf M_f\mathbf b$. Rigid motions
//! are interpolated exactly by every element (beams included, through their rotation
//! slots), so mass, centre of mass, inertia tensor, $\int\rho\mathbf S$ and
//! $\int\rho\tilde{\mathbf x}\mathbf S$ are exact. The second-order invariants
//! $\int\rho\,x_k\mathbf S_l$ and $\int\rho\,\mathbf S_k^T\mathbf S_l$ place scalar fields in
//! the translation slots only: exact for solids (whose mass matrix is the same scalar matrix
//! in each direction), an approximation for beams (the rotary inertia of the sections is left
//! out of these deformation-dependent terms, and Hermite interpolation sees the scalar field
//! with zero slopes), averaged over the three directions.

use crate::eigen::{gram, symmetric_times};
use crate::error::ReductionError;
use crate::reduced_body::{DenseMatrix, InertiaData};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::Mat;
use fe_model::assembly::assemble_mass;
use fe_model::{DofMap, FeModel, SystemPattern};
use nalgebra::{Matrix3, Matrix6, Vector3};
use rayon::prelude::*;

/// The rigid-motion matrix on the dofs whose full slots (`6 node + k`) are `slots`: columns
/// are translations along $x, y, z$, then rotations about the axes through `c`.
fn rigid_modes(slots: &[usize], nodes: &[[f64; 3]], c: Vector3<f64>) -> Mat<f64> {
    Mat::from_fn(slots.len(), 6, |d, l| {
        let (node, k) = (slots[d] / 6, slots[d] % 6);
        fe_model::rigid::rigid_motion_block(&(Vector3::from(nodes[node]) - c))[(k, l)]
    })
}

/// Mass data and the rigid fit $\boldsymbol\Phi_{com} = (\boldsymbol\Phi_R^T\mathbf M
/// \boldsymbol\Phi_R)^{-1}\boldsymbol\Phi_R^T\mathbf M\mathbf V$ (6 x n) from the CB basis on
/// every slot of the model, `S_full` ($6 n_{nodes} \times n$), with $\mathbf M$ the mass
/// matrix of the model without supports or spiders (module docs).
pub fn inertia_data(model: &FeModel, S_full: &Mat<f64>) -> Result<(InertiaData, Mat<f64>), ReductionError> {
    let mut bare = model.clone();
    bare.supports.clear();
    bare.constraints.clear();
    let dofs = DofMap::new(&bare)?;
    let pattern = SystemPattern::new(&bare, &dofs);
    let M = assemble_mass(&bare, &pattern)?;
    let slots: Vec<usize> = (0..dofs.n_free())
        .map(|d| dofs.full_slot(fe_model::Dof(d as u32)))
        .collect();
    let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    inertia_data_from_mass(M.as_ref(), &slots, &nodes, S_full)
}

/// [`inertia_data`] from a given mass matrix $\mathbf M$ on the dofs whose full slots
/// (`6 node + k`) are `slots` (row $d$ of $\mathbf M$ is slot `slots[d]`), node coordinates
/// `nodes`, and the CB basis on every slot, `S_full` ($6 n_{nodes} \times n$). Used directly
/// for matrices from another FE code (`reduce_external_dofs`, whose docs say what differs).
pub fn inertia_data_from_mass(
    M: SparseColMatRef<'_, usize, f64>,
    slots: &[usize],
    nodes: &[[f64; 3]],
    S_full: &Mat<f64>,
) -> Result<(InertiaData, Mat<f64>), ReductionError> {
    let n_f = slots.len();
    let n = S_full.ncols();
    let S = gather_rows(n_f, n, |d, j| S_full[(slots[d], j)]);
    let par = faer::get_global_parallelism();
    // M is symmetric (assembled with both triangles): the gather product reads it once.
    let MS = symmetric_times(M, S.as_ref(), par);

    // Mass and centre of mass from the rigid modes about the origin: with translations T and
    // rotations W, T^T M W = m c~^T (see the module docs).
    let R0 = rigid_modes(slots, nodes, Vector3::zeros());
    let G0 = gram(R0.as_ref(), symmetric_times(M, R0.as_ref(), par).as_ref(), par);
    let mass = (G0[(0, 0)] + G0[(1, 1)] + G0[(2, 2)]) / 3.0;
    if !(mass > 0.0) {
        return Err(ReductionError::MassNotPositiveDefinite {
            dof: None,
            why: format!("the body's total mass is {mass:.3e}"),
        });
    }
    let c = Vector3::new(G0[(1, 5)], G0[(2, 3)], G0[(0, 4)]) / mass;
    let R = rigid_modes(slots, nodes, c);
    let MR = symmetric_times(M, R.as_ref(), par);
    let G = gram(R.as_ref(), MR.as_ref(), par);
    let inertia_com = Matrix3::from_fn(|i, j| G[(3 + i, 3 + j)]);
    let RtMS = gram(R.as_ref(), MS.as_ref(), par);
    let S_t = DenseMatrix::from_faer(RtMS.subrows(0, 3));
    let S_r = DenseMatrix::from_faer(RtMS.subrows(3, 3));

    // (theory guide §4) Phi_com: the rigid motion that fits each CB mode best in the mass norm.
    let G6 = Matrix6::from_fn(|i, j| G[(i, j)]);
    let G6_inv = G6
        .try_inverse()
        .ok_or_else(|| ReductionError::MassNotPositiveDefinite {
            dof: None,
            why: "the rigid-body mass matrix Phi_R^T M Phi_R is singular".into(),
        })?;
    let Phi_com = Mat::from_fn(6, n, |i, j| (0..6).map(|k| G6_inv[(i, k)] * RtMS[(k, j)]).sum());

    // Second-order invariants from scalar fields placed in translation slot `comp`:
    // P_comp(f)^T M P_comp(g) = f_c^T M_cc g_c, with M_cc the block of M on the dofs of slot
    // `comp` and f_c the field at their nodes. All three fields S_0, S_1, S_2 side by side
    // (F_c, n_c x 3n) make one sparse product and one dense product per direction:
    // S_bar[3k + l] = 1/3 sum_c (F_c^T M_cc F_c)_{kl} and S_x[3k + l] = 1/3 sum_c (X_c^T M_cc F_c)_{kl}.
    let mut S_x = Mat::<f64>::zeros(9, n);
    let mut S_bar: Vec<Mat<f64>> = (0..9).map(|_| Mat::zeros(n, n)).collect();
    let mut position = vec![usize::MAX; n_f];
    for comp in 0..3 {
        let dofs_c: Vec<usize> = (0..n_f).filter(|&d| slots[d] % 6 == comp).collect();
        if dofs_c.is_empty() {
            continue;
        }
        let n_c = dofs_c.len();
        for (r, &d) in dofs_c.iter().enumerate() {
            position[d] = r;
        }
        let M_cc = submatrix(M, &dofs_c, &position);
        for &d in &dofs_c {
            position[d] = usize::MAX;
        }
        let node_c = |r: usize| slots[dofs_c[r]] / 6;
        let F = gather_rows(n_c, 3 * n, |r, col| S_full[(6 * node_c(r) + col / n, col % n)]);
        let X = Mat::from_fn(n_c, 3, |r, k| nodes[node_c(r)][k] - c[k]);
        let MF = symmetric_times(M_cc.as_ref(), F.as_ref(), par);
        let G = gram(F.as_ref(), MF.as_ref(), par);
        let XtMF = gram(X.as_ref(), MF.as_ref(), par);
        for k in 0..3 {
            for l in 0..3 {
                S_bar[3 * k + l] += G.submatrix(k * n, l * n, n, n) * faer::Scale(1.0 / 3.0);
                for j in 0..n {
                    S_x[(3 * k + l, j)] += XtMF[(k, l * n + j)] / 3.0;
                }
            }
        }
    }
    Ok((
        InertiaData {
            mass,
            center_of_mass: [c.x, c.y, c.z],
            inertia_com: [
                [inertia_com[(0, 0)], inertia_com[(0, 1)], inertia_com[(0, 2)]],
                [inertia_com[(1, 0)], inertia_com[(1, 1)], inertia_com[(1, 2)]],
                [inertia_com[(2, 0)], inertia_com[(2, 1)], inertia_com[(2, 2)]],
            ],
            S_t,
            S_r,
            S_x: DenseMatrix::from_faer(S_x.as_ref()),
            S_bar: S_bar.iter().map(|m| DenseMatrix::from_faer(m.as_ref())).collect(),
        },
        Phi_com,
    ))
}

/// `Mat::from_fn(nrows, ncols, f)` with the columns filled in parallel: for the gathers of
/// the basis ($\mathbf V$, $\mathbf S$, their rows), millions of entries for a large body.
pub(crate) fn gather_rows(nrows: usize, ncols: usize, f: impl Fn(usize, usize) -> f64 + Sync) -> Mat<f64> {
    let mut A = Mat::<f64>::zeros(nrows, ncols);
    A.par_col_iter_mut()
        .enumerate()
        .for_each(|(j, col)| col.iter_mut().enumerate().for_each(|(i, a)| *a = f(i, j)));
    A
}

/// The block of `M` on the rows and columns `rows` (sorted ascending), with `position[d]` the
/// index of dof `d` in `rows` (`usize::MAX` if absent).
fn submatrix(M: SparseColMatRef<'_, usize, f64>, rows: &[usize], position: &[usize]) -> SparseColMat<usize, f64> {
    let mut col_ptr = Vec::with_capacity(rows.len() + 1);
    let mut row_idx = Vec::new();
    let mut values = Vec::new();
    col_ptr.push(0);
    for &d in rows {
        for (&i, &v) in M.row_idx_of_col_raw(d).iter().zip(M.val_of_col(d)) {
            if position[i] != usize::MAX {
                row_idx.push(position[i]);
                values.push(v);
            }
        }
        col_ptr.push(row_idx.len());
    }
    let symbolic = SymbolicSparseColMat::new_unsorted_checked(rows.len(), rows.len(), col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}
