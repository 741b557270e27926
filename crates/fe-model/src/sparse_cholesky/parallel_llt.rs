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
//! subtree runs on one thread with sequential dense kernels. The supernodes above the
//! subtrees (the top separators of a nested dissection, few and large) form a tree whose
//! leaves are the subtrees; its branches with no common ancestor are independent too and run
//! concurrently (rayon tasks, the largest first), a top supernode as soon as its children
//! are done, so that a thread done with its subtrees starts on a top separator above them
//! while the other still works below another. A top supernode gathers its columns by ranges
//! in parallel (the descendants' updates of those columns, sequential products), factors its
//! diagonal block right-looking by blocks of columns (each block's rows below solved by
//! ranges, the trailing triangle updated by ranges of columns) and solves its rows below the
//! diagonal block by ranges. Every parallel step is a set of ranges with sequential kernels
//! that a free thread takes, so a thread busy in another branch leaves its share to the
//! others without a barrier waiting for it. faer's own loop runs the supernodes in order and
//! parallelises only inside the dense kernels, which on two cores spends about a quarter of
//! the CPU time in thread barriers.
//!
//! Each subtree of the split, and each top supernode's branch, must be a contiguous range of
//! supernodes and of values, so that the factor splits into disjoint mutable slices:
//! [`FactorPlan::new`] checks it (faer's supernodes are in a near-postorder, which makes them
//! contiguous on the meshes measured). Where a subtree is not contiguous, faer's loop is
//! used; where only a top branch is not, the top runs in order after all the subtrees.

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
use std::sync::atomic::{AtomicUsize, Ordering};

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
    /// The top as a tree over the subtrees, for its independent branches to run
    /// concurrently; `None` if a branch is not a contiguous range of supernodes.
    branches: Option<Branches>,
}

/// A node of the top's tree: a subtree of the split (`plan.tasks[t]`) or a top supernode
/// (`plan.top[k]`) with its branch below it.
#[derive(Clone, Copy, Debug)]
enum Node {
    Task(usize),
    Top(usize),
}

/// The supernodes above the subtrees as a tree whose leaves are the subtrees: each top
/// supernode's branch (itself and all its descendants) is a contiguous range of supernodes
/// tiled by its children's branches, so that the branches split the factor into disjoint
/// slices, and branches with no common ancestor run concurrently.
#[derive(Debug)]
struct Branches {
    /// The children of `plan.top[k]`, the largest (flops) first.
    children: Vec<Vec<Node>>,
    /// The nodes without a parent, the largest first.
    roots: Vec<Node>,
    /// The first supernode of the branch of `plan.top[k]`.
    first: Vec<usize>,
    /// Top supernodes on the longest path from a subtree to a root.
    depth: usize,
}

