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
use fe_model::assembly::assemble_mass_with_pattern;
use fe_model::{DofMap, FeModel, SystemPattern};
use nalgebra::{Matrix3, Matrix6, Vector3};
use rayon::prelude::*;

/// The rigid-motion matrix on the dofs whose full slots (`6 node + k`) are `slots`: columns
/// are translations along $x, y, z$, then rotations about the axes through `c`.
fn rigid_modes(slots: &[usize], nodes: &[[f64; 3]], c: Vector3<f64>) -> Mat<f64> {
    gather_rows(slots.len(), 6, |d, l| {
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
    let M = assemble_mass_with_pattern(&bare, SystemPattern::new(&bare, &dofs))?;
    // Only the nonzero entries from here on (see `inertia_data_nonzero`): M itself is freed.
    let M = nonzero_entries(M.as_ref());
    let slots: Vec<usize> = (0..dofs.n_free())
        .map(|d| dofs.full_slot(fe_model::Dof(d as u32)))
        .collect();
    let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
    inertia_data_nonzero(M.as_ref(), &slots, &nodes, S_full, faer::get_global_parallelism())
}

/// The stored entries of `M` that are not zero. A solid's mass couples only equal
/// displacement components: on the stiffness's pattern two thirds of the stored entries are
/// exact zeros, which the products would read for nothing (leaving them out changes no sum).
fn nonzero_entries(M: SparseColMatRef<'_, usize, f64>) -> SparseColMat<usize, f64> {
    let all: Vec<usize> = (0..M.ncols()).collect();
    select_entries(M, M.nrows(), &all, |r, v| (v != 0.0).then_some(r))
}

/// [`inertia_data`] from a given mass matrix $\mathbf M$ on the dofs whose full slots
/// (`6 node + k`) are `slots` (row $d$ of $\mathbf M$ is slot `slots[d]`), node coordinates
/// `nodes`, and the CB basis on every slot, `S_full` ($6 n_{nodes} \times n$). Used directly
/// for matrices from another FE code (`reduce_external_dofs`, whose docs say what differs).
///
/// Every sum over the dofs has a fixed order (the products row by row, the Gram products by
/// fixed blocks of rows added in order): the result is the same bit for bit for any number
/// of threads.
pub fn inertia_data_from_mass(
    M: SparseColMatRef<'_, usize, f64>,
    slots: &[usize],
    nodes: &[[f64; 3]],
    S_full: &Mat<f64>,
) -> Result<(InertiaData, Mat<f64>), ReductionError> {
    inertia_data_nonzero(
        nonzero_entries(M).as_ref(),
        slots,
        nodes,
        S_full,
        faer::get_global_parallelism(),
    )
}

/// [`inertia_data_from_mass`] for a mass matrix `M` without stored zeros ([`nonzero_entries`]),
/// with the parallelism `par` of its products.
fn inertia_data_nonzero(
    M: SparseColMatRef<'_, usize, f64>,
    slots: &[usize],
    nodes: &[[f64; 3]],
    S_full: &Mat<f64>,
    par: faer::Par,
) -> Result<(InertiaData, Mat<f64>), ReductionError> {
    let n_f = slots.len();
    let n = S_full.ncols();
    let S = gather_rows(n_f, n, |d, j| S_full[(slots[d], j)]);
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
    // F_c and X_c depend only on the nodes of the dofs of slot `comp`: where those and M_cc
    // equal the previous direction's (a solid's mass is the same scalar matrix in each
    // direction), its products are the same bit for bit and are not computed again.
    let mut S_x = Mat::<f64>::zeros(9, n);
    let mut S_bar: Vec<Mat<f64>> = (0..9).map(|_| Mat::zeros(n, n)).collect();
    let mut position = vec![usize::MAX; n_f];
    let mut previous: Option<DirectionProducts> = None;
    for comp in 0..3 {
        let dofs_c: Vec<usize> = (0..n_f).filter(|&d| slots[d] % 6 == comp).collect();
        if dofs_c.is_empty() {
            continue;
        }
        let n_c = dofs_c.len();
        for (r, &d) in dofs_c.iter().enumerate() {
            position[d] = r;
        }
        let M_cc = select_entries(M, n_c, &dofs_c, |i, _| (position[i] != usize::MAX).then(|| position[i]));
        for &d in &dofs_c {
            position[d] = usize::MAX;
        }
        let nodes_c: Vec<usize> = dofs_c.iter().map(|&d| slots[d] / 6).collect();
        let same = previous
            .as_ref()
            .is_some_and(|p| p.nodes_c == nodes_c && same_matrix(p.M_cc.as_ref(), M_cc.as_ref()));
        if !same {
            let F = gather_rows(n_c, 3 * n, |r, col| S_full[(6 * nodes_c[r] + col / n, col % n)]);
            let X = Mat::from_fn(n_c, 3, |r, k| nodes[nodes_c[r]][k] - c[k]);
            let MF = symmetric_times(M_cc.as_ref(), F.as_ref(), par);
            let G = gram(F.as_ref(), MF.as_ref(), par);
            let XtMF = gram(X.as_ref(), MF.as_ref(), par);
            previous = Some(DirectionProducts { nodes_c, M_cc, G, XtMF });
        }
        let DirectionProducts { G, XtMF, .. } = previous.as_ref().expect("computed above");
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

/// The products of one direction's scalar fields in [`inertia_data_nonzero`]: the nodes of the
/// dofs of its translation slot, its block $\mathbf M_{cc}$, $\mathbf F_c^T\mathbf M_{cc}
/// \mathbf F_c$ and $\mathbf X_c^T\mathbf M_{cc}\mathbf F_c$.
struct DirectionProducts {
    nodes_c: Vec<usize>,
    M_cc: SparseColMat<usize, f64>,
    G: Mat<f64>,
    XtMF: Mat<f64>,
}

/// Whether `A` and `B` have the same shape, stored entries and values, bit for bit.
fn same_matrix(A: SparseColMatRef<'_, usize, f64>, B: SparseColMatRef<'_, usize, f64>) -> bool {
    A.nrows() == B.nrows()
        && A.ncols() == B.ncols()
        && A.symbolic().col_ptr() == B.symbolic().col_ptr()
        && A.symbolic().col_nnz() == B.symbolic().col_nnz()
        && A.symbolic().row_idx() == B.symbolic().row_idx()
        && A.val().len() == B.val().len()
        && A.val().par_iter().zip(B.val()).all(|(a, b)| a.to_bits() == b.to_bits())
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

/// The columns `cols` of `A` ($n_{rows}$ rows), each with the stored entries that
/// `keep(row, value)` maps to a row (`None`: left out), in `A`'s order: blocks and filtered
/// copies of a sparse matrix, built column by column in parallel.
pub(crate) fn select_entries(
    A: SparseColMatRef<'_, usize, f64>,
    nrows: usize,
    cols: &[usize],
    keep: impl Fn(usize, f64) -> Option<usize> + Sync,
) -> SparseColMat<usize, f64> {
    let entries = |c: usize| {
        A.row_idx_of_col_raw(c)
            .iter()
            .zip(A.val_of_col(c))
            .filter_map(|(&i, &v)| keep(i, v).map(|r| (r, v)))
    };
    let counts: Vec<usize> = cols.par_iter().map(|&c| entries(c).count()).collect();
    let mut col_ptr = Vec::with_capacity(cols.len() + 1);
    col_ptr.push(0);
    for k in &counts {
        col_ptr.push(col_ptr.last().expect("starts with 0") + k);
    }
    let nnz = col_ptr[cols.len()];
    let (mut row_idx, mut values) = (vec![0usize; nnz], vec![0.0; nnz]);
    let mut pieces: Vec<(&mut [usize], &mut [f64])> = Vec::with_capacity(cols.len());
    let (mut rows_rest, mut values_rest) = (row_idx.as_mut_slice(), values.as_mut_slice());
    for &k in &counts {
        let (r, r_tail) = rows_rest.split_at_mut(k);
        let (v, v_tail) = values_rest.split_at_mut(k);
        pieces.push((r, v));
        (rows_rest, values_rest) = (r_tail, v_tail);
    }
    pieces
        .par_iter_mut()
        .zip(cols.par_iter())
        .for_each(|((rows, vals), &c)| {
            for ((row, val), (r, v)) in rows.iter_mut().zip(vals.iter_mut()).zip(entries(c)) {
                (*row, *val) = (r, v);
            }
        });
    let symbolic = SymbolicSparseColMat::new_unsorted_checked(nrows, cols.len(), col_ptr, None, row_idx);
    SparseColMat::new(symbolic, values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fe_model::assembly::assemble_mass;
    use fe_model::{add_interface_on_set, box_mesh, solid_model, CellKind, IsotropicMaterial, MassKind, SpiderKind};

    /// The mass data computed in parallel (3 threads: products by rows, Gram products by
    /// blocks) equal those of the sequential products bit for bit, on a hex8 and a tet10 block
    /// with a pseudo-random basis of 7 columns, and the mass against its analytic value:
    /// every sum has the same order whatever the threads, so no round-off tolerance is
    /// needed between them.
    #[test]
    fn parallel_invariants_equal_the_sequential_ones_bit_for_bit() {
        let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
        for kind in [CellKind::Hex8, CellKind::Tet10] {
            // More rows than one block of the Gram products (1024).
            let mesh = box_mesh(kind, [1.6, 0.6, 0.6], [16, 6, 6]).unwrap();
            let mut model = solid_model(mesh, steel.clone(), MassKind::Consistent).unwrap();
            add_interface_on_set(&mut model, "root", "x0", None, SpiderKind::Rbe2).unwrap();
            let mut state = 7u64;
            let S_full = Mat::from_fn(6 * model.node_count(), 7, |_, _| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            });
            let mut bare = model.clone();
            bare.constraints.clear();
            let dofs = DofMap::new(&bare).unwrap();
            assert!(dofs.n_free() > 2 * crate::eigen::GS_ROWS, "several row blocks");
            let pattern = SystemPattern::new(&bare, &dofs);
            let M = nonzero_entries(assemble_mass(&bare, &pattern).unwrap().as_ref());
            let slots: Vec<usize> = (0..dofs.n_free())
                .map(|d| dofs.full_slot(fe_model::Dof(d as u32)))
                .collect();
            let nodes: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|x| [x.x, x.y, x.z]).collect();
            let sequential = inertia_data_nonzero(M.as_ref(), &slots, &nodes, &S_full, faer::Par::Seq).unwrap();
            let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
            let parallel = pool
                .install(|| inertia_data_nonzero(M.as_ref(), &slots, &nodes, &S_full, faer::Par::rayon(3)))
                .unwrap();
            let (a, b) = (&sequential.0, &parallel.0);
            assert_eq!(a.mass.to_bits(), b.mass.to_bits());
            assert_eq!(a.center_of_mass, b.center_of_mass);
            assert_eq!(a.inertia_com, b.inertia_com);
            for (x, y) in [(&a.S_t, &b.S_t), (&a.S_r, &b.S_r), (&a.S_x, &b.S_x)]
                .into_iter()
                .chain(a.S_bar.iter().zip(&b.S_bar))
            {
                assert_eq!(x.data, y.data, "{kind:?}");
            }
            assert_eq!(sequential.1, parallel.1, "Phi_com, {kind:?}");
            // 1.6 x 0.6 x 0.6 m of steel; the sum of the element masses to round-off.
            let mass = 7850.0 * 1.6 * 0.6 * 0.6;
            assert!(
                (a.mass - mass).abs() < 1e-12 * mass,
                "{kind:?}: mass {} against {mass}",
                a.mass
            );
        }
    }

    /// The second-order invariants of a solid, whose three directions share one computation
    /// (their mass blocks are equal), against the straightforward sums over the whole mass
    /// matrix, direction by direction: $\bar{\mathbf S}_{kl} = \frac13\sum_c
    /// \mathbf P_c(\mathbf S_k)^T\mathbf M\mathbf P_c(\mathbf S_l)$ and $S_{x,kl} =
    /// \frac13\sum_c\mathbf P_c(x_k - c_k)^T\mathbf M\mathbf P_c(\mathbf S_l)$, with
    /// $\mathbf P_c(f)$ the field $f$ in translation slot $c$ of every node.
    #[test]
    fn solid_second_order_invariants_equal_the_sums_over_each_direction() {
        let steel = IsotropicMaterial::new("steel", 210e9, 0.3, 7850.0).unwrap();
        let mesh = box_mesh(CellKind::Hex8, [0.8, 0.3, 0.2], [5, 3, 2]).unwrap();
        let model = solid_model(mesh, steel, MassKind::Consistent).unwrap();
        let n = 4;
        let mut state = 11u64;
        let S_full = Mat::from_fn(6 * model.node_count(), n, |_, _| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        });
        let (data, _) = inertia_data(&model, &S_full).unwrap();
        let dofs = DofMap::new(&model).unwrap();
        let M = assemble_mass(&model, &SystemPattern::new(&model, &dofs)).unwrap();
        let M = M.to_dense();
        let n_f = dofs.n_free();
        let c = data.center_of_mass;
        // P_c(f): the nodal field f placed in translation slot `comp` of every free dof.
        let place = |comp: usize, f: &dyn Fn(usize) -> f64| {
            Mat::from_fn(n_f, 1, |d, _| {
                let slot = dofs.full_slot(fe_model::Dof(d as u32));
                if slot % 6 == comp {
                    f(slot / 6)
                } else {
                    0.0
                }
            })
        };
        let nodes = &model.mesh.nodes;
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for k in 0..3 {
            for l in 0..3 {
                for j in 0..n {
                    let mut x = 0.0;
                    for comp in 0..3 {
                        let g = place(comp, &|node| S_full[(6 * node + l, j)]);
                        let f = place(comp, &|node| nodes[node][k] - c[k]);
                        x += (f.transpose() * &M * &g)[(0, 0)] / 3.0;
                    }
                    let got = data.S_x.data[(3 * k + l) + 9 * j];
                    worst = worst.max((got - x).abs());
                    scale = scale.max(x.abs());
                    for i in 0..n {
                        let mut s = 0.0;
                        for comp in 0..3 {
                            let f = place(comp, &|node| S_full[(6 * node + k, i)]);
                            let g = place(comp, &|node| S_full[(6 * node + l, j)]);
                            s += (f.transpose() * &M * &g)[(0, 0)] / 3.0;
                        }
                        let got = data.S_bar[3 * k + l].data[i + n * j];
                        worst = worst.max((got - s).abs());
                        scale = scale.max(s.abs());
                    }
                }
            }
        }
        // Sums of a few hundred products of order one, in another order: round-off.
        assert!(worst <= 1e-13 * scale, "worst difference {worst:.3e} of {scale:.3e}");
    }
}
