//! A sparse Cholesky factor $\mathbf P\mathbf A\mathbf P^T = \mathbf L\mathbf L^T$ (faer,
//! supernodal or simplicial as faer's symbolic analysis chooses) with the fill-reducing
//! ordering of [`crate::ordering`], and the separate triangular solves with $\mathbf L$ and
//! $\mathbf L^T$ that `reduction`'s shift-invert operator needs. Shared by the statics of this
//! crate and by `reduction::ShiftInvert`.

use crate::ordering::{factor_flops, symbolic_cholesky, FillOrdering};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::sparse::linalg::cholesky::simplicial::SimplicialLltRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::linalg::triangular_solve;
use faer::sparse::SparseColMatRef;
use faer::{Conj, MatMut, Par};

/// Why [`SparseCholesky::new`] failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CholeskyError {
    /// The matrix is not positive definite: the pivot of `dof` (index of the matrix as given,
    /// not of the permuted factor) was not positive.
    #[error("the matrix is not positive definite: non-positive pivot at dof {dof}")]
    NonPositivePivot { dof: usize },
    /// faer ran out of memory or index range, or the ordering's input was wrong.
    #[error("sparse Cholesky: {0}")]
    Failed(String),
}

/// $\mathbf P\mathbf A\mathbf P^T = \mathbf L\mathbf L^T$ for a symmetric positive definite
/// $\mathbf A$ (lower triangle read).
#[derive(Debug)]
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    L_values: Vec<f64>,
    /// `perm_fwd[k]` is the row of $\mathbf A$ at row `k` of the factor.
    perm_fwd: Vec<usize>,
    /// Inverse of `perm_fwd`.
    perm_inv: Vec<usize>,
    ordering: FillOrdering,
}

impl SparseCholesky {
    /// Orders (see [`symbolic_cholesky`]: `points[d]` the position of dof `d`, used by nested
    /// dissection) and factors `A` (its lower triangle), with faer's global parallelism.
    ///
    /// # Errors
    /// [`CholeskyError::NonPositivePivot`] with the dof in `A`'s numbering;
    /// [`CholeskyError::Failed`] for memory, index overflow, or `points` of the wrong length.
    pub fn new(
        A: SparseColMatRef<'_, usize, f64>,
        points: Option<&[[f64; 3]]>,
        ordering: FillOrdering,
    ) -> Result<Self, CholeskyError> {
        let n = A.nrows();
        let (symbolic, ordering) =
            symbolic_cholesky(A.symbolic(), points, ordering).map_err(|e| CholeskyError::Failed(e.to_string()))?;
        let (perm_fwd, perm_inv) = match symbolic.perm() {
            Some(p) => {
                let (fwd, inv) = p.arrays();
                (fwd.to_vec(), inv.to_vec())
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let par = faer::get_global_parallelism();
        let mut L_values = Vec::new();
        L_values.try_reserve_exact(symbolic.len_val()).map_err(|_| {
            CholeskyError::Failed(format!("out of memory for the factor ({} values)", symbolic.len_val()))
        })?;
        L_values.resize(symbolic.len_val(), 0.0);
        let mut mem = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
            .map_err(|_| CholeskyError::Failed("out of memory for the factorisation workspace".into()))?;
        let result = symbolic.factorize_numeric_llt::<f64>(
            &mut L_values,
            A,
            faer::Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        );
        match result {
            Ok(_) => {}
            Err(LltError::NonPositivePivot { index }) => {
                return Err(CholeskyError::NonPositivePivot {
                    dof: perm_fwd[index.min(n.saturating_sub(1))],
                })
            }
        }
        Ok(Self {
            symbolic,
            L_values,
            perm_fwd,
            perm_inv,
            ordering,
        })
    }

    /// Dimension $n$.
    pub fn nrows(&self) -> usize {
        self.perm_fwd.len()
    }

    /// Number of stored values of $\mathbf L$ (supernodal storage includes explicit zeros).
    pub fn factor_len(&self) -> usize {
        self.L_values.len()
    }

    /// Floating-point operations of the factorisation ([`factor_flops`]).
    pub fn flops(&self) -> f64 {
        factor_flops(&self.symbolic)
    }

    /// The ordering used ([`FillOrdering::Amd`] or [`FillOrdering::NestedDissection`]).
    pub fn ordering(&self) -> FillOrdering {
        self.ordering
    }

    /// $\mathbf P$: `perm_fwd()[k]` is the row of $\mathbf A$ at row `k` of the factor.
    pub fn perm_fwd(&self) -> &[usize] {
        &self.perm_fwd
    }

    /// $\mathbf P^{-1}$.
    pub fn perm_inv(&self) -> &[usize] {
        &self.perm_inv
    }

    /// Solves $\mathbf A\mathbf X = \mathbf B$ in place (`rhs`: $\mathbf B$ in, $\mathbf X$
    /// out, original order).
    ///
    /// # Panics
    /// If `rhs.nrows()` differs from [`Self::nrows`].
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.solve_scratch(rhs.ncols(), par));
        LltRef::new(&self.symbolic, &self.L_values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            par,
            MemStack::new(&mut mem),
        );
    }

    /// Workspace of [`Self::l_solve`] and [`Self::l_transpose_solve`] for `k` columns.
    pub fn solve_scratch(&self, k: usize, par: Par) -> StackReq {
        self.symbolic.solve_in_place_scratch::<f64>(k, par)
    }

    /// The diagonal of $\mathbf L$, in the permuted order.
    pub fn pivots(&self) -> Vec<f64> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                // The diagonal is the first stored entry of each column of L.
                let col_ptr = s.col_ptr();
                (0..s.nrows()).map(|j| self.L_values[col_ptr[j]]).collect()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let L = SupernodalLltRef::<'_, usize, f64>::new(s, &self.L_values);
                let mut d = vec![0.0; s.nrows()];
                for sn in 0..s.n_supernodes() {
                    let node = L.supernode(sn);
                    let start = node.start();
                    let val = node.val();
                    for k in 0..val.ncols() {
                        d[start + k] = val[(k, k)];
                    }
                }
                d
            }
        }
    }

    /// Forward solve $\mathbf L\mathbf x = \mathbf b$ in place (permuted order).
    pub fn l_solve(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let L = SimplicialLltRef::<'_, usize, f64>::new(s, &self.L_values);
                let L = SparseColMatRef::new(s.factor(), L.values());
                triangular_solve::solve_lower_triangular_in_place(L, Conj::No, rhs, par);
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                SupernodalLltRef::<'_, usize, f64>::new(s, &self.L_values).l_solve_with_conj(Conj::No, rhs, par, stack);
            }
        }
    }

    /// Backward solve $\mathbf L^T\mathbf x = \mathbf b$ in place (permuted order).
    pub fn l_transpose_solve(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let L = SimplicialLltRef::<'_, usize, f64>::new(s, &self.L_values);
                let L = SparseColMatRef::new(s.factor(), L.values());
                triangular_solve::solve_lower_triangular_transpose_in_place(L, Conj::No, rhs, par);
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                SupernodalLltRef::<'_, usize, f64>::new(s, &self.L_values).l_transpose_solve_with_conj(
                    Conj::No,
                    rhs,
                    par,
                    stack,
                );
            }
        }
    }
}