impl Branches {
    /// The branches of the split `tasks`, `top` of a tree with supernode parents `parent`
    /// (`usize::MAX` for a root) and flops `weight`; `None` if a branch is not contiguous.
    fn new(ns: usize, parent: &[usize], tasks: &[Range<usize>], top: &[usize], weight: &[usize]) -> Option<Self> {
        let mut top_position = vec![usize::MAX; ns];
        for (k, &sn) in top.iter().enumerate() {
            top_position[sn] = k;
        }
        let mut children: Vec<Vec<Node>> = vec![Vec::new(); top.len()];
        let mut roots = Vec::new();
        let mut attach = |node: Node, root: usize| match parent[root] {
            usize::MAX => {
                roots.push(node);
                Some(())
            }
            p => {
                children.get_mut(top_position[p])?.push(node);
                Some(())
            }
        };
        for (t, range) in tasks.iter().enumerate() {
            attach(Node::Task(t), range.end - 1)?;
        }
        for (k, &sn) in top.iter().enumerate() {
            attach(Node::Top(k), sn)?;
        }
        // Ranges and flops, the top ascending (children before parents).
        let mut first = vec![0usize; top.len()];
        let mut flops = vec![0usize; top.len()];
        let mut level = vec![0usize; top.len()];
        let task_flops: Vec<usize> = tasks.iter().map(|r| r.clone().map(|sn| weight[sn]).sum()).collect();
        let range = |node: Node, first: &[usize]| match node {
            Node::Task(t) => tasks[t].clone(),
            Node::Top(k) => first[k]..top[k] + 1,
        };
        // The nodes of `nodes` tile `start..end`.
        let tiles = |nodes: &[Node], first: &[usize], start: usize, end: usize| {
            let mut ranges: Vec<Range<usize>> = nodes.iter().map(|&c| range(c, first)).collect();
            ranges.sort_unstable_by_key(|r| r.start);
            let mut at = start;
            for r in ranges {
                if r.start != at {
                    return false;
                }
                at = r.end;
            }
            at == end
        };
        for k in 0..top.len() {
            let start = children[k]
                .iter()
                .map(|&c| range(c, &first).start)
                .min()
                .unwrap_or(top[k]);
            if !tiles(&children[k], &first, start, top[k]) {
                return None;
            }
            first[k] = start;
            level[k] = 1 + children[k]
                .iter()
                .map(|&c| match c {
                    Node::Task(_) => 0,
                    Node::Top(j) => level[j],
                })
                .max()
                .unwrap_or(0);
            flops[k] = weight[top[k]]
                + children[k]
                    .iter()
                    .map(|&c| match c {
                        Node::Task(t) => task_flops[t],
                        Node::Top(j) => flops[j],
                    })
                    .sum::<usize>();
        }
        if !tiles(&roots, &first, 0, ns) {
            return None;
        }
        let size = |node: &Node| {
            std::cmp::Reverse(match *node {
                Node::Task(t) => task_flops[t],
                Node::Top(k) => flops[k],
            })
        };
        for c in &mut children {
            c.sort_by_key(size);
        }
        roots.sort_by_key(size);
        Some(Self {
            children,
            roots,
            first,
            depth: level.into_iter().max().unwrap_or(0),
        })
    }
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
        let parent: Vec<usize> = (0..ns)
            .map(|sn| {
                s.supernode(sn)
                    .pattern()
                    .first()
                    .map_or(usize::MAX, |&row| supernode_of_row[row])
            })
            .collect();
        let branches = Branches::new(ns, &parent, &ranges, &top, &weight);
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
            branches,
        })
    }

    /// Whether the top's branches run concurrently (else the top runs in order after all the
    /// subtrees).
    #[cfg(test)]
    pub(super) fn branched(&self) -> bool {
        self.branches.is_some()
    }

    /// Runs the top in order after all the subtrees (for the tests of that path, which is
    /// taken where a branch is not contiguous).
    #[cfg(test)]
    pub(super) fn run_top_in_order(&mut self) {
        self.branches = None;
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
    /// triangle: the permuted lower triangle and one task's workspace per thread, or with
    /// concurrent branches up to one per level of the top's tree more (a thread waiting
    /// inside a parallel loop of a top supernode may take another task meanwhile); the plan's
    /// own arrays not counted.
    pub(super) fn workspace_bytes<T: Real>(&self, n: usize, lower: usize, threads: usize) -> usize {
        let per_thread = 1 + self.branches.as_ref().map_or(0, |b| b.depth);
        lower * (size_of::<T>() + size_of::<usize>())
            + (n + 1) * size_of::<usize>()
            + threads.max(1) * per_thread * self.task_bytes::<T>(n)
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

/// What one factorisation factors: the symbolic factor, the plan over its tree and `A`, the
/// lower triangle of $\mathbf P\mathbf A\mathbf P^T$.
struct Problem<'a, T> {
    s: &'a SymbolicSupernodalCholesky<usize>,
    plan: &'a FactorPlan,
    A: SparseColMatRef<'a, usize, T>,
}

// By hand: a derive would ask `T: Copy` of the values, not of the references held.
impl<T> Clone for Problem<'_, T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T> Copy for Problem<'_, T> {}

/// Columns `columns` (of the supernode's own, from 0) of supernode `sn` of `problem` before its dense
/// factorisation: the entries of `A` minus the updates of the descendants. `Lc` holds
/// those columns (all rows of the supernode's block, column-major), `head` the values
/// before the supernode, which start at value `base` of the factor and hold all of its
/// descendants; `local` maps the rows of the supernode's pattern to rows of its block.
#[allow(clippy::too_many_arguments)]
fn gather_columns<T: Real>(
    problem: Problem<'_, T>,
    sn: usize,
    columns: Range<usize>,
    head: &[T],
    base: usize,
    Lc: &mut [T],
    local: &[usize],
    buffers: &mut Buffers<T>,
    par: Par,
) {
    let (s, plan, A) = (problem.s, problem.plan, problem.A);
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

/// Factors supernode `sn` of `problem` in place: `Ls` its values, `head` the values before
/// them, which start at value `base` of the factor and hold all of `sn`'s descendants. With `par` of several threads the columns
/// are gathered by ranges in parallel. Returns the index (in the factor's order) of a
/// non-positive pivot.
#[allow(clippy::too_many_arguments)]
fn factor_supernode<T: Real>(
    problem: Problem<'_, T>,
    sn: usize,
    head: &[T],
    base: usize,
    Ls: &mut [T],
    scratch: &mut Scratch<T>,
    par: Par,
) -> Result<(), usize> {
    let s = problem.s;
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
            problem,
            sn,
            0..s_ncols,
            head,
            base,
            Ls,
            &scratch.local,
            &mut scratch.buffers,
            Par::Seq,
        );
    } else {
        // Ranges of columns with about equal work: column j is updated in its s_nrows - j
        // rows; 2 ranges per thread, so that a thread slowed by the load is helped.
        let mut pieces = Vec::with_capacity(2 * threads);
        let mut rest = &mut *Ls;
        for columns in balanced_column_ranges(s_ncols, s_nrows, 2 * threads) {
            let (piece, tail) = std::mem::take(&mut rest).split_at_mut(columns.len() * s_nrows);
            rest = tail;
            pieces.push((columns, piece));
        }
        let local = &scratch.local;
        pieces
            .into_par_iter()
            .with_max_len(1)
            .for_each_init(Buffers::default, |buffers, (columns, Lc)| {
                gather_columns(problem, sn, columns, head, base, Lc, local, buffers, Par::Seq)
            });
    }
    // The diagonal block and the rows below it.
    let Ls = MatMut::from_column_major_slice_mut(Ls, s_nrows, s_ncols);
    let (mut Ls_top, Ls_bottom) = Ls.split_at_row_mut(s_ncols);
    dense_cholesky(Ls_top.rb_mut(), threads, MemStack::new(&mut scratch.dense)).map_err(|index| s_start + index)?;
    // Each row below the diagonal block is solved on its own: with several threads, ranges of
    // rows in parallel with sequential kernels (no barriers inside the solve).
    let solve_threads = if s_ncols < PARALLEL_GATHER_MIN_COLUMNS {
        1
    } else {
        threads
    };
    solve_rows_below(Ls_top.rb(), Ls_bottom, solve_threads);
    Ok(())
}

