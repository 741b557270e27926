//! A sparse Cholesky factor $\mathbf P\mathbf A\mathbf P^T = \mathbf L\mathbf L^T$ (faer,
//! supernodal or simplicial as faer's symbolic analysis chooses) with the fill-reducing
//! ordering of [`crate::ordering`], and the separate triangular solves with $\mathbf L$ and
//! $\mathbf L^T$ that `reduction`'s shift-invert operator needs. Shared by the statics of this
//! crate and by `reduction::ShiftInvert`.
//!
//! The numeric factorisation of a supernodal factor with faer's global parallelism of several
//! threads is ours (`parallel_llt`): left-looking on faer's symbolic structure, the disjoint
//! subtrees of the elimination tree in parallel with sequential dense kernels, then the top
//! separators in order, each with its columns gathered and its rows below the diagonal block
//! solved by ranges in parallel. faer's supernodal loop (one supernode after another, parallel
//! only inside the dense kernels, which on two cores spent about a quarter of the CPU time in
//! thread barriers) factors a simplicial factor, on one thread, and below $10^9$ flops
//! (about 10 000 dofs of a 3D solid), where both take a few hundredths of a second and the
//! same CPU time; ours then needs no schedule. Both give the same values to round-off
//! (faer's dense kernels on the same blocks; at 26 000 dofs of the benchmark blocks they
//! differ by 1.6e-16 relative to a supernode's norm).

use crate::ordering::{factor_flops, symbolic_cholesky, FillOrdering};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltError;
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{solve_lower_triangular_in_place, solve_upper_triangular_in_place};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::simplicial::SimplicialLltRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::linalg::triangular_solve;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Accum, Conj, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

mod parallel_llt;
use parallel_llt::{FactorPlan, Real};

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

/// Precision of the stored values of $\mathbf L$.
///
/// A single-precision factor holds half the bytes; its solves are accurate to about
/// $\kappa(\mathbf A)\,\varepsilon_{32}$ ($\varepsilon_{32} = 1.2\cdot 10^{-7}$) and need
/// iterative refinement in double precision to reach a double-precision solve's accuracy
/// (`reduction::ShiftInvert::solve_refined`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precision {
    /// f64 values.
    Double,
    /// f32 values.
    Single,
}

impl Precision {
    /// Bytes per stored value.
    pub fn bytes(self) -> usize {
        match self {
            Precision::Double => 8,
            Precision::Single => 4,
        }
    }

    /// "double" or "single", for messages.
    pub fn name(self) -> &'static str {
        match self {
            Precision::Double => "double",
            Precision::Single => "single",
        }
    }
}

/// The values of $\mathbf L$ in their precision.
#[derive(Debug)]
enum Values {
    Double(Vec<f64>),
    Single(Vec<f32>),
}

/// The symbolic analysis of [`SparseCholesky`]: the fill-reducing ordering and the pattern of
/// $\mathbf L$, no values. It tells the size of the factor before any value is computed, so
/// that the caller can choose the precision ([`SymbolicFactor::numeric_bytes`]) and refuse a
/// factor that does not fit in memory.
#[derive(Debug)]
pub struct SymbolicFactor {
    symbolic: SymbolicCholesky<usize>,
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
    ordering: FillOrdering,
    /// The schedule of our subtree-parallel numeric factorisation (`None`: faer's).
    plan: Option<FactorPlan>,
}

/// Floating-point operations ([`factor_flops`]) below which the numeric factorisation is
/// faer's supernodal loop rather than the subtree-parallel one of `parallel_llt`.
const PARALLEL_FACTOR_MIN_FLOPS: f64 = 1e9;

