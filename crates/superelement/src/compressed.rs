//! The reduced geometric stiffnesses kept by their nonzero entries.
//!
//! A body's $\mathbf G_k$ ([`crate::GeometricStiffness`]) are $n$ matrices of $n\times n$, so the
//! dense products of an evaluation cost $n^3$; but only the CB coordinates that stress the body
//! give a nonzero $\mathbf G_k$. A straight beam is the common case: only the coordinates that
//! stretch it carry an axial force (on the C2 rod segment along $x$, the axial constraint modes
//! of its two ends: 2 of the 14 $\mathbf G_k$; on a skew beam the six end translations), and the
//! nonzero ones couple only the bending and torsion coordinates. A [`Compressed`] matrix stores
//! the nonzero entries row by row, so the products cost what is there.
//!
//! **Round-off zeros.** The reduction computes the $\mathbf G_k$ from solves and products, so the
//! entries that vanish in exact arithmetic come out as round-off. Entries are compared by what
//! they contribute at a typical deformation: with the coordinate weights $c_i$ of
//! [`coordinate_weights`] (the size of a coordinate that displaces the body by one length unit:
//! 1 for $\mathbf u_k$, $1/\ell$ for $\boldsymbol\theta_k$ with $\ell$ the radius of gyration,
//! $\sqrt{m/m_{ii}}$ for $\eta_i$), $(\mathbf G_k)_{ij}$ counts as $c_ic_jc_k|(\mathbf G_k)_{ij}|$,
//! which makes the comparison independent of the units of the coordinates. [`clean`] sets the
//! entries below [`ROUND_OFF`] times the largest to zero, once, when the superelement is built,
//! and only if that leaves the $\mathbf G_k$ sparse enough for the compressed products
//! ([`COMPRESSED_SHARE`]; else they stay as they are). `tests/unit/compressed.rs` measures the
//! gap on straight beams along an axis and skew (2 to 10 modes): what is dropped is round-off,
//! what is kept is a real coupling.
//!
//! [`Compressed::mul_into`] visits the stored entries row by row. Multiplying instead by the
//! dense block of a $\mathbf G_k$'s nonzero rows and columns (its zeros included, contiguous
//! columns, no index per entry, the same sums) was measured slower in the C2 step with modified
//! Newton: 53.1M against 49.9M instructions in the geometric gradient over 1600 steps (2.0k a
//! step more), the block's zeros costing more than the indices saved.
//!
//! The second-order inertia invariants $\bar{\mathbf S}_{ab}$ of a straight beam are sparse too
//! (an eighth of their entries on the C2 rod segment), but their dense products are only
//! $9n^2$ per vector, and compressed products were measured slower than faer's dense ones at
//! $n = 14$ (10.1k against 9.4k instructions for the contractions), and again as one list of
//! entries visited once for all right-hand sides (9.6k against 9.4k per call in the C2 step,
//! and 2.2k more than faer for the $\mathbf q\mathbf q$ blocks): they stay dense.

#![allow(non_snake_case)]

use faer::{Mat, MatRef};

/// Weighted entries below this fraction of the group's largest are round-off zeros of the
/// reduction (module docs): two orders of magnitude above the largest round-off and three below
/// the smallest real entry measured by `tests/unit/compressed.rs`.
pub const ROUND_OFF: f64 = 1e-9;

/// The share of the dense entries up to which the invariants of a body are used in
/// compressed form: a compressed product costs about five instructions a stored entry (index,
/// value, scattered update) against about one an entry for faer's dense kernels plus their
/// fixed cost, so it pays below about a fifth.
pub const COMPRESSED_SHARE: f64 = 0.2;

/// The coordinate weights $c_i$ of a body (module docs): 1 for the interface displacements,
/// $1/\ell$ for the interface rotations ($\ell = \sqrt{\mathrm{tr}\,\mathbf I_c/m}$), $\sqrt{m/m_{ii}}$
/// for the fixed-interface modes ($m_{ii}$ their diagonal of $\mathbf M_{CB}$).
pub fn coordinate_weights(body: &reduction::ReducedBody) -> Vec<f64> {
    let m = body.inertia.mass;
    let I = &body.inertia.inertia_com;
    let ell = ((I[0][0] + I[1][1] + I[2][2]) / m).sqrt();
    let n = body.n_coordinates();
    let mut c = Vec::with_capacity(n);
    for _ in &body.interfaces {
        c.extend([1.0; 3]);
        c.extend([1.0 / ell; 3]);
    }
    for i in c.len()..n {
        c.push((m / body.M_CB.data[i + n * i]).sqrt());
    }
    c
}

