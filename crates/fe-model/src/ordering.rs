//! Fill-reducing orderings for the sparse Cholesky factorisations of the project
//! (statics here, the Craig-Bampton and modal factorisations of `reduction`).
//!
//! faer's symbolic Cholesky orders by approximate minimum degree (AMD) unless given a
//! permutation ([`SymmetricOrdering::Custom`]). On 3D solid meshes AMD's factor grows much
//! faster than nested dissection's: a clamped hex8 block of 197k dofs gives 594 M factor
//! values with AMD (`BENCHMARKS.md`). Nested dissection (George 1973, "Nested dissection of a
//! regular finite element mesh", SIAM J. Numer. Anal. 10) orders a vertex separator after
//! the two parts it separates, recursively, so the fill of an $n$-dof 3D mesh is
//! $O(n^{4/3})$ and the work $O(n^2)$, the optimum for such meshes (Lipton, Rose & Tarjan
//! 1979, SIAM J. Numer. Anal. 16).
//!
//! # Method ([`nested_dissection`])
//!
//! 1. The graph: vertices are the mesh points (every dof at the same point belongs to one
//!    vertex: a node's three or six dofs), edges the off-diagonal pattern of $\mathbf A$ (both
//!    triangles read, so a lower-triangle-only matrix works too). Dofs that share a point always
//!    have identical graph neighbourhoods in an FE matrix, so nothing is lost by compressing;
//!    any grouping gives a *valid* ordering (a separator of the quotient graph is one of the
//!    dof graph), only quality depends on it.
//! 2. Recursive coordinate bisection: cut the vertex set at the median of its coordinate along
//!    each axis on which it spreads; the vertex separator of a cut is the smaller of the two
//!    sets of cut-adjacent vertices (on a structured hex mesh, one plane of nodes), and the cut
//!    with the smallest separator is taken (the first, the longest extent, on ties). Cutting
//!    always across the longest extent instead takes the larger plane wherever the elements are
//!    not cubes: on the 2.6 x 1 x 1 block of 48 x 37 x 37 hex8 of `reduction/benches` (204k
//!    dofs) that gave a factor of 356.5 M values and 1156 Gflop, the smallest separator 280 M
//!    and 734 Gflop, as METIS's multilevel `METIS_NodeND` (282 M, 736 Gflop). The two
//!    remaining parts are ordered first, recursively, then the separator.
//! 3. Parts of at most [`ND_LEAF_VERTICES`] vertices are ordered by faer's AMD on their
//!    induced subgraph (as METIS orders its leaves by minimum degree).
//! 4. Every vertex's dofs are numbered consecutively, in their original order.

use crate::dof::DofMap;
use crate::error::FeError;
use crate::model::FeModel;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::{amd, SymbolicSupernodalParams};
use faer::sparse::{SymbolicSparseColMat, SymbolicSparseColMatRef};
use serde::{Deserialize, Serialize};

/// Which fill-reducing ordering a sparse Cholesky factorisation uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum FillOrdering {
    /// Nested dissection when the dof coordinates are known and the matrix has at least
    /// [`ND_MIN_DOFS`] rows, AMD otherwise.
    #[default]
    Auto,
    /// faer's approximate minimum degree.
    Amd,
    /// [`nested_dissection`] on the dof coordinates (AMD if none are given).
    NestedDissection,
}

/// Below this many rows [`FillOrdering::Auto`] keeps AMD: on small or thin models (beams,
/// plates a few elements thick) minimum degree is as good, and its symbolic phase is cheaper.
/// On the hex8 blocks of `reduction/benches/ordering.rs`, nested dissection's factor needs
/// half AMD's flops at 9.4k dofs (1.9 against 3.8 Gflop) and 0.1 against 0.2 Gflop at 2.7k.
pub const ND_MIN_DOFS: usize = 5_000;