impl SymbolicFactor {
    /// Orders `A` (its lower triangle; see [`symbolic_cholesky`]: `points[d]` the position of
    /// dof `d`, used by nested dissection) and computes the pattern of $\mathbf L$.
    ///
    /// # Errors
    /// [`CholeskyError::Failed`] for index overflow or `points` of the wrong length.
    pub fn analyse(
        A: SymbolicSparseColMatRef<'_, usize>,
        points: Option<&[[f64; 3]]>,
        ordering: FillOrdering,
    ) -> Result<Self, CholeskyError> {
        let n = A.nrows();
        let (symbolic, ordering) =
            symbolic_cholesky(A, points, ordering).map_err(|e| CholeskyError::Failed(e.to_string()))?;
        let (perm_fwd, perm_inv) = match symbolic.perm() {
            Some(p) => {
                let (fwd, inv) = p.arrays();
                (fwd.to_vec(), inv.to_vec())
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let plan = match (symbolic.raw(), faer::get_global_parallelism()) {
            (SymbolicCholeskyRaw::Supernodal(s), Par::Rayon(threads))
                if factor_flops(&symbolic) >= PARALLEL_FACTOR_MIN_FLOPS =>
            {
                FactorPlan::new(s, threads.get())
            }
            _ => None,
        };
        Ok(Self {
            symbolic,
            perm_fwd,
            perm_inv,
            ordering,
            plan,
        })
    }

    /// Chooses the numeric factorisation against the default (ours, parallel over subtrees,
    /// for a supernodal factor of at least 10^9 flops with several threads; else faer's
    /// supernodal loop): `Some(threads)` plans ours for `threads` threads whatever the size,
    /// `None` chooses faer's. Returns whether ours will be used: it needs a supernodal factor
    /// whose tree splits into at least two subtrees, and the global parallelism of several
    /// threads when [`SymbolicFactor::factor`] runs. For benchmarks and tests.
    pub fn set_parallel_subtrees(&mut self, threads: Option<usize>) -> bool {
        self.plan = match (self.symbolic.raw(), threads) {
            (SymbolicCholeskyRaw::Supernodal(s), Some(threads)) => FactorPlan::new(s, threads),
            _ => None,
        };
        self.plan.is_some()
    }

    /// Number of subtrees that the numeric factorisation runs in parallel (0: faer's
    /// supernodal loop, for a simplicial factor, one thread or a small matrix) and the
    /// fraction of its floating-point operations in the supernodes above them, factored in
    /// order with all threads in each dense kernel (their own columns' operations, as
    /// [`factor_flops`] counts them).
    pub fn parallel_subtrees(&self) -> (usize, f64) {
        match (&self.plan, self.symbolic.raw()) {
            (Some(plan), SymbolicCholeskyRaw::Supernodal(s)) => {
                let top: f64 = plan
                    .top
                    .iter()
                    .map(|&sn| parallel_llt::supernode_flops(s, sn) as f64)
                    .sum();
                (plan.tasks.len(), top / self.flops().max(1.0))
            }
            _ => (0, 0.0),
        }
    }

    /// Number of values of $\mathbf L$ (supernodal storage includes explicit zeros).
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Floating-point operations of the numeric factorisation ([`factor_flops`]).
    pub fn flops(&self) -> f64 {
        factor_flops(&self.symbolic)
    }

    /// The ordering used ([`FillOrdering::Amd`] or [`FillOrdering::NestedDissection`]).
    pub fn ordering(&self) -> FillOrdering {
        self.ordering
    }

    /// Bytes that [`SymbolicFactor::factor`] allocates in `precision` for a matrix with
    /// `stored` stored entries: the values of $\mathbf L$ and the workspace
    /// ([`SymbolicFactor::workspace_bytes`]).
    pub fn numeric_bytes(&self, precision: Precision, stored: usize) -> usize {
        self.factor_len() * precision.bytes() + self.workspace_bytes(precision, stored)
    }

    /// Bytes that [`SymbolicFactor::factor`] allocates in `precision` beside the values of
    /// $\mathbf L$ and frees before it returns: the workspace of the numeric factorisation
    /// (faer's with the global parallelism, or the permuted matrix and one workspace per
    /// thread of the subtree-parallel one, and its schedule) and, in single precision, the
    /// f32 copy of the matrix's `stored` values.
    pub fn workspace_bytes(&self, precision: Precision, stored: usize) -> usize {
        let par = faer::get_global_parallelism();
        if let Some(plan) = &self.plan {
            let (n, threads) = (self.perm_fwd.len(), par.degree());
            return plan.bytes()
                + match precision {
                    Precision::Double => plan.workspace_bytes::<f64>(n, stored, threads),
                    Precision::Single => plan.workspace_bytes::<f32>(n, stored, threads) + 4 * stored,
                };
        }
        let (scratch, copy) = match precision {
            Precision::Double => (
                self.symbolic
                    .factorize_numeric_llt_scratch::<f64>(par, Default::default()),
                0,
            ),
            Precision::Single => (
                self.symbolic
                    .factorize_numeric_llt_scratch::<f32>(par, Default::default()),
                4 * stored,
            ),
        };
        scratch.size_bytes() + copy
    }

    /// The numeric factorisation of `A` (the matrix analysed, lower triangle read) with values
    /// in `precision`, with faer's global parallelism (parallel over subtrees of the
    /// elimination tree, see the module docs). In single precision the values of `A`
    /// are rounded to f32 first.
    ///
    /// # Errors
    /// [`CholeskyError::NonPositivePivot`] with the dof in `A`'s numbering;
    /// [`CholeskyError::Failed`] for memory.
    pub fn factor(
        self,
        A: SparseColMatRef<'_, usize, f64>,
        precision: Precision,
    ) -> Result<SparseCholesky, CholeskyError> {
        let n = A.nrows();
        let Self {
            symbolic,
            perm_fwd,
            perm_inv,
            ordering,
            plan,
        } = self;
        let pivot_error = |index: usize| CholeskyError::NonPositivePivot {
            dof: perm_fwd[index.min(n.saturating_sub(1))],
        };
        let L_values = match precision {
            Precision::Double => {
                Values::Double(numeric::<f64>(&symbolic, plan.as_ref(), A).map_err(|e| e.map(pivot_error))?)
            }
            Precision::Single => {
                let mut values = Vec::new();
                values.try_reserve_exact(A.val().len()).map_err(|_| {
                    CholeskyError::Failed(format!(
                        "out of memory for the single-precision copy of the matrix ({} values)",
                        A.val().len()
                    ))
                })?;
                values.extend(A.val().iter().map(|&v| v as f32));
                let A32 = SparseColMatRef::new(A.symbolic(), &values);
                let L = numeric::<f32>(&symbolic, plan.as_ref(), A32).map_err(|e| e.map(pivot_error))?;
                Values::Single(L)
            }
        };
        let tree = match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => SolveTree::new(s, rayon::current_num_threads()),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        };
        Ok(SparseCholesky {
            symbolic,
            L_values,
            perm_fwd,
            perm_inv,
            ordering,
            tree,
        })
    }
}

/// A failed [`numeric`] factorisation: out of memory, or the index of a non-positive pivot
/// (in the order of the factor).
enum NumericError {
    Memory(CholeskyError),
    Pivot(usize),
}

impl NumericError {
    fn map(self, pivot: impl FnOnce(usize) -> CholeskyError) -> CholeskyError {
        match self {
            NumericError::Memory(e) => e,
            NumericError::Pivot(index) => pivot(index),
        }
    }
}

/// The numeric LL^T factorisation of `A` on `symbolic`, values of type `T`: with the global
/// parallelism of several threads and a `plan`, ours, parallel over subtrees
/// ([`parallel_llt`]); else faer's.
fn numeric<T: Real>(
    symbolic: &SymbolicCholesky<usize>,
    plan: Option<&FactorPlan>,
    A: SparseColMatRef<'_, usize, T>,
) -> Result<Vec<T>, NumericError> {
    let par = faer::get_global_parallelism();
    let mut L_values = Vec::new();
    L_values.try_reserve_exact(symbolic.len_val()).map_err(|_| {
        NumericError::Memory(CholeskyError::Failed(format!(
            "out of memory for the factor ({} values)",
            symbolic.len_val()
        )))
    })?;
    // Zeroed by all threads: the kernel maps and clears each new page at its first write
    // (half a million 4 kB pages at 200k dofs), which on one thread took a noticeable part of
    // the stage (BENCHMARKS, fresh pages).
    L_values.par_extend(rayon::iter::repeat_n(T::zero_impl(), symbolic.len_val()));
    if let (Some(plan), SymbolicCholeskyRaw::Supernodal(s), Par::Rayon(_)) = (plan, symbolic.raw(), par) {
        let A = permuted_lower(symbolic, A)?;
        return match parallel_llt::factor(s, plan, A.as_ref(), &mut L_values, par) {
            Ok(()) => Ok(L_values),
            Err(index) => Err(NumericError::Pivot(index)),
        };
    }
    let mut mem =
        MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<T>(par, Default::default())).map_err(|_| {
            NumericError::Memory(CholeskyError::Failed(
                "out of memory for the factorisation workspace".into(),
            ))
        })?;
    match symbolic.factorize_numeric_llt::<T>(
        &mut L_values,
        A,
        faer::Side::Lower,
        Default::default(),
        par,
        MemStack::new(&mut mem),
        Default::default(),
    ) {
        Ok(_) => Ok(L_values),
        Err(LltError::NonPositivePivot { index }) => Err(NumericError::Pivot(index)),
    }
}

/// The lower triangle of $\mathbf P\mathbf A\mathbf P^T$ (row indices unsorted) from the lower
/// triangle of `A`, with the ordering of `symbolic`.
fn permuted_lower<T: Real>(
    symbolic: &SymbolicCholesky<usize>,
    A: SparseColMatRef<'_, usize, T>,
) -> Result<faer::sparse::SparseColMat<usize, T>, NumericError> {
    let n = A.nrows();
    let lower: usize = (0..n)
        .map(|j| A.row_idx_of_col_raw(j).iter().filter(|&&i| i >= j).count())
        .sum();
    let memory = || {
        NumericError::Memory(CholeskyError::Failed(format!(
            "out of memory for the permuted matrix ({lower} values)"
        )))
    };
    let (mut values, mut row_idx) = (Vec::new(), Vec::new());
    values.try_reserve_exact(lower).map_err(|_| memory())?;
    row_idx.try_reserve_exact(lower).map_err(|_| memory())?;
    // Zeroed by all threads, as the factor's values (fresh pages).
    values.par_extend(rayon::iter::repeat_n(T::zero_impl(), lower));
    row_idx.par_extend(rayon::iter::repeat_n(0usize, lower));
    let mut col_ptr = vec![0usize; n + 1];
    let identity: Vec<usize>;
    let perm = match symbolic.perm() {
        Some(p) => p,
        None => {
            identity = (0..n).collect();
            faer::perm::PermRef::new_checked(&identity, &identity, n)
        }
    };
    let mut mem = MemBuffer::new(faer::sparse::utils::permute_self_adjoint_scratch::<usize>(n));
    faer::sparse::utils::permute_self_adjoint_to_unsorted(
        &mut values,
        &mut col_ptr,
        &mut row_idx,
        A,
        perm,
        faer::Side::Lower,
        faer::Side::Lower,
        MemStack::new(&mut mem),
    );
    let symbolic = faer::sparse::SymbolicSparseColMat::new_unsorted_checked(n, n, col_ptr, None, row_idx);
    Ok(faer::sparse::SparseColMat::new(symbolic, values))
}