/// Columns of a block step of [`dense_cholesky`] on several threads.
const DENSE_BLOCK: usize = 128;

/// Diagonal blocks with fewer columns are factored by faer's sequential dense Cholesky.
const PARALLEL_DENSE_MIN_COLUMNS: usize = 384;

/// The dense Cholesky factor of the symmetric `A` (lower triangle) in place. With `threads`
/// of several threads and a large block, right-looking by blocks of [`DENSE_BLOCK`] columns:
/// each block's diagonal factored on one thread, the rows below it solved by ranges in
/// parallel, the trailing lower triangle updated by ranges of columns in parallel, with
/// sequential kernels (a thread busy elsewhere leaves its ranges to the others, no barrier
/// waits for it). Returns the index of a non-positive pivot.
fn dense_cholesky<T: Real>(mut A: MatMut<'_, T>, threads: usize, stack: &mut MemStack) -> Result<(), usize> {
    let seq = |A: MatMut<'_, T>, stack: &mut MemStack| match cholesky_in_place(
        A,
        Default::default(),
        Par::Seq,
        stack,
        Default::default(),
    ) {
        Ok(_) => Ok(()),
        Err(LltError::NonPositivePivot { index }) => Err(index),
    };
    let n = A.nrows();
    if threads < 2 || n < PARALLEL_DENSE_MIN_COLUMNS {
        return seq(A, stack);
    }
    let mut j = 0;
    while j < n {
        let b = DENSE_BLOCK.min(n - j);
        let (mut A00, _, mut A10, A11) = A.rb_mut().get_mut(j.., j..).split_at_mut(b, b);
        seq(A00.rb_mut(), stack).map_err(|index| j + index)?;
        let A00 = A00.rb();
        solve_rows_below(A00, A10.rb_mut(), threads);
        let A10 = A10.rb();
        // Column c of the trailing block is updated in its m - c rows.
        let m = A11.nrows();
        column_ranges(A11, m, threads)
            .into_par_iter()
            .with_max_len(1)
            .for_each(|(columns, piece)| {
                let (c0, w) = (columns.start, columns.len());
                let (diagonal, below) = piece.subrows_mut(c0, m - c0).split_at_row_mut(w);
                let B = A10.subrows(c0, w);
                triangular::matmul(
                    diagonal,
                    BlockStructure::TriangularLower,
                    Accum::Add,
                    B,
                    BlockStructure::Rectangular,
                    B.transpose(),
                    BlockStructure::Rectangular,
                    T::zero_impl() - T::one_impl(),
                    Par::Seq,
                );
                matmul(
                    below,
                    Accum::Add,
                    A10.subrows(c0 + w, m - c0 - w),
                    B.transpose(),
                    T::zero_impl() - T::one_impl(),
                    Par::Seq,
                );
            });
        j += b;
    }
    Ok(())
}