/// Supernode relaxation with nested dissection (faer's `SymbolicSupernodalParams::relax`):
/// none, only the fundamental supernodes. Relaxed (amalgamated) supernodes store explicit
/// zeros to make fewer, larger dense blocks; with nested dissection the supernodes of the
/// separators are large already, and on the hex8 blocks of `reduction/benches/craig_bampton.rs`
/// faer's default relaxation gave a factor 5 % larger (279.8 M against 266.0 M values at
/// 203 616 dofs, 39.9 M against 37.5 M at 50 124) for the same 734 Gflop and no faster
/// factorisation, and every Lanczos solve reads the larger factor. Larger relaxation (merging
/// up to 64 or 128 columns) made the factor larger again and the factorisation no faster.
const ND_RELAX: Option<&[(usize, f64)]> = None;

/// Largest part (in vertices, i.e. mesh points) that nested dissection leaves to AMD.
pub const ND_LEAF_VERTICES: usize = 32;

/// Symbolic Cholesky analysis of the pattern `A` (lower triangle read by faer, both or lower
/// stored) with the fill-reducing ordering `ordering`, and the ordering actually used
/// ([`FillOrdering::Amd`] or [`FillOrdering::NestedDissection`]). `points[d]` is the position
/// of dof `d` (its node's coordinates), needed by nested dissection.
///
/// # Errors
/// [`FeError::OrderingPoints`] if `points` does not have one entry per row;
/// [`FeError::LinearAlgebra`] if faer runs out of memory or index range.
pub fn symbolic_cholesky(
    A: SymbolicSparseColMatRef<'_, usize>,
    points: Option<&[[f64; 3]]>,
    ordering: FillOrdering,
) -> Result<(SymbolicCholesky<usize>, FillOrdering), FeError> {
    let n = A.nrows();
    let resolved = match (ordering, points) {
        (FillOrdering::Amd, _) | (_, None) => FillOrdering::Amd,
        (FillOrdering::Auto, Some(_)) if n < ND_MIN_DOFS => FillOrdering::Amd,
        _ => FillOrdering::NestedDissection,
    };
    let faer_error = |e: faer::sparse::FaerError| FeError::LinearAlgebra(format!("symbolic Cholesky: {e:?}"));
    let symbolic = match (resolved, points) {
        (FillOrdering::NestedDissection, Some(points)) => {
            let (fwd, inv) = nested_dissection(A, points)?;
            factorize_symbolic_cholesky(
                A,
                faer::Side::Lower,
                SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n)),
                CholeskySymbolicParams {
                    supernodal_params: SymbolicSupernodalParams { relax: ND_RELAX },
                    ..Default::default()
                },
            )
            .map_err(faer_error)?
        }
        _ => factorize_symbolic_cholesky(
            A,
            faer::Side::Lower,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams::default(),
        )
        .map_err(faer_error)?,
    };
    Ok((symbolic, resolved))
}

/// Floating-point operations of the numeric factorisation of `symbolic`, $\sum_j c_j^2$ with
/// $c_j$ the entries of column $j$ of $\mathbf L$ (George & Liu, "Computer Solution of Large
/// Sparse Positive Definite Systems", 1981, §2.2), counting the explicit zeros a supernodal
/// factor stores: the work the factorisation does.
pub fn factor_flops(symbolic: &SymbolicCholesky<usize>) -> f64 {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => s.col_ptr().windows(2).map(|w| ((w[1] - w[0]) as f64).powi(2)).sum(),
        SymbolicCholeskyRaw::Supernodal(s) => {
            let (begin, end, rows) = (s.supernode_begin(), s.supernode_end(), s.col_ptr_for_row_idx());
            (0..s.n_supernodes())
                .map(|k| {
                    let (c, r) = ((end[k] - begin[k]) as f64, (rows[k + 1] - rows[k]) as f64);
                    // Column i of the supernode holds c - i + r entries, i = 0..c.
                    (0..end[k] - begin[k]).map(|i| (c - i as f64 + r).powi(2)).sum::<f64>()
                })
                .sum()
        }
    }
}