/// $\mathbf P\mathbf A\mathbf P^T = \mathbf L\mathbf L^T$ for a symmetric positive definite
/// $\mathbf A$ (lower triangle read), with the values of $\mathbf L$ in double or single
/// precision ([`Precision`]).
#[derive(Debug)]
pub struct SparseCholesky {
    symbolic: SymbolicCholesky<usize>,
    L_values: Values,
    /// `perm_fwd[k]` is the row of $\mathbf A$ at row `k` of the factor.
    perm_fwd: Vec<usize>,
    /// Inverse of `perm_fwd`.
    perm_inv: Vec<usize>,
    ordering: FillOrdering,
    /// The split of the supernodal tree for the parallel triangular solves (`None`: simplicial
    /// factor, or supernodes not in postorder; then faer's sequential solves are used).
    tree: Option<SolveTree>,
}

impl SparseCholesky {
    /// Orders (see [`symbolic_cholesky`]: `points[d]` the position of dof `d`, used by nested
    /// dissection) and factors `A` (its lower triangle) in double precision, with faer's
    /// global parallelism: [`SymbolicFactor::analyse`], then [`SymbolicFactor::factor`].
    ///
    /// # Errors
    /// [`CholeskyError::NonPositivePivot`] with the dof in `A`'s numbering;
    /// [`CholeskyError::Failed`] for memory, index overflow, or `points` of the wrong length.
    pub fn new(
        A: SparseColMatRef<'_, usize, f64>,
        points: Option<&[[f64; 3]]>,
        ordering: FillOrdering,
    ) -> Result<Self, CholeskyError> {
        SymbolicFactor::analyse(A.symbolic(), points, ordering)?.factor(A, Precision::Double)
    }

    /// The precision of the stored values.
    pub fn precision(&self) -> Precision {
        match self.L_values {
            Values::Double(_) => Precision::Double,
            Values::Single(_) => Precision::Single,
        }
    }

    /// The f64 values; the separate triangular solves exist for a double-precision factor
    /// only.
    fn double(&self) -> &[f64] {
        match &self.L_values {
            Values::Double(v) => v,
            Values::Single(_) => panic!("the separate triangular solves need a double-precision factor"),
        }
    }

    /// Dimension $n$.
    pub fn nrows(&self) -> usize {
        self.perm_fwd.len()
    }

    /// Number of stored values of $\mathbf L$ (supernodal storage includes explicit zeros).
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Floating-point operations of the factorisation ([`factor_flops`]).
    pub fn flops(&self) -> f64 {
        factor_flops(&self.symbolic)
    }

    /// Number of subtrees of the elimination tree that the triangular solves run in parallel
    /// (0: sequential solves, for a simplicial factor or a single thread), and the fraction of
    /// the factor's values above them (solved in order, all threads on each dense product).
    pub fn parallel_subtrees(&self) -> (usize, f64) {
        match (&self.tree, self.symbolic.raw()) {
            (Some(tree), SymbolicCholeskyRaw::Supernodal(s)) => {
                let ptr = s.col_ptr_for_val();
                let top: usize = tree.top.iter().map(|&sn| ptr[sn + 1] - ptr[sn]).sum();
                (tree.tasks.len(), top as f64 / self.factor_len().max(1) as f64)
            }
            _ => (0, 0.0),
        }
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
    /// out, original order). With a single-precision factor the right-hand sides are rounded
    /// to f32 and solved in f32 (faer's sequential supernodal or simplicial solves): accurate
    /// to about $\kappa(\mathbf A)\,\varepsilon_{32}$ only.
    ///
    /// # Panics
    /// If `rhs.nrows()` differs from [`Self::nrows`].
    pub fn solve_in_place(&self, mut rhs: MatMut<'_, f64>) {
        let par = faer::get_global_parallelism();
        let (n, k) = rhs.shape();
        assert_eq!(
            n,
            self.nrows(),
            "right-hand side with {n} rows for a factor of {}",
            self.nrows()
        );
        match &self.L_values {
            Values::Double(_) => {
                let mut mem = MemBuffer::new(self.solve_scratch(k, par));
                let stack = MemStack::new(&mut mem);
                // P^T L^{-T} L^{-1} P b, through the (parallel) triangular solves.
                let mut y = faer::Mat::<f64>::from_fn(n, k, |i, j| rhs[(self.perm_fwd[i], j)]);
                self.l_solve(y.as_mut(), par, stack);
                self.l_transpose_solve(y.as_mut(), par, stack);
                for j in 0..k {
                    for i in 0..n {
                        rhs[(self.perm_fwd[i], j)] = y[(i, j)];
                    }
                }
            }
            Values::Single(values) => {
                let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f32>(k, par));
                let stack = MemStack::new(&mut mem);
                let mut y = faer::Mat::<f32>::from_fn(n, k, |i, j| rhs[(self.perm_fwd[i], j)] as f32);
                match self.symbolic.raw() {
                    SymbolicCholeskyRaw::Simplicial(s) => {
                        let L = SimplicialLltRef::<'_, usize, f32>::new(s, values);
                        let L = SparseColMatRef::new(s.factor(), L.values());
                        triangular_solve::solve_lower_triangular_in_place(L, Conj::No, y.as_mut(), par);
                        triangular_solve::solve_lower_triangular_transpose_in_place(L, Conj::No, y.as_mut(), par);
                    }
                    SymbolicCholeskyRaw::Supernodal(s) => {
                        let L = SupernodalLltRef::<'_, usize, f32>::new(s, values);
                        L.l_solve_with_conj(Conj::No, y.as_mut(), par, stack);
                        L.l_transpose_solve_with_conj(Conj::No, y.as_mut(), par, stack);
                    }
                }
                for j in 0..k {
                    for i in 0..n {
                        rhs[(self.perm_fwd[i], j)] = y[(i, j)] as f64;
                    }
                }
            }
        }
    }

    /// Workspace of [`Self::l_solve`] and [`Self::l_transpose_solve`] for `k` columns.
    pub fn solve_scratch(&self, k: usize, par: Par) -> StackReq {
        self.symbolic.solve_in_place_scratch::<f64>(k, par)
    }