/// `0..ncols` split into at most `ranges` non-empty ranges of about equal work when column
/// `j` costs `nrows - j` (its rows from the diagonal down).
fn balanced_column_ranges(ncols: usize, nrows: usize, ranges: usize) -> Vec<Range<usize>> {
    let total: usize = (0..ncols).map(|j| nrows - j).sum();
    let mut pieces = Vec::with_capacity(ranges);
    let (mut begin, mut done) = (0, 0);
    for r in 1..=ranges {
        let mut end = begin;
        while end < ncols && (r == ranges || done * ranges < r * total) {
            done += nrows - end;
            end += 1;
        }
        if end > begin {
            pieces.push(begin..end);
        }
        begin = end;
    }
    pieces
}

/// The columns of `A` in the ranges of [`balanced_column_ranges`] for `threads` threads (2
/// per thread, so that a thread slowed by the load is helped), each with its range.
fn column_ranges<T>(A: MatMut<'_, T>, nrows: usize, threads: usize) -> Vec<(Range<usize>, MatMut<'_, T>)> {
    let ranges = balanced_column_ranges(A.ncols(), nrows, 2 * threads);
    let mut pieces = Vec::with_capacity(ranges.len());
    let mut rest = A;
    for columns in ranges {
        let (piece, tail) = rest.split_at_col_mut(columns.len());
        rest = tail;
        pieces.push((columns, piece));
    }
    pieces
}

/// The rows `B` below a factored diagonal block `L`: $\mathbf B \leftarrow \mathbf B\mathbf L^{-T}$,
/// with several threads by ranges of rows in parallel with sequential kernels.
fn solve_rows_below<T: Real>(L: MatRef<'_, T>, B: MatMut<'_, T>, threads: usize) {
    if threads < 2 || B.nrows() < 2 * threads {
        solve_lower_triangular_in_place(L, B.transpose_mut(), Par::Seq);
        return;
    }
    let ranges = 2 * threads;
    let mut pieces = Vec::with_capacity(ranges);
    let mut rest = B;
    for r in 0..ranges {
        let take = rest.nrows() / (ranges - r);
        let (piece, tail) = rest.split_at_row_mut(take);
        pieces.push(piece);
        rest = tail;
    }
    pieces
        .into_par_iter()
        .with_max_len(1)
        .for_each(|piece| solve_lower_triangular_in_place(L, piece.transpose_mut(), Par::Seq));
}