/// The position of every free dof of `dofs`: its node's coordinates (for
/// [`symbolic_cholesky`] and [`nested_dissection`]).
pub fn dof_points(model: &FeModel, dofs: &DofMap) -> Vec<[f64; 3]> {
    (0..dofs.n_free())
        .map(|d| {
            let x = &model.mesh.nodes[dofs.full_slot(crate::dof::Dof(d as u32)) / 6];
            [x.x, x.y, x.z]
        })
        .collect()
}

/// Nested-dissection ordering of the symmetric pattern `A` (module docs): returns
/// `(perm_fwd, perm_inv)`, `perm_fwd[k]` the row of `A` eliminated `k`-th.
///
/// # Errors
/// [`FeError::OrderingPoints`] if `points` does not have one finite entry per row of `A`.
pub fn nested_dissection(
    A: SymbolicSparseColMatRef<'_, usize>,
    points: &[[f64; 3]],
) -> Result<(Vec<usize>, Vec<usize>), FeError> {
    nested_dissection_with_leaves(A, points, ND_LEAF_VERTICES)
}

/// [`nested_dissection`] leaving parts of at most `leaf_vertices` vertices (at least 2) to AMD,
/// for studies of that choice (`reduction/benches/ordering.rs`).
///
/// # Errors
/// Those of [`nested_dissection`].
pub fn nested_dissection_with_leaves(
    A: SymbolicSparseColMatRef<'_, usize>,
    points: &[[f64; 3]],
    leaf_vertices: usize,
) -> Result<(Vec<usize>, Vec<usize>), FeError> {
    let n = A.nrows();
    if points.len() != n || A.ncols() != n {
        return Err(FeError::OrderingPoints {
            n_dofs: n,
            n_points: points.len(),
            why: "one point per dof is needed".into(),
        });
    }
    if let Some(d) = points.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        return Err(FeError::OrderingPoints {
            n_dofs: n,
            n_points: points.len(),
            why: format!("dof {d} has the non-finite position {:?}", points[d]),
        });
    }
    // 1. Vertices: dofs grouped by position (bitwise), in order of first appearance.
    let key = |d: usize| points[d].map(f64::to_bits);
    let mut by_point: Vec<usize> = (0..n).collect();
    by_point.sort_unstable_by_key(|&d| (key(d), d));
    let mut vertex_of = vec![0u32; n];
    let mut vertex_points: Vec<[f64; 3]> = Vec::new();
    let mut vertex_dof_ptr = vec![0usize];
    let mut vertex_dofs: Vec<usize> = Vec::with_capacity(n);
    for (k, &d) in by_point.iter().enumerate() {
        if k > 0 && key(by_point[k - 1]) != key(d) {
            vertex_dof_ptr.push(vertex_dofs.len());
        }
        if k == 0 || key(by_point[k - 1]) != key(d) {
            vertex_points.push(points[d]);
        }
        vertex_of[d] = (vertex_points.len() - 1) as u32;
        vertex_dofs.push(d);
    }
    vertex_dof_ptr.push(vertex_dofs.len());
    let n_vertices = vertex_points.len();
    let graph = QuotientGraph::new(A, &vertex_of, n_vertices);

    // 2-3. Recursive bisection.
    let mut order = Vec::with_capacity(n_vertices);
    let mut state = Dissection {
        graph: &graph,
        points: &vertex_points,
        label: vec![0u8; n_vertices],
        local: vec![u32::MAX; n_vertices],
        leaf_vertices: leaf_vertices.max(2),
    };
    state.dissect((0..n_vertices as u32).collect(), &mut order);

    // 4. Vertices to dofs.
    let mut perm_fwd = Vec::with_capacity(n);
    for &v in &order {
        let v = v as usize;
        perm_fwd.extend_from_slice(&vertex_dofs[vertex_dof_ptr[v]..vertex_dof_ptr[v + 1]]);
    }
    let mut perm_inv = vec![0usize; n];
    for (k, &d) in perm_fwd.iter().enumerate() {
        perm_inv[d] = k;
    }
    Ok((perm_fwd, perm_inv))
}

