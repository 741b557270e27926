//! Invariant matrices kept by their nonzero entries.
//!
//! The second-order inertia invariants $\bar{\mathbf S}_{ab}$ ([`crate::mass`]) and the reduced
//! geometric stiffnesses $\mathbf G_k$ ([`crate::GeometricStiffness`]) are $n\times n$, but for
//! many bodies most of their entries vanish. A straight beam along a body axis is the common
//! case: a CB coordinate moves the beam's axis along one body axis only (the axial constraint
//! modes along the beam, the bending ones across it, the torsional ones not at all), so
//! $\bar{\mathbf S}_{ab} = \int\rho\,\mathbf S_a^T\mathbf S_b$ couples only the coordinates that move
//! the axis along $a$ with those along $b$; and only the coordinates that stretch the beam carry
//! an axial force, so every other $\mathbf G_k$ is zero (on the C2 rod segment, 2 of the 14). A
//! [`Compressed`] matrix stores the nonzero entries column by column, so the products of an
//! evaluation cost what is there instead of $n^2$.
//!
//! **Round-off zeros.** The reduction computes these matrices from solves and products, so the
//! entries that vanish in exact arithmetic come out as round-off. Entries are compared by what
//! they contribute at a typical deformation: with the coordinate weights $c_i$ of
//! [`coordinate_weights`] (the size of a coordinate that displaces the body by one length unit:
//! 1 for $\mathbf u_k$, $1/\ell$ for $\boldsymbol\theta_k$ with $\ell$ the radius of gyration,
//! $\sqrt{m/m_{ii}}$ for $\eta_i$), the entry $(\bar{\mathbf S}_{ab})_{ij}$ counts as
//! $c_ic_j|(\bar{\mathbf S}_{ab})_{ij}|$ and $(\mathbf G_k)_{ij}$ as $c_ic_jc_k|(\mathbf G_k)_{ij}|$,
//! which makes the comparison independent of the units of the coordinates. [`clean`] sets the
//! entries below [`ROUND_OFF`] times the group's largest (the nine $\bar{\mathbf S}_{ab}$, or all
//! $\mathbf G_k$) to zero once, when the superelement is built, for the dense and the compressed
//! form alike. `tests/unit/compressed.rs` measures the gap on straight beams along an axis and
//! skew (2 to 10 modes): what is dropped is round-off, what is kept is a real coupling.

#![allow(non_snake_case)]

use faer::{Mat, MatRef};

/// Weighted entries below this fraction of the group's largest are round-off zeros of the
/// reduction (module docs): two orders of magnitude above the largest round-off and three below
/// the smallest real entry measured by `tests/unit/compressed.rs`.
pub const ROUND_OFF: f64 = 1e-9;

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
    /// row of $\mathbf A$ is $s$ times a column, and [`Self::scatter_add_at`] writes whole columns
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

    /// The full matrix again.
    pub fn to_dense(&self) -> Mat<f64> {
        let mut A = Mat::zeros(self.n, self.n);
        self.scatter_add(1.0, &mut A);
        A
    }

    /// `out[t] = A x[t]` for `K` vectors at once (one pass over the entries).
    #[inline]
    pub fn mul_into<const K: usize>(&self, x: [&[f64]; K], mut out: [&mut [f64]; K]) {
        for o in out.iter_mut() {
            o.fill(0.0);
        }
        for (r, &i) in self.rows.iter().enumerate() {
            let range = self.start[r]..self.start[r + 1];
            let mut acc = [0.0; K];
            for (&j, a) in self.cols[range.clone()].iter().zip(&self.values[range]) {
                for t in 0..K {
                    acc[t] += a * x[t][j];
                }
            }
            for t in 0..K {
                out[t][i] = acc[t];
            }
        }
    }

    /// `out += alpha * A` for an $n\times n$ `out`.
    #[inline]
    pub fn scatter_add(&self, alpha: f64, out: &mut Mat<f64>) {
        self.scatter_add_at(alpha, out, 0, 0);
    }

    /// `out[r0 + i, c0 + j] += alpha * A[i, j]`: `A` added into the block of `out` at (`r0`, `c0`).
    #[inline]
    pub fn scatter_add_at(&self, alpha: f64, out: &mut Mat<f64>, r0: usize, c0: usize) {
        if alpha == 0.0 {
            return;
        }
        if let Some(sign) = self.transpose_sign {
            // Row i of A is sign times column i: add it into column c0 + i.
            let alpha = sign * alpha;
            for (r, &i) in self.rows.iter().enumerate() {
                let o = &mut out.col_as_slice_mut(c0 + i)[r0..];
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
                out[(r0 + i, c0 + j)] += alpha * a;
            }
        }
    }
}