/// The values of $\mathbf L$ (`L_values`, zero on entry, `s.len_val()` of them) for the lower
/// triangle `A` of $\mathbf P\mathbf A\mathbf P^T$ with the threads of `par`: the subtrees
/// of `plan` in parallel, each on one thread with sequential dense kernels, and the top
/// supernodes by concurrent branches (else, where a branch is not contiguous, in order after
/// all the subtrees), each with its gathers, dense Cholesky and solves by ranges in parallel.
///
/// # Errors
/// The index (in the factor's order) of the first non-positive pivot, as the sequential loop
/// would find it: a supernode whose descendants hit one is not factored, and the smallest
/// index found is reported (the branches are disjoint ranges of the factor's order).
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
    let problem = Problem { s, plan, A };
    if let Some(branches) = &plan.branches {
        let run = Branched {
            problem,
            branches,
            threads: par.degree(),
            scratches: std::sync::Mutex::new(Vec::new()),
            failure: AtomicUsize::new(usize::MAX),
        };
        run.nodes(&branches.roots, L_values, 0);
        return match run.failure.into_inner() {
            usize::MAX => Ok(()),
            index => Err(index),
        };
    }
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
                    if let Err(index) = factor_supernode(problem, sn, head, v0, Ls, &mut scratch, Par::Seq) {
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
        factor_supernode(problem, sn, head, 0, Ls, &mut scratch, par)?;
    }
    Ok(())
}

/// The factorisation by branches of the top's tree: the children of a node run concurrently
/// (rayon tasks, the largest first), a top supernode when all of its children are done, with
/// its column gathers, dense Cholesky and solves split into ranges that free threads take.
struct Branched<'a, T> {
    problem: Problem<'a, T>,
    branches: &'a Branches,
    threads: usize,
    /// Workspaces not in use (one per thread at most at a time, but for a thread that
    /// takes another task while it waits inside a parallel loop).
    scratches: std::sync::Mutex<Vec<Scratch<T>>>,
    /// The smallest index (in the factor's order) of a non-positive pivot found.
    failure: AtomicUsize,
}