    /// The largest difference between the values of this factor and `other`'s (the same
    /// matrix and analysis, e.g. factored by another method) relative to the Frobenius norm
    /// of the supernode (column, for a simplicial factor) they belong to:
    /// $\max_s \lVert\mathbf L_s - \mathbf L'_s\rVert_F / \lVert\mathbf L_s\rVert_F$.
    /// Infinite for factors of different size, pattern or precision.
    pub fn relative_difference(&self, other: &SparseCholesky) -> f64 {
        let blocks: Vec<usize> = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s.col_ptr_for_val().to_vec(),
            SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().to_vec(),
        };
        if self.factor_len() != other.factor_len() || self.perm_fwd != other.perm_fwd {
            return f64::INFINITY;
        }
        fn largest<T: Copy + Into<f64>>(blocks: &[usize], a: &[T], b: &[T]) -> f64 {
            blocks
                .windows(2)
                .map(|w| {
                    let (mut diff, mut norm) = (0.0f64, 0.0f64);
                    for (&x, &y) in a[w[0]..w[1]].iter().zip(&b[w[0]..w[1]]) {
                        let (x, y): (f64, f64) = (x.into(), y.into());
                        diff += (x - y) * (x - y);
                        norm += x * x;
                    }
                    if diff == 0.0 {
                        0.0
                    } else {
                        (diff / norm).sqrt()
                    }
                })
                .fold(0.0, f64::max)
        }
        match (&self.L_values, &other.L_values) {
            (Values::Double(a), Values::Double(b)) => largest(&blocks, a, b),
            (Values::Single(a), Values::Single(b)) => largest(&blocks, a, b),
            _ => f64::INFINITY,
        }
    }

    /// The diagonal of $\mathbf L$, in the permuted order.
    pub fn pivots(&self) -> Vec<f64> {
        match &self.L_values {
            Values::Double(values) => pivots(&self.symbolic, values),
            Values::Single(values) => pivots(&self.symbolic, values),
        }
    }

    /// Forward solve $\mathbf L\mathbf x = \mathbf b$ in place (permuted order).
    pub fn l_solve(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        self.triangular_solve(false, rhs, par, stack);
    }

    /// Backward solve $\mathbf L^T\mathbf x = \mathbf b$ in place (permuted order).
    pub fn l_transpose_solve(&self, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        self.triangular_solve(true, rhs, par, stack);
    }

    /// [`Self::l_solve`], or [`Self::l_transpose_solve`] with `transpose`: in the factor's own
    /// storage, by the subtree-parallel solves of the tree where there is one and threads.
    fn triangular_solve(&self, transpose: bool, rhs: MatMut<'_, f64>, par: Par, stack: &mut MemStack) {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let L = SimplicialLltRef::<'_, usize, f64>::new(s, self.double());
                let L = SparseColMatRef::new(s.factor(), L.values());
                if transpose {
                    triangular_solve::solve_lower_triangular_transpose_in_place(L, Conj::No, rhs, par);
                } else {
                    triangular_solve::solve_lower_triangular_in_place(L, Conj::No, rhs, par);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let L = SupernodalLltRef::<'_, usize, f64>::new(s, self.double());
                match (&self.tree, par, transpose) {
                    (Some(tree), Par::Rayon(_), false) => tree.l_solve(L, rhs, par),
                    (Some(tree), Par::Rayon(_), true) => tree.l_transpose_solve(L, rhs, par),
                    (_, _, false) => L.l_solve_with_conj(Conj::No, rhs, par, stack),
                    (_, _, true) => L.l_transpose_solve_with_conj(Conj::No, rhs, par, stack),
                }
            }
        }
    }
}

/// The diagonal of $\mathbf L$ with values `values` on `symbolic`, in the permuted order, in f64.
fn pivots<T: faer::traits::RealField + Copy + Into<f64>>(symbolic: &SymbolicCholesky<usize>, values: &[T]) -> Vec<f64> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            // The diagonal is the first stored entry of each column of L.
            let col_ptr = s.col_ptr();
            (0..s.nrows()).map(|j| values[col_ptr[j]].into()).collect()
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let L = SupernodalLltRef::<'_, usize, T>::new(s, values);
            let mut d = vec![0.0; s.nrows()];
            for sn in 0..s.n_supernodes() {
                let node = L.supernode(sn);
                let start = node.start();
                let val = node.val();
                for k in 0..val.ncols() {
                    d[start + k] = val[(k, k)].into();
                }
            }
            d
        }
    }
}

/// Memory available to this process \[bytes\]: `MemAvailable` of `/proc/meminfo` (free memory
/// plus the page cache and reclaimable buffers the kernel can give back without swapping), and
/// within a control group with a memory limit (`/sys/fs/cgroup/memory.max`, cgroup v2) at most
/// the limit less the group's current use. `None` where neither can be read (not Linux).
pub fn available_memory() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
        text.lines().find_map(|line| {
            let rest = line.strip_prefix("MemAvailable:")?;
            let kb: u64 = rest.trim().trim_end_matches("kB").trim().parse().ok()?;
            Some(kb * 1024)
        })
    });
    let read = |path: &str| std::fs::read_to_string(path).ok()?.trim().parse::<u64>().ok();
    let cgroup = match (read("/sys/fs/cgroup/memory.max"), read("/sys/fs/cgroup/memory.current")) {
        (Some(max), Some(current)) => Some(max.saturating_sub(current)),
        _ => None,
    };
    match (meminfo, cgroup) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// Splits the supernodal elimination tree of `s` for `threads` threads into disjoint subtrees
/// (each its supernodes, ascending) and the supernodes above them (ascending), by `weight`
/// per supernode: starting from the roots, the subtree of largest weight is replaced by its
/// children until there are at least 4 subtrees per thread or the largest weighs at most 1/8
/// per thread of the total, as long as the supernodes moved to the top weigh at most half of
/// it (a few per cent on large 3D meshes, whose top separators are small next to the rest of
/// the factor). `None` for one thread, if there is nothing to split, or if a supernode's
/// parent (the supernode of the first row below its diagonal block) does not come after it.
fn split_tree(
    s: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
    threads: usize,
    weight: &[usize],
) -> Option<(Vec<Vec<usize>>, Vec<usize>)> {
    let ns = s.n_supernodes();
    if threads < 2 || ns < 2 {
        return None;
    }
    let (begin, end) = (s.supernode_begin(), s.supernode_end());
    let mut supernode_of_row = vec![0usize; s.nrows()];
    for sn in 0..ns {
        supernode_of_row[begin[sn]..end[sn]].fill(sn);
    }
    let mut parent = vec![usize::MAX; ns];
    for (sn, p) in parent.iter_mut().enumerate() {
        if let Some(&first_row) = s.supernode(sn).pattern().iter().min() {
            *p = supernode_of_row[first_row];
            if *p <= sn {
                return None;
            }
        }
    }
    let mut work = weight.to_vec();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); ns];
    for sn in 0..ns {
        if parent[sn] != usize::MAX {
            work[parent[sn]] += work[sn];
            children[parent[sn]].push(sn);
        }
    }
    let mut roots: Vec<usize> = (0..ns).filter(|&sn| parent[sn] == usize::MAX).collect();
    let total: usize = roots.iter().map(|&sn| work[sn]).sum();
    let mut top = Vec::new();
    let mut top_work = 0usize;
    loop {
        let (k, &largest) = roots.iter().enumerate().max_by_key(|&(_, &r)| work[r])?;
        let enough = roots.len() >= 4 * threads || work[largest] * 8 * threads <= total;
        if enough || children[largest].is_empty() || 2 * (top_work + weight[largest]) > total {
            break;
        }
        roots.swap_remove(k);
        top.push(largest);
        top_work += weight[largest];
        roots.extend(&children[largest]);
    }
    if roots.len() < 2 {
        return None;
    }
    roots.sort_unstable();
    top.sort_unstable();
    let tasks = roots
        .iter()
        .map(|&root| {
            let mut members = vec![root];
            let mut next = 0;
            while next < members.len() {
                members.extend(&children[members[next]]);
                next += 1;
            }
            members.sort_unstable();
            members
        })
        .collect();
    Some((tasks, top))
}

