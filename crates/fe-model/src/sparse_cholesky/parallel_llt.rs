//! The numeric supernodal factorisation $\mathbf P\mathbf A\mathbf P^T = \mathbf L\mathbf L^T$
//! on faer's symbolic structure, parallel over subtrees of the supernodal elimination tree.
//!
//! Left-looking: supernode $s$ (columns $c_s..e_s$, rows below them $\mathcal R_s$) gathers
//! the columns of $\mathbf P\mathbf A\mathbf P^T$, subtracts the update of every descendant
//! $d$ whose rows reach $s$,
//! $$\mathbf L_s \leftarrow \mathbf L_s - \mathbf L_{d,\mathcal R}\,\mathbf L_{d,\mathcal C}^T,
//! \qquad \mathcal C = \mathcal R_d \cap [c_s, e_s),\ \mathcal R = \mathcal R_d \cap [c_s, n),$$
//! then factors its diagonal block $\mathbf L_{s,ss}\mathbf L_{s,ss}^T$ and solves the rows below
//! it, $\mathbf L_{s,\mathcal R_s} \leftarrow \mathbf L_{s,\mathcal R_s}\mathbf L_{s,ss}^{-T}$
//! (theory guide, linear analyses of a part). A supernode reads only its descendants'
//! columns and writes only its own, so disjoint subtrees are independent (Liu, "The role of
//! elimination trees in sparse factorization", SIAM J. Matrix Anal. Appl. 11, 1990): each
//! subtree runs on one thread with sequential dense kernels. Then the supernodes above the
//! subtrees (the top separators of a nested dissection, few and large) run in order, each with
//! its columns gathered by ranges in parallel (the descendants' updates of those columns,
//! sequential products) and its rows below the diagonal block solved by ranges in parallel;
//! only the dense Cholesky of the diagonal block is faer's parallel one. faer's own loop runs
//! the supernodes in order and parallelises only inside the dense kernels, which on two cores
//! spends about a quarter of the CPU time in thread barriers.
//!
//! Each subtree of the split must be a contiguous range of supernodes and of values, so that
//! the factor splits into disjoint mutable slices: [`FactorPlan::new`] checks it (faer's
//! supernodes are in a near-postorder, which makes the subtrees of the split contiguous on
//! the meshes measured; where they are not, faer's loop is used).

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{cholesky_in_place, cholesky_in_place_scratch, LltError};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::sparse::SparseColMatRef;
use faer::{Accum, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::ops::Range;

/// Columns of a descendant's update computed at a time: bounds the update buffer to
/// (rows of the descendant) x `UPDATE_COLUMNS` values.
const UPDATE_COLUMNS: usize = 256;

/// A value type of the factor (f64 or f32).
pub(super) trait Real:
    faer::traits::RealField + Copy + Send + Sync + std::ops::AddAssign + std::ops::SubAssign
{
}
impl Real for f64 {}
impl Real for f32 {}

/// The schedule of the parallel factorisation: the descendants that update each supernode,
/// the subtrees run in parallel and the supernodes above them.
#[derive(Debug)]
pub(super) struct FactorPlan {
    /// `descendants[descendant_ptr[s]..descendant_ptr[s + 1]]`: the supernodes $d < s$ with a
    /// row of their pattern among the columns of $s$, ascending.
    descendant_ptr: Vec<usize>,
    descendants: Vec<usize>,
    /// The subtrees, each a contiguous range of supernodes, ascending and disjoint.
    pub(super) tasks: Vec<Range<usize>>,
    /// The floating-point operations of each subtree's columns.
    task_flops: Vec<usize>,
    /// The other supernodes, ascending.
    pub(super) top: Vec<usize>,
    /// Largest pattern below a diagonal block (rows of the update buffer).
    max_pattern: usize,
    /// Largest supernode (columns).
    max_columns: usize,
}

/// Floating-point operations of the columns of supernode `sn`: $\sum_j c_j^2$ over its
/// columns, $c_j$ the entries of column $j$ of $\mathbf L$ (as [`crate::factor_flops`]).
pub(super) fn supernode_flops(s: &SymbolicSupernodalCholesky<usize>, sn: usize) -> usize {
    let k = s.supernode_end()[sn] - s.supernode_begin()[sn];
    let p = s.supernode(sn).pattern().len();
    (0..k).map(|j| (k - j + p) * (k - j + p)).sum()
}

impl FactorPlan {
    /// The plan for `threads` threads: the supernodal tree split by floating-point operations
    /// ([`super::split_tree`]). `None` if there is nothing to split (one thread, one
    /// subtree) or a subtree of the split is not a contiguous range of supernodes.
    pub(super) fn new(s: &SymbolicSupernodalCholesky<usize>, threads: usize) -> Option<Self> {
        let ns = s.n_supernodes();
        let weight: Vec<usize> = (0..ns).map(|sn| supernode_flops(s, sn)).collect();
        let (tasks, top) = super::split_tree(s, threads, &weight)?;
        let mut ranges = Vec::with_capacity(tasks.len());
        for members in &tasks {
            let (first, last) = (members[0], members[members.len() - 1]);
            if last - first + 1 != members.len() {
                return None;
            }
            ranges.push(first..last + 1);
        }
        ranges.sort_unstable_by_key(|r| r.start);
        // The descendants of each supernode: d updates the supernodes its pattern's rows
        // belong to (sorted rows, so each supernode once per d, and d ascending).
        let (begin, end) = (s.supernode_begin(), s.supernode_end());
        let mut supernode_of_row = vec![0usize; s.nrows()];
        for sn in 0..ns {
            supernode_of_row[begin[sn]..end[sn]].fill(sn);
        }
        let supernode_of_row = &supernode_of_row;
        let targets = |d: usize| {
            let pattern = s.supernode(d).pattern();
            let mut last = usize::MAX;
            pattern.iter().filter_map(move |&row| {
                let t = supernode_of_row[row];
                (t != last).then(|| {
                    last = t;
                    t
                })
            })
        };
        let mut descendant_ptr = vec![0usize; ns + 1];
        for d in 0..ns {
            for t in targets(d) {
                descendant_ptr[t + 1] += 1;
            }
        }
        for sn in 0..ns {
            descendant_ptr[sn + 1] += descendant_ptr[sn];
        }
        let mut next = descendant_ptr[..ns].to_vec();
        let mut descendants = vec![0usize; descendant_ptr[ns]];
        for d in 0..ns {
            for t in targets(d) {
                descendants[next[t]] = d;
                next[t] += 1;
            }
        }
        let max_pattern = (0..ns).map(|sn| s.supernode(sn).pattern().len()).max().unwrap_or(0);
        let max_columns = (0..ns).map(|sn| end[sn] - begin[sn]).max().unwrap_or(0);
        Some(Self {
            descendant_ptr,
            descendants,
            task_flops: ranges.iter().map(|r| r.clone().map(|sn| weight[sn]).sum()).collect(),
            tasks: ranges,
            top,

            max_pattern,
            max_columns,
        })
    }

    /// Bytes of the workspace of one task in precision `T`: the row map, the update buffer
    /// and its row positions, the dense factorisation's scratch.
    fn task_bytes<T: Real>(&self, n: usize) -> usize {
        let update = self.max_pattern + self.max_columns;
        n * size_of::<usize>()
            + update * UPDATE_COLUMNS.min(self.max_columns) * size_of::<T>()
            + update * size_of::<usize>()
            + cholesky_in_place_scratch::<T>(self.max_columns, Par::Seq, Default::default()).size_bytes()
    }

    /// Bytes that [`factor`] allocates beside the values of $\mathbf L$ with `threads`
    /// threads, for a matrix of dimension `n` with `lower` stored entries in its lower
    /// triangle: the permuted lower triangle and one task's workspace per thread (the plan's
    /// own arrays not counted).
    pub(super) fn workspace_bytes<T: Real>(&self, n: usize, lower: usize, threads: usize) -> usize {
        lower * (size_of::<T>() + size_of::<usize>())
            + (n + 1) * size_of::<usize>()
            + threads.max(1) * self.task_bytes::<T>(n)
    }

    /// Bytes of the plan itself.
    pub(super) fn bytes(&self) -> usize {
        (self.descendant_ptr.len() + self.descendants.len() + 2 * self.tasks.len() + self.top.len())
            * size_of::<usize>()
    }
}

/// The update buffers of one thread.
struct Buffers<T> {
    /// The update of one descendant, by blocks of columns.
    update: Vec<T>,
    /// Rows of the current supernode's block that the update's rows go to.
    positions: Vec<usize>,
}

/// The workspace of one thread of the subtrees.
struct Scratch<T> {
    /// Row of the factor -> row of the current supernode's block (set for its pattern).
    local: Vec<usize>,
    buffers: Buffers<T>,
    /// Scratch of the dense factorisation of a diagonal block.
    dense: MemBuffer,
}

impl<T> Default for Buffers<T> {
    fn default() -> Self {
        Self {
            update: Vec::new(),
            positions: Vec::new(),
        }
    }
}

impl<T: Real> Scratch<T> {
    fn new(n: usize, max_columns: usize) -> Self {
        Self {
            local: vec![0; n],
            buffers: Buffers::default(),
            dense: MemBuffer::new(cholesky_in_place_scratch::<T>(
                max_columns,
                Par::Seq,
                Default::default(),
            )),
        }
    }
}

/// Columns `columns` (of the supernode's own, from 0) of supernode `sn` before its dense
/// factorisation: the entries of `A` minus the updates of the descendants. `Lc` holds
/// those columns (all rows of the supernode's block, column-major), `head` the values
/// before the supernode, which start at value `base` of the factor and hold all of its
/// descendants; `local` maps the rows of the supernode's pattern to rows of its block.
#[allow(clippy::too_many_arguments)]
fn gather_columns<T: Real>(
    s: &SymbolicSupernodalCholesky<usize>,
    plan: &FactorPlan,
    A: SparseColMatRef<'_, usize, T>,
    sn: usize,
    columns: Range<usize>,
    head: &[T],
    base: usize,
    Lc: &mut [T],
    local: &[usize],
    buffers: &mut Buffers<T>,
    par: Par,
) {
    let (s_start, s_end) = (s.supernode_begin()[sn], s.supernode_end()[sn]);
    let s_nrows = s_end - s_start + s.supernode(sn).pattern().len();
    let col_ptr_val = s.col_ptr_for_val();
    let local_row = |r: usize| if r < s_end { r - s_start } else { local[r] };
    // The columns of A.
    for j in columns.clone() {
        let column = &mut Lc[(j - columns.start) * s_nrows..][..s_nrows];
        let j = s_start + j;
        for (&i, &v) in A.row_idx_of_col_raw(j).iter().zip(A.val_of_col(j)) {
            if i >= j {
                column[local_row(i)] += v;
            }
        }
    }
    // The updates of the descendants.
    let (first_column, last_column) = (s_start + columns.start, s_start + columns.end);
    for &d in &plan.descendants[plan.descendant_ptr[sn]..plan.descendant_ptr[sn + 1]] {
        let d_pattern = s.supernode(d).pattern();
        let d_ncols = s.supernode_end()[d] - s.supernode_begin()[d];
        // The rows of d from the first of these columns down, and among them those that
        // are these columns.
        let first = d_pattern.partition_point(|&r| r < first_column);
        let rows = &d_pattern[first..];
        let mid = rows.partition_point(|&r| r < last_column);
        if mid == 0 {
            continue;
        }
        let m = rows.len();
        let Ld = MatRef::from_column_major_slice(
            &head[col_ptr_val[d] - base..col_ptr_val[d + 1] - base],
            d_ncols + d_pattern.len(),
            d_ncols,
        );
        let L_rows = Ld.subrows(d_ncols + first, m);
        buffers.positions.clear();
        buffers.positions.extend(rows.iter().map(|&r| local_row(r)));
        let mut c0 = 0;
        while c0 < mid {
            let c1 = (c0 + UPDATE_COLUMNS).min(mid);
            let (w, h) = (c1 - c0, m - c0);
            if buffers.update.len() < w * h {
                buffers.update.resize(w * h, T::zero_impl());
            }
            let mut W = MatMut::from_column_major_slice_mut(&mut buffers.update[..w * h], h, w);
            let B = L_rows.subrows(c0, w);
            let (W_top, W_bottom) = W.rb_mut().split_at_row_mut(w);
            // The block on the diagonal of L_s is symmetric: its lower triangle only.
            triangular::matmul(
                W_top,
                BlockStructure::TriangularLower,
                Accum::Replace,
                B,
                BlockStructure::Rectangular,
                B.transpose(),
                BlockStructure::Rectangular,
                T::one_impl(),
                par,
            );
            matmul(
                W_bottom,
                Accum::Replace,
                L_rows.subrows(c1, m - c1),
                B.transpose(),
                T::one_impl(),
                par,
            );
            let W = &buffers.update[..w * h];
            for jj in 0..w {
                let column = &mut Lc[(buffers.positions[c0 + jj] - columns.start) * s_nrows..][..s_nrows];
                let w_column = &W[jj * h..][..h];
                for (&p, &v) in buffers.positions[c0 + jj..].iter().zip(&w_column[jj..]) {
                    column[p] -= v;
                }
            }
            c0 = c1;
        }
    }
}

/// Supernodes with fewer columns gather their columns in one piece (with `par` in the
/// dense products); larger ones by ranges of columns in parallel.
const PARALLEL_GATHER_MIN_COLUMNS: usize = 64;

/// Factors supernode `sn` in place: `Ls` its values, `head` the values before them, which
/// start at value `base` of the factor and hold all of `sn`'s descendants. `A` is the lower
/// triangle of $\mathbf P\mathbf A\mathbf P^T$. With `par` of several threads the columns
/// are gathered by ranges in parallel. Returns the index (in the factor's order) of a
/// non-positive pivot.
#[allow(clippy::too_many_arguments)]
fn factor_supernode<T: Real>(
    s: &SymbolicSupernodalCholesky<usize>,
    plan: &FactorPlan,
    A: SparseColMatRef<'_, usize, T>,
    sn: usize,
    head: &[T],
    base: usize,
    Ls: &mut [T],
    scratch: &mut Scratch<T>,
    par: Par,
) -> Result<(), usize> {
    let (s_start, s_end) = (s.supernode_begin()[sn], s.supernode_end()[sn]);
    let s_pattern = s.supernode(sn).pattern();
    let s_ncols = s_end - s_start;
    let s_nrows = s_ncols + s_pattern.len();
    for (i, &row) in s_pattern.iter().enumerate() {
        scratch.local[row] = s_ncols + i;
    }
    let threads = par.degree();
    if threads < 2 || s_ncols < PARALLEL_GATHER_MIN_COLUMNS {
        gather_columns(
            s,
            plan,
            A,
            sn,
            0..s_ncols,
            head,
            base,
            Ls,
            &scratch.local,
            &mut scratch.buffers,
            par,
        );
    } else {
        // Ranges of columns with about equal work: column j is updated in its s_nrows - j
        // rows; 2 ranges per thread, so that a thread slowed by the load is helped.
        let ranges = 2 * threads;
        let total: usize = (0..s_ncols).map(|j| s_nrows - j).sum();
        let mut pieces = Vec::with_capacity(ranges);
        let mut rest = &mut *Ls;
        let (mut begin, mut done) = (0, 0);
        for r in 1..=ranges {
            let mut end = begin;
            while end < s_ncols && (r == ranges || done * ranges < r * total) {
                done += s_nrows - end;
                end += 1;
            }
            let (piece, tail) = std::mem::take(&mut rest).split_at_mut((end - begin) * s_nrows);
            rest = tail;
            if end > begin {
                pieces.push((begin..end, piece));
            }
            begin = end;
        }
        let local = &scratch.local;
        pieces
            .into_par_iter()
            .with_max_len(1)
            .for_each_init(Buffers::default, |buffers, (columns, Lc)| {
                gather_columns(s, plan, A, sn, columns, head, base, Lc, local, buffers, Par::Seq)
            });
    }
    // The diagonal block and the rows below it.
    let Ls = MatMut::from_column_major_slice_mut(Ls, s_nrows, s_ncols);
    let (mut Ls_top, Ls_bottom) = Ls.split_at_row_mut(s_ncols);
    match cholesky_in_place(
        Ls_top.rb_mut(),
        Default::default(),
        par,
        MemStack::new(&mut scratch.dense),
        Default::default(),
    ) {
        Ok(_) => {}
        Err(LltError::NonPositivePivot { index }) => return Err(s_start + index),
    }
    // Each row below the diagonal block is solved on its own: with several threads, ranges of
    // rows in parallel with sequential kernels (no barriers inside the solve).
    let rows = Ls_bottom.nrows();
    if threads < 2 || s_ncols < PARALLEL_GATHER_MIN_COLUMNS || rows < 2 * threads {
        solve_lower_triangular_in_place(Ls_top.rb(), Ls_bottom.transpose_mut(), par);
    } else {
        let ranges = 2 * threads;
        let mut pieces = Vec::with_capacity(ranges);
        let mut rest = Ls_bottom;
        for r in 0..ranges {
            let take = rest.nrows() / (ranges - r);
            let (piece, tail) = rest.split_at_row_mut(take);
            pieces.push(piece);
            rest = tail;
        }
        let Ls_top = Ls_top.rb();
        pieces
            .into_par_iter()
            .with_max_len(1)
            .for_each(|piece| solve_lower_triangular_in_place(Ls_top, piece.transpose_mut(), Par::Seq));
    }
    Ok(())
}

/// The values of $\mathbf L$ (`L_values`, zero on entry, `s.len_val()` of them) for the lower
/// triangle `A` of $\mathbf P\mathbf A\mathbf P^T$: the subtrees of `plan` in parallel, each
/// on one thread with sequential dense kernels, then the top in order, each supernode with
/// its columns gathered by ranges in parallel and `par` in its dense factorisation.
///
/// # Errors
/// The index (in the factor's order) of the first non-positive pivot: the smallest among the
/// subtrees that hit one (as the sequential loop would find), else the top's.
pub(super) fn factor<T: Real>(
    s: &SymbolicSupernodalCholesky<usize>,
    plan: &FactorPlan,
    A: SparseColMatRef<'_, usize, T>,
    L_values: &mut [T],
    par: Par,
) -> Result<(), usize> {
    let n = s.nrows();
    let col_ptr_val = s.col_ptr_for_val();
    assert_eq!(L_values.len(), s.len_val());
    // The factor split into the subtrees' disjoint slices.
    let mut chunks = Vec::with_capacity(plan.tasks.len());
    let mut rest = &mut *L_values;
    let mut offset = 0;
    for (t, range) in plan.tasks.iter().enumerate() {
        let (v0, v1) = (col_ptr_val[range.start], col_ptr_val[range.end]);
        let (_, tail) = std::mem::take(&mut rest).split_at_mut(v0 - offset);
        let (chunk, tail) = tail.split_at_mut(v1 - v0);
        rest = tail;
        offset = v1;
        chunks.push((t, v0, chunk));
    }
    // Largest first: each thread takes the largest subtree left when it is free.
    chunks.sort_by_key(|&(t, ..)| plan.task_flops[t]);
    let queue = std::sync::Mutex::new(chunks);
    let first_failure = (0..rayon::current_num_threads().min(plan.tasks.len()))
        .into_par_iter()
        .with_max_len(1)
        .filter_map(|_| {
            let mut scratch = Scratch::<T>::new(n, plan.max_columns);
            let mut failure: Option<usize> = None;
            loop {
                // The lock only to take the next subtree. A poisoned queue (a panic on
                // another thread) still holds valid slices.
                let next = queue.lock().unwrap_or_else(|e| e.into_inner()).pop();
                let Some((t, v0, chunk)) = next else { break };
                for sn in plan.tasks[t].clone() {
                    let (head, tail) = chunk.split_at_mut(col_ptr_val[sn] - v0);
                    let Ls = &mut tail[..col_ptr_val[sn + 1] - col_ptr_val[sn]];
                    if let Err(index) = factor_supernode(s, plan, A, sn, head, v0, Ls, &mut scratch, Par::Seq) {
                        failure = Some(failure.map_or(index, |f| f.min(index)));
                        break;
                    }
                }
            }
            failure
        })
        .min();
    if let Some(index) = first_failure {
        return Err(index);
    }
    let mut scratch = Scratch::<T>::new(n, plan.max_columns);
    for &sn in &plan.top {
        let (head, tail) = L_values.split_at_mut(col_ptr_val[sn]);
        let Ls = &mut tail[..col_ptr_val[sn + 1] - col_ptr_val[sn]];
        factor_supernode(s, plan, A, sn, head, 0, Ls, &mut scratch, par)?;
    }
    Ok(())
}