/// Adjacency of the vertices (compressed rows, no self loops, no duplicates).
struct QuotientGraph {
    ptr: Vec<usize>,
    adj: Vec<u32>,
}

impl QuotientGraph {
    fn new(A: SymbolicSparseColMatRef<'_, usize>, vertex_of: &[u32], n_vertices: usize) -> Self {
        // Edges in both directions, from either stored triangle.
        let mut edges: Vec<(u32, u32)> = Vec::new();
        let mut seen = vec![u32::MAX; n_vertices];
        // Per column vertex: deduplicate its neighbours within the column before pushing.
        for j in 0..A.ncols() {
            let vj = vertex_of[j];
            for &i in A.row_idx_of_col_raw(j) {
                let vi = vertex_of[i];
                if vi != vj && seen[vi as usize] != j as u32 {
                    seen[vi as usize] = j as u32;
                    edges.push((vj, vi));
                    edges.push((vi, vj));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let mut ptr = vec![0usize; n_vertices + 1];
        for &(a, _) in &edges {
            ptr[a as usize + 1] += 1;
        }
        for v in 0..n_vertices {
            ptr[v + 1] += ptr[v];
        }
        let adj = edges.into_iter().map(|(_, b)| b).collect();
        Self { ptr, adj }
    }

    fn neighbours(&self, v: u32) -> &[u32] {
        &self.adj[self.ptr[v as usize]..self.ptr[v as usize + 1]]
    }
}

/// Work arrays of the recursion: `label` marks the side of each vertex of the part being cut,
/// `local` its index within a leaf.
struct Dissection<'a> {
    graph: &'a QuotientGraph,
    points: &'a [[f64; 3]],
    label: Vec<u8>,
    local: Vec<u32>,
    leaf_vertices: usize,
}

/// A bisection of a part: `separator` between `rest` and `other`.
struct Cut {
    rest: Vec<u32>,
    other: Vec<u32>,
    separator: Vec<u32>,
}

const OUTSIDE: u8 = 0;
const SIDE_A: u8 = 1;
const SIDE_B: u8 = 2;

impl Dissection<'_> {
    /// Appends the elimination order of `part` to `order`: both halves, then the separator.
    fn dissect(&mut self, part: Vec<u32>, order: &mut Vec<u32>) {
        if part.len() <= self.leaf_vertices {
            self.leaf(&part, order);
            return;
        }
        // One cut across every axis on which the part spreads, longest extent first; the
        // smallest separator wins, the first on ties.
        let mut best: Option<Cut> = None;
        for axis in self.axes(&part) {
            let Some((a, b)) = self.bisect(&part, axis) else {
                continue;
            };
            let cut = self.separate(&part, a, b);
            if cut.separator.len() < part.len()
                && best
                    .as_ref()
                    .is_none_or(|best| cut.separator.len() < best.separator.len())
            {
                best = Some(cut);
            }
        }
        let Some(Cut { rest, other, separator }) = best else {
            self.leaf(&part, order);
            return;
        };
        self.dissect(rest, order);
        self.dissect(other, order);
        order.extend_from_slice(&separator);
    }

    /// The axes along which the points of `part` spread, longest extent first.
    fn axes(&self, part: &[u32]) -> Vec<usize> {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for &v in part {
            let p = self.points[v as usize];
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let mut axes: Vec<usize> = (0..3).filter(|&k| hi[k] > lo[k]).collect();
        axes.sort_by(|&i, &j| (hi[j] - lo[j]).total_cmp(&(hi[i] - lo[i])));
        axes
    }

    /// The vertex separator of the split `(a, b)` of `part`: the vertices of the side with
    /// fewer cut-adjacent vertices that touch the other side.
    fn separate(&mut self, part: &[u32], a: Vec<u32>, b: Vec<u32>) -> Cut {
        for &v in &a {
            self.label[v as usize] = SIDE_A;
        }
        for &v in &b {
            self.label[v as usize] = SIDE_B;
        }
        let boundary = |this: &Self, side: &[u32], other: u8| -> Vec<bool> {
            side.iter()
                .map(|&v| {
                    this.graph
                        .neighbours(v)
                        .iter()
                        .any(|&w| this.label[w as usize] == other)
                })
                .collect()
        };
        let on_a = boundary(self, &a, SIDE_B);
        let on_b = boundary(self, &b, SIDE_A);
        for &v in part {
            self.label[v as usize] = OUTSIDE;
        }
        let count = |flags: &[bool]| flags.iter().filter(|&&f| f).count();
        let (cut, cut_flags, other) = if count(&on_a) <= count(&on_b) {
            (a, on_a, b)
        } else {
            (b, on_b, a)
        };
        let mut rest = Vec::with_capacity(cut.len());
        let mut separator = Vec::new();
        for (v, on) in cut.into_iter().zip(cut_flags) {
            if on {
                separator.push(v);
            } else {
                rest.push(v);
            }
        }
        Cut { rest, other, separator }
    }

    /// Splits `part` at the median of its coordinate `axis`; `None` if one side would be
    /// empty.
    fn bisect(&self, part: &[u32], axis: usize) -> Option<(Vec<u32>, Vec<u32>)> {
        let mut part = part.to_vec();
        let coord = |v: u32| self.points[v as usize][axis];
        let mid = part.len() / 2;
        let (_, &mut median, _) = part.select_nth_unstable_by(mid, |&u, &v| coord(u).total_cmp(&coord(v)));
        let median = coord(median);
        // Points on the median plane go to the side that keeps the halves closer in size.
        let below = part.iter().filter(|&&v| coord(v) < median).count();
        let at_or_below = part.iter().filter(|&&v| coord(v) <= median).count();
        let half = part.len() / 2;
        let split_below = below.abs_diff(half) <= at_or_below.abs_diff(half) && below > 0;
        let (a, b): (Vec<u32>, Vec<u32>) = if split_below {
            part.into_iter().partition(|&v| coord(v) < median)
        } else {
            part.into_iter().partition(|&v| coord(v) <= median)
        };
        (!a.is_empty() && !b.is_empty()).then_some((a, b))
    }

    /// Orders a small part by AMD on its induced subgraph.
    fn leaf(&mut self, part: &[u32], order: &mut Vec<u32>) {
        let m = part.len();
        if m <= 2 {
            order.extend_from_slice(part);
            return;
        }
        for (k, &v) in part.iter().enumerate() {
            self.local[v as usize] = k as u32;
        }
        let mut col_ptr = Vec::with_capacity(m + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0usize);
        for &v in part {
            let k = self.local[v as usize] as usize;
            row_idx.push(k);
            for &w in self.graph.neighbours(v) {
                let l = self.local[w as usize];
                if l != u32::MAX {
                    row_idx.push(l as usize);
                }
            }
            let start = col_ptr[col_ptr.len() - 1];
            row_idx[start..].sort_unstable();
            col_ptr.push(row_idx.len());
        }
        for &v in part {
            self.local[v as usize] = u32::MAX;
        }
        let nnz = row_idx.len();
        let pattern = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let mut fwd = vec![0usize; m];
        let mut inv = vec![0usize; m];
        let ordered = MemBuffer::try_new(amd::order_scratch::<usize>(m, nnz))
            .ok()
            .and_then(|mut mem| {
                amd::order(
                    &mut fwd,
                    &mut inv,
                    pattern.as_ref(),
                    amd::Control::default(),
                    MemStack::new(&mut mem),
                )
                .ok()
            })
            .is_some();
        if ordered {
            order.extend(fwd.iter().map(|&k| part[k]));
        } else {
            // AMD cannot fail on a valid pattern but for memory: the part's own order is
            // still a valid (if fuller) ordering.
            order.extend_from_slice(part);
        }
    }
}