/// The supernodal elimination tree split for parallel triangular solves: disjoint subtrees
/// (`tasks`), each solved by one thread, and the supernodes above them (`top`), solved in
/// order by all threads together.
///
/// The pattern of a column of $\mathbf L$ holds rows of its ancestors in the elimination tree
/// only (Liu, "The role of elimination trees in sparse factorization", SIAM J. Matrix Anal.
/// Appl. 11, 1990, §3), so in $\mathbf L\mathbf x = \mathbf b$ disjoint subtrees are
/// independent: each updates its own rows, gathered into a buffer of its own, and the rows
/// of the top, collected in a second buffer added to $\mathbf x$ before the top is solved.
/// $\mathbf L^T\mathbf x = \mathbf b$ runs the other way: the top first, then the subtrees,
/// which read the rows of the top. A solve with a factor larger than the caches is
/// memory-bound and gains what the memory bus gives a second core.
#[derive(Debug)]
struct SolveTree {
    /// The supernodes of each subtree solved in parallel, ascending.
    tasks: Vec<Vec<usize>>,
    /// The other supernodes, ascending.
    top: Vec<usize>,
    /// For each row: its subtree (`usize::MAX` for a row of the top) and its position in
    /// that subtree's rows or among the rows of the top (`top_rows`).
    owner: Vec<usize>,
    local: Vec<usize>,
    /// Rows of the top, ascending.
    top_rows: Vec<usize>,
}

impl SolveTree {
    /// The split of [`split_tree`] weighted by the factor's values, with each subtree's rows
    /// numbered for its gathered buffer. `None` for one thread or if there is nothing to split.
    fn new(
        s: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<usize>,
        threads: usize,
    ) -> Option<Self> {
        let col_ptr_val = s.col_ptr_for_val();
        let weight: Vec<usize> = (0..s.n_supernodes())
            .map(|sn| col_ptr_val[sn + 1] - col_ptr_val[sn])
            .collect();
        let (tasks, top) = split_tree(s, threads, &weight)?;
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let n = s.nrows();
        let mut owner = vec![usize::MAX; n];
        let mut local = vec![0usize; n];
        for (t, members) in tasks.iter().enumerate() {
            let mut position = 0;
            for &sn in members {
                for row in begin[sn]..end[sn] {
                    owner[row] = t;
                    local[row] = position;
                    position += 1;
                }
            }
        }
        let mut top_rows = Vec::new();
        for &sn in &top {
            for row in begin[sn]..end[sn] {
                local[row] = top_rows.len();
                top_rows.push(row);
            }
        }
        Some(Self {
            tasks,
            top,
            owner,
            local,
            top_rows,
        })
    }

    /// The rows of subtree `t` of `x`, gathered.
    fn gather(&self, L: SupernodalLltRef<'_, usize, f64>, t: usize, x: MatRef<'_, f64>) -> Mat<f64> {
        let s = L.symbolic();
        let rows: usize = self.tasks[t]
            .iter()
            .map(|&sn| s.supernode_end()[sn] - s.supernode_begin()[sn])
            .sum();
        let mut buf = Mat::<f64>::zeros(rows, x.ncols());
        for &sn in &self.tasks[t] {
            for row in s.supernode_begin()[sn]..s.supernode_end()[sn] {
                for j in 0..x.ncols() {
                    buf[(self.local[row], j)] = x[(row, j)];
                }
            }
        }
        buf
    }

    /// Writes the gathered rows `buf` of subtree `t` back into `x`.
    fn scatter(&self, L: SupernodalLltRef<'_, usize, f64>, t: usize, buf: &Mat<f64>, mut x: MatMut<'_, f64>) {
        let s = L.symbolic();
        for &sn in &self.tasks[t] {
            for row in s.supernode_begin()[sn]..s.supernode_end()[sn] {
                for j in 0..x.ncols() {
                    x[(row, j)] = buf[(self.local[row], j)];
                }
            }
        }
    }

    /// $\mathbf L\mathbf x = \mathbf b$ in place.
    fn l_solve(&self, L: SupernodalLltRef<'_, usize, f64>, mut x: MatMut<'_, f64>, par: Par) {
        let k = x.ncols();
        let n_top = self.top_rows.len();
        // The subtrees, each on its own rows, with a buffer for the updates of the top's rows.
        let x_in = x.rb();
        let solved: Vec<(Mat<f64>, Mat<f64>)> = (0..self.tasks.len())
            .into_par_iter()
            .with_max_len(1)
            .map(|t| {
                let mut buf = self.gather(L, t, x_in);
                let mut ext = Mat::<f64>::zeros(n_top, k);
                let mut tmp = Vec::new();
                for &sn in &self.tasks[t] {
                    let node = L.supernode(sn);
                    let (Ls_top, Ls_bot) = node.val().split_at_row(node.val().ncols());
                    let start = self.local[node.start()];
                    let mut x_top = buf.as_mut().subrows_mut(start, Ls_top.nrows());
                    solve_lower_triangular_in_place(Ls_top, x_top.rb_mut(), Par::Seq);
                    let pattern = node.pattern();
                    tmp.resize(pattern.len() * k, 0.0);
                    let mut u = MatMut::from_column_major_slice_mut(&mut tmp, pattern.len(), k);
                    matmul(u.rb_mut(), Accum::Replace, Ls_bot, x_top.rb(), 1.0, Par::Seq);
                    for j in 0..k {
                        for (idx, &i) in pattern.iter().enumerate() {
                            if self.owner[i] == t {
                                buf[(self.local[i], j)] -= u[(idx, j)];
                            } else {
                                ext[(self.local[i], j)] -= u[(idx, j)];
                            }
                        }
                    }
                }
                (buf, ext)
            })
            .collect();
        for (t, (buf, ext)) in solved.iter().enumerate() {
            self.scatter(L, t, buf, x.rb_mut());
            for j in 0..k {
                for (q, &row) in self.top_rows.iter().enumerate() {
                    x[(row, j)] += ext[(q, j)];
                }
            }
        }
        // The top, in order, each supernode's panel by row ranges on all threads.
        let threads = par.degree();
        let mut tmp = Vec::new();
        for &sn in &self.top {
            let (panel, pattern, start, mut y) = top_block(L, sn, x.rb(), &mut tmp);
            let w = panel.ncols();
            panel_forward(panel, y.rb_mut(), threads);
            x.rb_mut().subrows_mut(start, w).copy_from(y.rb().subrows(0, w));
            for j in 0..k {
                for (idx, &i) in pattern.iter().enumerate() {
                    x[(i, j)] += y[(w + idx, j)];
                }
            }
        }
    }