/// Sets the entries of `group` whose weighted size `weight(k, i, j) * |A_k[i, j]|` is below
/// [`ROUND_OFF`] times the group's largest to zero; returns the largest weighted size set to
/// zero relative to the largest (0 for none).
pub fn clean(group: &mut [&mut Mat<f64>], weight: impl Fn(usize, usize, usize) -> f64) -> f64 {
    let mut big: f64 = 0.0;
    for (k, A) in group.iter().enumerate() {
        for j in 0..A.ncols() {
            for (i, v) in A.col_as_slice(j).iter().enumerate() {
                big = big.max(weight(k, i, j) * v.abs());
            }
        }
    }
    let limit = ROUND_OFF * big;
    let mut dropped: f64 = 0.0;
    for (k, A) in group.iter_mut().enumerate() {
        for j in 0..A.ncols() {
            for (i, v) in A.col_as_slice_mut(j).iter_mut().enumerate() {
                let w = weight(k, i, j) * v.abs();
                if w < limit {
                    dropped = dropped.max(w / big);
                    *v = 0.0;
                }
            }
        }
    }
    dropped
}

/// An $n\times n$ matrix stored by its nonzero entries, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Compressed {
    /// $n$.
    pub n: usize,
    /// The rows with a nonzero entry, increasing.
    pub rows: Vec<usize>,
    /// Entries of row `rows[r]` are `cols[start[r]..start[r + 1]]`, `values[..]`.
    pub start: Vec<usize>,
    pub cols: Vec<usize>,
    pub values: Vec<f64>,
    /// $s$ with $\mathbf A^T = s\mathbf A$ exactly (1: symmetric, -1: skew), if either: then a
    /// row of $\mathbf A$ is $s$ times a column, and [`Self::scatter_add`] writes whole columns
    /// of a column-major output.
    pub transpose_sign: Option<f64>,
}

impl Compressed {
    /// The nonzero entries of `A` ($n\times n$).
    pub fn new(A: MatRef<'_, f64>) -> Self {
        let mut out = Self {
            n: A.nrows(),
            rows: Vec::new(),
            start: vec![0],
            cols: Vec::new(),
            values: Vec::new(),
            transpose_sign: [1.0, -1.0]
                .into_iter()
                .find(|&sign| (0..A.ncols()).all(|j| (0..A.nrows()).all(|i| A[(j, i)] == sign * A[(i, j)]))),
        };
        for i in 0..A.nrows() {
            let before = out.cols.len();
            for j in 0..A.ncols() {
                let v = A[(i, j)];
                if v != 0.0 {
                    out.cols.push(j);
                    out.values.push(v);
                }
            }
            if out.cols.len() > before {
                out.rows.push(i);
                out.start.push(out.cols.len());
            }
        }
        out
    }

    /// No nonzero entry.
    pub fn is_zero(&self) -> bool {
        self.values.is_empty()
    }

    /// Entries stored.
    pub fn stored(&self) -> usize {
        self.values.len()
    }

    /// `out = A x`.
    #[inline]
    pub fn mul_into(&self, x: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (r, &i) in self.rows.iter().enumerate() {
            let range = self.start[r]..self.start[r + 1];
            out[i] = self.cols[range.clone()]
                .iter()
                .zip(&self.values[range])
                .map(|(&j, a)| a * x[j])
                .sum();
        }
    }

    /// `out += alpha * A` for an $n\times n$ column-major `out`.
    #[inline]
    pub fn scatter_add(&self, alpha: f64, out: &mut Mat<f64>) {
        if alpha == 0.0 {
            return;
        }
        if let Some(sign) = self.transpose_sign {
            // Row i of A is sign times column i: add it into column i.
            let alpha = sign * alpha;
            for (r, &i) in self.rows.iter().enumerate() {
                let o = out.col_as_slice_mut(i);
                let range = self.start[r]..self.start[r + 1];
                for (&j, a) in self.cols[range.clone()].iter().zip(&self.values[range]) {
                    o[j] += alpha * a;
                }
            }
            return;
        }
        for (r, &i) in self.rows.iter().enumerate() {
            let range = self.start[r]..self.start[r + 1];
            for (&j, a) in self.cols[range.clone()].iter().zip(&self.values[range]) {
                out[(i, j)] += alpha * a;
            }
        }
    }
}