impl<T: Real> Branched<'_, T> {
    fn scratch(&self) -> Scratch<T> {
        // A poisoned lock (a panic on another thread) still holds valid workspaces.
        let spare = self.scratches.lock().unwrap_or_else(|e| e.into_inner()).pop();
        spare.unwrap_or_else(|| Scratch::new(self.problem.s.nrows(), self.problem.plan.max_columns))
    }

    fn give_back(&self, scratch: Scratch<T>) {
        self.scratches.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
    }

    /// The first supernode of `node`'s branch.
    fn first(&self, node: Node) -> usize {
        match node {
            Node::Task(t) => self.problem.plan.tasks[t].start,
            Node::Top(k) => self.branches.first[k],
        }
    }

    /// Factors the branches `nodes`, which tile `values` (the factor's values from value
    /// `base`), concurrently. Returns whether all of them succeeded.
    fn nodes(&self, nodes: &[Node], values: &mut [T], base: usize) -> bool {
        let col_ptr_val = self.problem.s.col_ptr_for_val();
        // The slices of the nodes, in the order of their supernodes.
        let mut order: Vec<usize> = (0..nodes.len()).collect();
        order.sort_unstable_by_key(|&i| self.first(nodes[i]));
        let mut slices: Vec<Option<(&mut [T], usize)>> = (0..nodes.len()).map(|_| None).collect();
        let values_end = base + values.len();
        let mut rest = values;
        for (k, &i) in order.iter().enumerate() {
            let start = col_ptr_val[self.first(nodes[i])];
            let end = order
                .get(k + 1)
                .map_or(values_end, |&next| col_ptr_val[self.first(nodes[next])]);
            let (slice, tail) = std::mem::take(&mut rest).split_at_mut(end - start);
            rest = tail;
            slices[i] = Some((slice, start));
        }
        let ok = std::sync::atomic::AtomicBool::new(true);
        if nodes.len() == 1 {
            let (slice, start) = slices[0].take().expect("a slice per node");
            return self.node(nodes[0], slice, start);
        }
        rayon::scope_fifo(|scope| {
            // The largest first: `nodes` are in that order.
            for (i, &node) in nodes.iter().enumerate() {
                let (slice, start) = slices[i].take().expect("a slice per node");
                let ok = &ok;
                scope.spawn_fifo(move |_| {
                    if !self.node(node, slice, start) {
                        ok.store(false, Ordering::Relaxed);
                    }
                });
            }
        });
        ok.into_inner()
    }

    /// Factors the branch of `node`: its values `values` from value `base`.
    fn node(&self, node: Node, values: &mut [T], base: usize) -> bool {
        let col_ptr_val = self.problem.s.col_ptr_for_val();
        let (supernodes, threads) = match node {
            Node::Task(t) => (self.problem.plan.tasks[t].clone(), 1),
            Node::Top(k) => {
                let sn = self.problem.plan.top[k];
                let (head, _) = values.split_at_mut(col_ptr_val[sn] - base);
                if !self.nodes(&self.branches.children[k], head, base) {
                    return false;
                }
                (sn..sn + 1, self.threads)
            }
        };
        let par = if threads < 2 { Par::Seq } else { Par::rayon(threads) };
        let mut scratch = self.scratch();
        let mut ok = true;
        for sn in supernodes {
            let (head, tail) = values.split_at_mut(col_ptr_val[sn] - base);
            let Ls = &mut tail[..col_ptr_val[sn + 1] - col_ptr_val[sn]];
            if let Err(index) = factor_supernode(self.problem, sn, head, base, Ls, &mut scratch, par) {
                self.failure.fetch_min(index, Ordering::Relaxed);
                ok = false;
                break;
            }
        }
        self.give_back(scratch);
        ok
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    /// A symmetric positive definite `n x n` matrix: a diagonally dominant one with
    /// deterministic off-diagonal values in [-1, 1].
    fn spd(n: usize) -> Mat<f64> {
        let off = |i: usize, j: usize| (((i * 7919 + j * 104_729) % 2001) as f64 - 1000.0) / 1000.0;
        Mat::from_fn(n, n, |i, j| match i.cmp(&j) {
            std::cmp::Ordering::Equal => n as f64,
            std::cmp::Ordering::Greater => off(i, j),
            std::cmp::Ordering::Less => off(j, i),
        })
    }

    /// [`dense_cholesky`] in `T` on 2 threads (blocked, parallel) against faer's sequential
    /// Cholesky: the largest difference of the lower triangles relative to the largest entry.
    fn blocked_against_faer<T: Real>(A: &Mat<f64>, cast: impl Fn(f64) -> T, back: impl Fn(T) -> f64) -> f64 {
        let n = A.nrows();
        let mut ours = Mat::<T>::from_fn(n, n, |i, j| cast(A[(i, j)]));
        let mut faer = ours.clone();
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<T>(n, Par::Seq, Default::default()));
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        pool.install(|| dense_cholesky(ours.as_mut(), 2, MemStack::new(&mut mem)))
            .unwrap();
        cholesky_in_place(
            faer.as_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .unwrap();
        let (mut difference, mut largest) = (0.0f64, 0.0f64);
        for j in 0..n {
            for i in j..n {
                difference = difference.max((back(ours[(i, j)]) - back(faer[(i, j)])).abs());
                largest = largest.max(back(faer[(i, j)]).abs());
            }
        }
        difference / largest
    }

    /// The blocked parallel dense Cholesky equals faer's sequential one to round-off, in
    /// double and single precision, on a size that is not a multiple of the block.
    #[test]
    fn blocked_dense_cholesky_matches_faer() {
        let n = 3 * DENSE_BLOCK + 77;
        assert!(n >= PARALLEL_DENSE_MIN_COLUMNS, "{n} columns take the blocked path");
        let A = spd(n);
        // Round-off: the same products summed in another order; the matrix is well
        // conditioned (diagonally dominant), so the factors differ by a small multiple of
        // eps * sqrt(n) relative to their largest entry: 1e-13 is ~500 eps64, 1e-5 ~80 eps32.
        let double = blocked_against_faer::<f64>(&A, |v| v, |v| v);
        assert!(double < 1e-13, "f64: relative difference {double:.2e}");
        let single = blocked_against_faer::<f32>(&A, |v| v as f32, f64::from);
        assert!(single < 1e-5, "f32: relative difference {single:.2e}");
    }

    /// A non-positive pivot in a later block of the blocked dense Cholesky is reported at
    /// its index in the whole block.
    #[test]
    fn blocked_dense_cholesky_reports_the_non_positive_pivot() {
        let n = 3 * DENSE_BLOCK + 77;
        let bad = 2 * DENSE_BLOCK + 5;
        let mut A = spd(n);
        A[(bad, bad)] = -1.0;
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(n, Par::Seq, Default::default()));
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let result = pool.install(|| dense_cholesky(A.as_mut(), 2, MemStack::new(&mut mem)));
        assert_eq!(result, Err(bad));
    }
}