    /// $\mathbf L^T\mathbf x = \mathbf b$ in place.
    fn l_transpose_solve(&self, L: SupernodalLltRef<'_, usize, f64>, mut x: MatMut<'_, f64>, par: Par) {
        let k = x.ncols();
        // The top first, in reverse order, each supernode's panel by column ranges on all
        // threads.
        let threads = par.degree();
        let mut tmp = Vec::new();
        for &sn in self.top.iter().rev() {
            let (panel, pattern, start, mut y) = top_block(L, sn, x.rb(), &mut tmp);
            let w = panel.ncols();
            for j in 0..k {
                for (idx, &i) in pattern.iter().enumerate() {
                    y[(w + idx, j)] = x[(i, j)];
                }
            }
            panel_backward(panel, y.rb_mut(), threads);
            x.rb_mut().subrows_mut(start, w).copy_from(y.rb().subrows(0, w));
        }
        // Then the subtrees, each on its own rows, reading the top's rows.
        let top_values = Mat::<f64>::from_fn(self.top_rows.len(), k, |q, j| x[(self.top_rows[q], j)]);
        let x_in = x.rb();
        let solved: Vec<Mat<f64>> = (0..self.tasks.len())
            .into_par_iter()
            .with_max_len(1)
            .map(|t| {
                let mut buf = self.gather(L, t, x_in);
                let mut tmp = Vec::new();
                for &sn in self.tasks[t].iter().rev() {
                    let node = L.supernode(sn);
                    let (Ls_top, Ls_bot) = node.val().split_at_row(node.val().ncols());
                    let pattern = node.pattern();
                    tmp.resize(pattern.len() * k, 0.0);
                    let mut u = MatMut::from_column_major_slice_mut(&mut tmp, pattern.len(), k);
                    for j in 0..k {
                        for (idx, &i) in pattern.iter().enumerate() {
                            u[(idx, j)] = if self.owner[i] == t {
                                buf[(self.local[i], j)]
                            } else {
                                top_values[(self.local[i], j)]
                            };
                        }
                    }
                    let start = self.local[node.start()];
                    let mut x_top = buf.as_mut().subrows_mut(start, Ls_top.nrows());
                    matmul(x_top.rb_mut(), Accum::Add, Ls_bot.transpose(), u.rb(), -1.0, Par::Seq);
                    solve_upper_triangular_in_place(Ls_top.transpose(), x_top, Par::Seq);
                }
                buf
            })
            .collect();
        for (t, buf) in solved.iter().enumerate() {
            self.scatter(L, t, buf, x.rb_mut());
        }
    }
}

/// Columns of a top supernode's panel per step of [`panel_forward`] and [`panel_backward`]:
/// the diagonal block of each step is solved on one thread, the rows below it by all.
const PANEL_STEP: usize = 128;

/// Rows (of a panel below a step's diagonal block) per parallel piece at least: below,
/// a product is not worth a task.
const PANEL_MIN_ROWS: usize = 256;

/// The work block of top supernode `sn` of `L` for the columns of `x`, in `tmp`: its panel,
/// its row pattern below the diagonal block, its first row, and the block $\mathbf y$ with the
/// diagonal block's rows of `x` on top (the rows below it unset).
#[allow(clippy::type_complexity)]
fn top_block<'a, 'b>(
    L: SupernodalLltRef<'a, usize, f64>,
    sn: usize,
    x: MatRef<'_, f64>,
    tmp: &'b mut Vec<f64>,
) -> (MatRef<'a, f64>, &'a [usize], usize, MatMut<'b, f64>) {
    let node = L.supernode(sn);
    let (panel, pattern) = (node.val(), node.pattern());
    let w = panel.ncols();
    tmp.clear();
    tmp.resize(panel.nrows() * x.ncols(), 0.0);
    let mut y = MatMut::from_column_major_slice_mut(tmp, panel.nrows(), x.ncols());
    y.rb_mut().subrows_mut(0, w).copy_from(x.subrows(node.start(), w));
    (panel, pattern, node.start(), y)
}

/// $\mathbf y \leftarrow$ the forward solve with the panel $\mathbf L_s = \[\mathbf L_{ss};
/// \mathbf L_{bs}\]$ of one supernode ($w$ columns, $w + m$ rows): $\mathbf y_{0:w}$ becomes
/// $\mathbf L_{ss}^{-1}\mathbf y_{0:w}$ and $\mathbf y_{w:w+m}$ has
/// $\mathbf L_{bs}\mathbf L_{ss}^{-1}\mathbf y_{0:w}$ subtracted. By steps of
/// [`PANEL_STEP`] columns: the step's diagonal block solved, then all rows below it updated
/// in row ranges on `threads` threads (a solve with few right-hand sides reads the panel once
/// and is bound by memory bandwidth, so the rows, not the columns, are split).
fn panel_forward(Ls: MatRef<'_, f64>, mut y: MatMut<'_, f64>, threads: usize) {
    let (rows, w) = Ls.shape();
    let mut j0 = 0;
    while j0 < w {
        let jb = PANEL_STEP.min(w - j0);
        let (head, rest) = y.rb_mut().split_at_row_mut(j0 + jb);
        let mut block = head.subrows_mut(j0, jb);
        solve_lower_triangular_in_place(Ls.submatrix(j0, j0, jb, jb), block.rb_mut(), Par::Seq);
        let below = Ls.submatrix(j0 + jb, j0, rows - j0 - jb, jb);
        let pieces = (below.nrows() / PANEL_MIN_ROWS).clamp(1, 4 * threads.max(1));
        if threads < 2 || pieces < 2 {
            matmul(rest, Accum::Add, below, block.rb(), -1.0, Par::Seq);
        } else {
            let chunk = below.nrows().div_ceil(pieces);
            below
                .par_row_chunks(chunk)
                .zip(rest.par_row_chunks_mut(chunk))
                .for_each(|(a, c)| matmul(c, Accum::Add, a, block.rb(), -1.0, Par::Seq));
        }
        j0 += jb;
    }
}

/// The backward solve with the panel of [`panel_forward`]: $\mathbf y_{0:w} \leftarrow
/// \mathbf L_{ss}^{-T}(\mathbf y_{0:w} - \mathbf L_{bs}^T\mathbf y_{w:w+m})$. By steps of
/// [`PANEL_STEP`] columns from the last: the step's rows of $\mathbf y$ updated with the
/// rows below its diagonal block, the step's columns split on `threads` threads, then its
/// diagonal block solved.
fn panel_backward(Ls: MatRef<'_, f64>, mut y: MatMut<'_, f64>, threads: usize) {
    let (rows, w) = Ls.shape();
    let mut end = w;
    while end > 0 {
        let jb = (end - 1) % PANEL_STEP + 1;
        let j0 = end - jb;
        let (head, rest) = y.rb_mut().split_at_row_mut(end);
        let mut block = head.subrows_mut(j0, jb);
        let below = Ls.submatrix(end, j0, rows - end, jb);
        // Pieces of at least 8 columns and PANEL_MIN_ROWS x PANEL_STEP values.
        let pieces = (below.nrows() * jb / (PANEL_MIN_ROWS * PANEL_STEP))
            .clamp(1, 4 * threads.max(1))
            .min(jb / 8);
        if threads < 2 || pieces < 2 {
            matmul(block.rb_mut(), Accum::Add, below.transpose(), rest.rb(), -1.0, Par::Seq);
        } else {
            let chunk = jb.div_ceil(pieces);
            below
                .par_col_chunks(chunk)
                .zip(block.rb_mut().par_row_chunks_mut(chunk))
                .for_each(|(a, c)| matmul(c, Accum::Add, a.transpose(), rest.rb(), -1.0, Par::Seq));
        }
        solve_upper_triangular_in_place(Ls.submatrix(j0, j0, jb, jb).transpose(), block, Par::Seq);
        end = j0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::{SparseColMat, Triplet};

    /// The 7-point Laplacian of an `e x e x e` grid plus the identity (SPD), both triangles,
    /// and the grid positions of its rows.
    fn grid_laplacian(e: usize) -> (SparseColMat<usize, f64>, Vec<[f64; 3]>) {
        let id = |i: usize, j: usize, k: usize| i + e * (j + e * k);
        let mut triplets = Vec::new();
        let mut points = vec![[0.0; 3]; e * e * e];
        for k in 0..e {
            for j in 0..e {
                for i in 0..e {
                    let r = id(i, j, k);
                    points[r] = [i as f64, j as f64, k as f64];
                    triplets.push(Triplet::new(r, r, 7.0));
                    for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        let (a, b, c) = (i + di, j + dj, k + dk);
                        if a < e && b < e && c < e {
                            let s = id(a, b, c);
                            triplets.push(Triplet::new(r, s, -1.0));
                            triplets.push(Triplet::new(s, r, -1.0));
                        }
                    }
                }
            }
        }
        let n = e * e * e;
        (SparseColMat::try_new_from_triplets(n, n, &triplets).unwrap(), points)
    }

    /// The parallel triangular solves of [`SolveTree`] against faer's sequential supernodal
    /// solves on the same factor: equal to round-off, for one and several right-hand sides.
    #[test]
    fn tree_solves_match_faer_sequential_solves() {
        // A balanced tree (a cube) and an unbalanced one (a cube, a chain and a small cube).
        for (A, points) in [grid_laplacian(22), unbalanced(16, 300, 6)] {
            tree_solves_match(&A, &points);
        }
    }

    /// $\|\mathbf A\mathbf x - \mathbf b\|_\infty / \|\mathbf b\|_\infty$ of the solution
    /// $\mathbf x$ of $\mathbf A\mathbf x = \mathbf b$ by `chol`.
    fn relative_residual(A: &SparseColMat<usize, f64>, chol: &SparseCholesky, b: &Mat<f64>) -> f64 {
        let mut x = b.clone();
        chol.solve_in_place(x.as_mut());
        (A * &x - b).norm_max() / b.norm_max()
    }

    /// The tree's forward and backward solves on 2 threads against faer's sequential ones,
    /// for 1, 4 and 8 right-hand sides, and the whole solve against `A`.
    fn tree_solves_match(A: &SparseColMat<usize, f64>, points: &[[f64; 3]]) {
        let n = A.nrows();
        let chol = SparseCholesky::new(A.as_ref(), Some(points), FillOrdering::NestedDissection).unwrap();
        let SymbolicCholeskyRaw::Supernodal(s) = chol.symbolic.raw() else {
            panic!("a 3D grid of {n} rows should give a supernodal factor");
        };
        let tree = SolveTree::new(s, 2).expect("nested dissection gives supernodes in postorder");
        assert!(tree.tasks.len() >= 2, "{} subtrees", tree.tasks.len());
        let L = SupernodalLltRef::<'_, usize, f64>::new(s, chol.double());
        let par = Par::rayon(2);
        for k in [1, 3, 4, 8] {
            let B = Mat::<f64>::from_fn(n, k, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0);
            let mut mem = MemBuffer::new(chol.solve_scratch(k, Par::Seq));
            // Forward and backward: sequential faer, then the tree's.
            type Sweep<'a> = (
                &'a str,
                &'a dyn Fn(MatMut<'_, f64>, &mut MemStack),
                &'a dyn Fn(MatMut<'_, f64>),
            );
            let sweeps: [Sweep; 2] = [
                (
                    "L x = b",
                    &|x, stack| L.l_solve_with_conj(Conj::No, x, Par::Seq, stack),
                    &|x| tree.l_solve(L, x, par),
                ),
                (
                    "L^T x = b",
                    &|x, stack| L.l_transpose_solve_with_conj(Conj::No, x, Par::Seq, stack),
                    &|x| tree.l_transpose_solve(L, x, par),
                ),
            ];
            for (what, sequential, parallel) in sweeps {
                let mut x_seq = B.clone();
                sequential(x_seq.as_mut(), MemStack::new(&mut mem));
                let mut x_par = B.clone();
                parallel(x_par.as_mut());
                let err = (&x_par - &x_seq).norm_max() / x_seq.norm_max();
                assert!(
                    err < 1e-13,
                    "{what}, {k} right-hand sides: relative difference {err:.2e}"
                );
            }
        }
        // The whole solve (permutation and both triangles) against A itself.
        let b = Mat::<f64>::from_fn(n, 2, |i, j| ((i * 5 + j) % 11) as f64 - 5.0);
        let r = relative_residual(A, &chol, &b);
        assert!(r < 1e-12, "A x = b: relative residual {r:.2e}");
    }

    /// The blocked panel solves of the top supernodes against faer's dense triangular solves
    /// and product, sequential, on a panel wider than [`PANEL_STEP`] (a last step of partial
    /// width) and tall enough for every split, with 1 to 3 threads and 1, 4 and 8 right-hand
    /// sides.
    #[test]
    fn panel_solves_match_dense_solves() {
        let (w, m) = (2 * PANEL_STEP + 37, 9 * PANEL_MIN_ROWS + 5);
        // A well-conditioned lower triangle (dominant diagonal) over a full block.
        let Ls = Mat::<f64>::from_fn(w + m, w, |i, j| match i.cmp(&j) {
            std::cmp::Ordering::Less => 0.0,
            std::cmp::Ordering::Equal => 4.0 + (i % 5) as f64,
            std::cmp::Ordering::Greater => (((i * 31 + j * 17) % 23) as f64 - 11.0) / (11.0 * w as f64),
        });
        let (Lss, Lbs) = Ls.as_ref().split_at_row(w);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
        for k in [1, 4, 8] {
            let y0 = Mat::<f64>::from_fn(w + m, k, |i, j| ((i * 7 + j * 13) % 19) as f64 - 9.0);
            // Forward: y_s <- L_ss^{-1} y_s, y_b <- y_b - L_bs y_s.
            let mut fwd = y0.clone();
            let (mut ys, mut yb) = fwd.as_mut().split_at_row_mut(w);
            solve_lower_triangular_in_place(Lss, ys.rb_mut(), Par::Seq);
            matmul(yb.rb_mut(), Accum::Add, Lbs, ys.rb(), -1.0, Par::Seq);
            // Backward: y_s <- L_ss^{-T} (y_s - L_bs^T y_b).
            let mut bwd = y0.clone();
            let (mut ys, yb) = bwd.as_mut().split_at_row_mut(w);
            matmul(ys.rb_mut(), Accum::Add, Lbs.transpose(), yb.rb(), -1.0, Par::Seq);
            solve_upper_triangular_in_place(Lss.transpose(), ys.rb_mut(), Par::Seq);
            for threads in 1..=3 {
                let mut y = y0.clone();
                pool.install(|| panel_forward(Ls.as_ref(), y.as_mut(), threads));
                let err = (&y - &fwd).norm_max() / fwd.norm_max();
                // Different summation orders only: round-off of a few hundred terms.
                assert!(err < 1e-13, "forward, {threads} threads, k = {k}: {err:.2e}");
                let mut y = y0.clone();
                pool.install(|| panel_backward(Ls.as_ref(), y.as_mut(), threads));
                let err = (&y - &bwd).norm_max() / bwd.norm_max();
                assert!(err < 1e-13, "backward, {threads} threads, k = {k}: {err:.2e}");
            }
        }
    }

    /// A 3D grid Laplacian of `e^3` rows and a chain of `c` rows tied to its corner, plus a
    /// small grid of `f^3` rows tied to the chain's end: an elimination tree with subtrees of
    /// very different sizes under a long path. Both triangles, and positions for nested
    /// dissection.
    fn unbalanced(e: usize, c: usize, f: usize) -> (SparseColMat<usize, f64>, Vec<[f64; 3]>) {
        let (big, mut points) = grid_laplacian(e);
        let (small, small_points) = grid_laplacian(f);
        let (nb, ns) = (big.nrows(), small.nrows());
        let n = nb + c + ns;
        let mut triplets = Vec::new();
        for (m, offset) in [(&big, 0), (&small, nb + c)] {
            for j in 0..m.ncols() {
                for (&i, &v) in m.row_idx_of_col_raw(j).iter().zip(m.val_of_col(j)) {
                    triplets.push(Triplet::new(i + offset, j + offset, v));
                }
            }
        }
        let edge = |t: &mut Vec<Triplet<usize, usize, f64>>, a: usize, b: usize| {
            t.push(Triplet::new(a, b, -1.0));
            t.push(Triplet::new(b, a, -1.0));
        };
        for k in 0..c {
            triplets.push(Triplet::new(nb + k, nb + k, 3.0));
            edge(&mut triplets, nb + k, if k == 0 { 0 } else { nb + k - 1 });
            points.push([-1.0 - k as f64, 0.0, 0.0]);
        }
        edge(&mut triplets, nb + c - 1, nb + c);
        points.extend(small_points.iter().map(|p| [p[0] - 2.0 - c as f64, p[1], p[2]]));
        (SparseColMat::try_new_from_triplets(n, n, &triplets).unwrap(), points)
    }

    /// The analysis of `B` with the subtree-parallel factorisation planned for `threads`
    /// threads (`None`: faer's loop); with `branched` false, the top run in order after the
    /// subtrees rather than by concurrent branches.
    fn analyse_for(
        B: &SparseColMat<usize, f64>,
        points: &[[f64; 3]],
        ordering: FillOrdering,
        threads: Option<usize>,
        branched: bool,
    ) -> (SymbolicFactor, bool) {
        let mut symbolic = SymbolicFactor::analyse(B.symbolic(), Some(points), ordering).unwrap();
        let planned = symbolic.set_parallel_subtrees(threads);
        if !branched {
            if let Some(plan) = &mut symbolic.plan {
                plan.run_top_in_order();
            }
        }
        (symbolic, planned)
    }

    /// The factor of the subtree-parallel path and faer's of the same analysis, in
    /// `precision`, with the split for 2 threads run on 2 threads, the top by concurrent
    /// branches where they are contiguous (`branched`) or in order; the number of subtrees and
    /// whether the branches ran concurrently.
    fn both_factors(
        A: &SparseColMat<usize, f64>,
        points: &[[f64; 3]],
        ordering: FillOrdering,
        precision: Precision,
        branched: bool,
    ) -> (SparseCholesky, SparseCholesky, usize, bool) {
        let (faer_symbolic, _) = analyse_for(A, points, ordering, None, true);
        let (ours_symbolic, planned) = analyse_for(A, points, ordering, Some(2), branched);
        assert!(planned, "a supernodal factor of {} rows should split", A.nrows());
        let concurrent = ours_symbolic.plan.as_ref().is_some_and(|plan| plan.branched());
        let subtrees = ours_symbolic.parallel_subtrees().0;
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let ours = pool.install(|| ours_symbolic.factor(A.as_ref(), precision).unwrap());
        (
            ours,
            faer_symbolic.factor(A.as_ref(), precision).unwrap(),
            subtrees,
            concurrent,
        )
    }

    /// The subtree-parallel numeric factorisation against faer's supernodal loop on the same
    /// analysis: equal values to round-off, in double and single precision, on a grid
    /// Laplacian (a balanced nested-dissection tree, its root separator of 484 columns large
    /// enough for the blocked parallel dense Cholesky) and on a matrix whose tree is
    /// unbalanced (AMD and nested dissection), with the top by concurrent branches and in
    /// order.
    #[test]
    fn subtree_parallel_factor_matches_faer() {
        let cases = [
            ("grid", grid_laplacian(22), FillOrdering::NestedDissection),
            ("unbalanced, AMD", unbalanced(16, 400, 7), FillOrdering::Amd),
            ("unbalanced, ND", unbalanced(16, 400, 7), FillOrdering::NestedDissection),
        ];
        for (name, (A, points), ordering) in &cases {
            // Round-off: both sum the same products of each update in their own order, the
            // difference grows with the supernode's depth in the tree; 1e-12 is ~5000 eps64
            // and 2e-4 ~1700 eps32 (a few per cent of the f32 factor's own error
            // kappa * eps32 on these matrices).
            for (precision, tolerance, branched) in [
                (Precision::Double, 1e-12, true),
                (Precision::Single, 2e-4, true),
                (Precision::Double, 1e-12, false),
                (Precision::Single, 2e-4, false),
            ] {
                let (ours, faer, subtrees, concurrent) = both_factors(A, points, *ordering, precision, branched);
                assert!(subtrees >= 2, "{name}: {subtrees} subtrees");
                // The grid's and the unbalanced matrix's AMD supernodes give contiguous
                // branches (faer's near-postorder); nested dissection of the unbalanced
                // matrix does not, which takes the path of the top in order.
                let expected = branched && *name != "unbalanced, ND";
                assert_eq!(concurrent, expected, "{name}: the top by concurrent branches");
                let difference = ours.relative_difference(&faer);
                assert!(
                    difference <= tolerance,
                    "{name}, {}, branched {branched}: largest difference relative to a supernode's norm {difference:.2e}",
                    precision.name()
                );
                // And the solve with it.
                if precision == Precision::Double {
                    let b = Mat::<f64>::from_fn(A.nrows(), 1, |i, _| ((i * 7) % 13) as f64 - 6.0);
                    let r = relative_residual(A, &ours, &b);
                    assert!(r < 1e-12, "{name}, branched {branched}: relative residual {r:.2e}");
                }
            }
        }
    }

    /// A non-positive pivot is reported with the dof of the matrix as given, the same as
    /// faer's sequential loop reports: one in a subtree, one in the top separator (in its
    /// blocked parallel dense Cholesky), and two in different subtrees (the first in the
    /// factor's order is reported); in double and single precision, the top by concurrent
    /// branches and in order.
    #[test]
    fn subtree_parallel_factor_reports_the_non_positive_pivot() {
        let (A, points) = grid_laplacian(22);
        let n = A.nrows();
        let analysed = SymbolicFactor::analyse(A.symbolic(), Some(&points), FillOrdering::NestedDissection).unwrap();
        // The last row of the factor belongs to the root separator, the first to a leaf.
        let (first, last) = (analysed.perm_fwd[0], analysed.perm_fwd[n - 1]);
        let middle = analysed.perm_fwd[n / 3];
        for bad in [vec![first], vec![last], vec![middle, first], vec![last, middle]] {
            let mut B = A.clone();
            for j in 0..n {
                let rows = B.row_idx_of_col_raw(j).to_vec();
                for (k, &i) in rows.iter().enumerate() {
                    if i == j && bad.contains(&j) {
                        B.val_of_col_mut(j)[k] = -1.0;
                    }
                }
            }
            let error = |threads, branched, precision| {
                let (symbolic, _) = analyse_for(&B, &points, FillOrdering::NestedDissection, threads, branched);
                let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
                match pool.install(|| symbolic.factor(B.as_ref(), precision)) {
                    Err(CholeskyError::NonPositivePivot { dof }) => dof,
                    other => panic!("dofs {bad:?} negative: {other:?}"),
                }
            };
            for precision in [Precision::Double, Precision::Single] {
                let faer = error(None, true, precision);
                for branched in [true, false] {
                    let ours = error(Some(2), branched, precision);
                    assert_eq!(ours, faer, "dofs {bad:?} negative, branched {branched}");
                    assert!(bad.contains(&ours), "dofs {bad:?} negative, reported {ours}");
                }
            }
        }
    }
}
