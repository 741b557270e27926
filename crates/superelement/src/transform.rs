//! The velocity transformation: $\boldsymbol\Phi_{rig}$ (5.2), $\mathbf Z_j$ and $\mathbf T_j$
//! (5.4)-(5.5), $\mathbf A$ (5.6), with the exact rotation factor $\boldsymbol\Lambda$, and the
//! derivatives of these maps with respect to the CB coordinates that the tangents need.
//!
//! # Exact variations
//!
//! The CB rotation coordinates are rotation vectors, $\boldsymbol\theta_k = \log(\mathbf R_j^T\mathbf R_k)$,
//! whose variation is $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ times the virtual rotation of (5.1)
//! ([`crate::local_coordinates::elastic_rotation`]). So the exact form of (5.3) is
//! $\delta\mathbf q^{jj} = \boldsymbol\Lambda(\bar{\mathbf R}^T\delta\mathbf q^{OO} - \boldsymbol\Phi_{rig}\delta\boldsymbol\Xi)$,
//! $\delta\boldsymbol\Xi = [\mathbf R_j^T\delta\mathbf r_j;\ \mathbf R_j^T\delta\boldsymbol\pi_j]$, and
//! (4.4) gives, with $\boldsymbol\Psi = \boldsymbol\Lambda\boldsymbol\Phi_{rig}$,
//!
//! $$\mathbf Z_j = (\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}\boldsymbol\Phi_j,\quad
//! \mathbf T_j = \mathbf I - \boldsymbol\Psi\mathbf Z_j,\quad
//! \delta\boldsymbol\Xi = \mathbf Z_j\boldsymbol\Lambda\bar{\mathbf R}^T\delta\mathbf q,\quad
//! \delta\mathbf q^{jj} = \mathbf T_j\boldsymbol\Lambda\bar{\mathbf R}^T\delta\mathbf q.$$
//!
//! For $\boldsymbol\Lambda = \mathbf I$ (undeformed, or small elastic rotations) these are the
//! AIC-FFR paper's (5.4)-(5.5) exactly. Here $\delta\mathbf q = [\delta\mathbf r_1, \delta\boldsymbol\pi_1, \dots,
//! \delta\mathbf r_N, \delta\boldsymbol\pi_N, \delta\boldsymbol\eta]$ are the superelement's
//! coordinates: $\boldsymbol\eta$ is independent, so $\boldsymbol\Phi_j$, $\mathbf Z_j$ and
//! $\mathbf T_j$ carry eta columns and $\bar{\mathbf R}$, $\boldsymbol\Lambda$ an identity eta block.
//!
//! We write $\mathbf X = [\mathbf Z_j;\ \mathbf T_j]$ and $\mathbf P = \mathbf X\boldsymbol\Lambda =
//! [\mathbf Y;\ \mathbf B]$ ($\mathbf Y = \mathbf Z_j\boldsymbol\Lambda$, $\mathbf B = \mathbf T_j\boldsymbol\Lambda$):
//! $\mathbf A = \mathrm{diag}(\mathbf R_j, \mathbf R_j, \mathbf I)\,\mathbf P\,\bar{\mathbf R}^T$ (5.6),
//! and the FFR quasi-velocities are $\boldsymbol\nu = \mathbf P\mathbf y$ with the interface
//! velocities in body axes $\mathbf y = \bar{\mathbf R}^T\dot{\mathbf q}$.
//!
//! # Derivative of $\mathbf P\mathbf y$
//!
//! $\boldsymbol\xi = \mathbf Y\mathbf y$ solves $\boldsymbol\Phi_j\boldsymbol\Lambda(\mathbf y -
//! \boldsymbol\Phi_{rig}\boldsymbol\xi) = 0$ and $\mathbf P\mathbf y = [\boldsymbol\xi;\ \boldsymbol\Lambda\boldsymbol\zeta]$,
//! $\boldsymbol\zeta = \mathbf y - \boldsymbol\Phi_{rig}\boldsymbol\xi$. Differentiating in a direction
//! $\boldsymbol\varepsilon$ of $\mathbf q^{jj}$ at fixed $\mathbf y$:
//! $D(\mathbf P\mathbf y)[\boldsymbol\varepsilon] = \mathbf X\mathbf N_y\boldsymbol\varepsilon$ with the
//! block-diagonal $\mathbf N_y$: $-\tilde{\boldsymbol\xi}_r$ on each $\mathbf u_k$ (from
//! $D\boldsymbol\Phi_{rig}$) and $\mathbf H(\boldsymbol\theta_k, \boldsymbol\zeta_{k,r})$ on each
//! $\boldsymbol\theta_k$ (from $D\boldsymbol\Lambda$, [`crate::so3::left_jacobian_inv_derivative`]).
//! Likewise $D\mathbf X[\boldsymbol\varepsilon]\mathbf w = -\mathbf X\tilde{\mathbf N}_{\mathbf Z\mathbf w}\boldsymbol\varepsilon$
//! with $\tilde{\mathbf N}_s$: $\tilde{\mathbf s}_r$ on $\mathbf u_k$, $\mathbf H(\boldsymbol\theta_k, \mathbf s_r)$ on
//! $\boldsymbol\theta_k$. Checked by `tests/unit/fd_tangent.rs` (every tangent is built from these).

#![allow(non_snake_case)]

use crate::error::SuperelementError;
use crate::local_coordinates::{theta_of, u_of};
use crate::so3::{self, skew};
use crate::state::Frame;
use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::{Matrix3, Matrix6, UnitQuaternion, Vector3};

/// $\boldsymbol\Phi_{rig}$ (5.2): the $n\times6$ rigid-body modes of the interface set about the
/// frame origin, on the *deformed* local positions $\mathbf r_k^{jj} = \mathbf x_k + \mathbf u_k$:
/// block rows $[\mathbf I,\ -\tilde{\mathbf r}_k^{jj}]$ (translation) and $[\mathbf 0,\ \mathbf I]$
/// (rotation) per interface, zero rows for $\boldsymbol\eta$.
pub fn phi_rig(r_loc: &[Vector3<f64>], n_modes: usize) -> Mat<f64> {
    let P = reduction::rigid_modes(r_loc, &Vector3::zeros(), n_modes);
    Mat::from_fn(P.nrows(), 6, |i, j| P[(i, j)])
}

/// $\boldsymbol\Phi_j\boldsymbol\Lambda\boldsymbol\Phi_{rig}$ (the 6x6 of (5.4), with the exact
/// rotation factor $\boldsymbol\Lambda$; module docs), from the deformed local
/// positions `r_loc` $= \mathbf x_k + \mathbf u_k$ and the blocks of $\boldsymbol\Lambda$.
#[inline]
pub(crate) fn phi_j_psi(Phi_j: faer::MatRef<'_, f64>, r_loc: &[Vector3<f64>], Lambda: &[Matrix3<f64>]) -> Matrix6<f64> {
    // Columns of G as arrays and of Phi_j as fixed-length slices: plain loops the compiler
    // unrolls and vectorises (the same sums in the same order as with nalgebra's vectors).
    let mut G = [[0.0f64; 6]; 6];
    let column = |c| -> &[f64; 6] { col(Phi_j, c)[..6].try_into().expect("6 rows") };
    for (k, (r, L)) in r_loc.iter().zip(Lambda).enumerate() {
        // Block rows of Psi for interface k: u_k -> [I, -r~], theta_k -> [0, Lambda_k].
        let mr = -skew(r);
        for c in 0..3 {
            let (pu, pt) = (column(6 * k + c), column(6 * k + 3 + c));
            for i in 0..6 {
                G[c][i] += pu[i];
            }
            for b in 0..3 {
                let (m, l) = (mr[(c, b)], L[(c, b)]);
                for i in 0..6 {
                    G[3 + b][i] += pu[i] * m + pt[i] * l;
                }
            }
        }
    }
    Matrix6::from_fn(|i, j| G[j][i])
}

/// Inverse of a 6x6 with its reciprocal condition number in the 1-norm,
/// $1/(\|\mathbf G\|_1\|\mathbf G^{-1}\|_1)$; `None` when it is singular. By $3\times3$ blocks
/// ([`block_inverse`]) where its leading block is well conditioned, else by nalgebra's LU.
pub(crate) fn inverse_with_rcond(G: &Matrix6<f64>) -> Option<(Matrix6<f64>, f64)> {
    let Gi = block_inverse(G).or_else(|| G.try_inverse())?;
    let norm1 = |A: &Matrix6<f64>| (0..6).map(|j| A.column(j).abs().sum()).fold(0.0, f64::max);
    Some((Gi, 1.0 / (norm1(G) * norm1(&Gi))))
}

/// $\mathbf G^{-1}$ by its $3\times3$ blocks $\mathbf G = [\mathbf A,\ \mathbf B;\ \mathbf C,\ \mathbf D]$: with the
/// Schur complement $\mathbf S = \mathbf D - \mathbf C\mathbf A^{-1}\mathbf B$,
/// $\mathbf G^{-1} = [\mathbf A^{-1} + \mathbf A^{-1}\mathbf B\mathbf S^{-1}\mathbf C\mathbf A^{-1},\
/// -\mathbf A^{-1}\mathbf B\mathbf S^{-1};\ -\mathbf S^{-1}\mathbf C\mathbf A^{-1},\ \mathbf S^{-1}]$, two
/// closed-form $3\times3$ inverses and six $3\times3$ products (a quarter of the LU inverse's
/// instructions). For $\boldsymbol\Phi_j\boldsymbol\Psi$ the leading block is
/// $\sum_k\boldsymbol\Phi_j^{t,u_k}$, independent of the deformation and the identity (to round-off)
/// for the frames of this crate, so no pivoting is needed; `None` (the caller's LU instead) when
/// $\mathbf A$ is singular or its 1-norm condition number exceeds $10^4$ (where skipping the row
/// interchanges could cost digits), or $\mathbf S$ is singular.
fn block_inverse(G: &Matrix6<f64>) -> Option<Matrix6<f64>> {
    let A: Matrix3<f64> = G.fixed_view::<3, 3>(0, 0).into_owned();
    let B: Matrix3<f64> = G.fixed_view::<3, 3>(0, 3).into_owned();
    let C: Matrix3<f64> = G.fixed_view::<3, 3>(3, 0).into_owned();
    let D: Matrix3<f64> = G.fixed_view::<3, 3>(3, 3).into_owned();
    let Ai = A.try_inverse()?;
    let norm1 = |M: &Matrix3<f64>| (0..3).map(|j| M.column(j).abs().sum()).fold(0.0, f64::max);
    if !(norm1(&A) * norm1(&Ai) <= 1e4) {
        return None;
    }
    let AiB = Ai * B;
    let CAi = C * Ai;
    let Si = (D - C * AiB).try_inverse()?;
    let top_right = -(AiB * Si);
    let bottom_left = -(Si * CAi);
    let top_left = Ai - top_right * CAi;
    let mut Gi = Matrix6::zeros();
    Gi.fixed_view_mut::<3, 3>(0, 0).copy_from(&top_left);
    Gi.fixed_view_mut::<3, 3>(0, 3).copy_from(&top_right);
    Gi.fixed_view_mut::<3, 3>(3, 0).copy_from(&bottom_left);
    Gi.fixed_view_mut::<3, 3>(3, 3).copy_from(&Si);
    Some(Gi)
}

/// Below this reciprocal condition number $\boldsymbol\Phi_j\boldsymbol\Phi_{rig}$ is treated as
/// singular: about $10^4$ times machine precision, where a solve loses all but four digits.
pub(crate) const RCOND_MIN: f64 = 1e-12;

/// Everything about one configuration that does not depend on velocities: the frame, the CB
/// coordinates and the transformation matrices in body axes (module docs).
#[derive(Clone, Debug)]
pub struct Kinematics {
    /// The frame solving (4.4).
    pub frame: Frame,
    /// Newton iterations the frame took (0 for explicit frames).
    pub frame_iterations: usize,
    /// $\mathbf R_j$ as a matrix.
    pub R_j: Matrix3<f64>,
    /// $\mathbf q^{jj}$ (4.3).
    pub q_jj: Vec<f64>,
    /// Deformed local interface positions $\mathbf r_k^{jj} = \mathbf x_k + \mathbf u_k$.
    pub r_loc: Vec<Vector3<f64>>,
    /// Blocks $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ of $\boldsymbol\Lambda$.
    pub Lambda: Vec<Matrix3<f64>>,
    /// $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$.
    pub G_inv: Matrix6<f64>,
    /// $\mathbf X = [\mathbf Z_j;\ \mathbf T_j]$, $(6+n)\times n$. Its $\mathbf T_j$ rows are
    /// formed only by the updates for tangents ([`Self::update`]; [`Self::T`]).
    pub(crate) X: Mat<f64>,
    /// $\mathbf P = \mathbf X\boldsymbol\Lambda = [\mathbf Y;\ \mathbf B]$, $(6+n)\times n$; its
    /// $\mathbf B$ rows as those of $\mathbf X$.
    pub(crate) P: Mat<f64>,
    /// Explicit copies for faer's products, filled by [`Self::update`] with the fields above
    /// (faer's small kernels are fastest on contiguous column-major operands): $\mathbf Z_j^T$
    /// ($n\times6$), the transpose of the interface rows of $\boldsymbol\Psi =
    /// \boldsymbol\Lambda\boldsymbol\Phi_{rig}$ ($6\times6N$; its eta rows are zero; products with
    /// $\boldsymbol\Psi$ itself go by 3x3 blocks, [`psi_product`]) and $\mathbf Y_r^T$ ($n\times3$,
    /// with tangents only).
    pub(crate) ZT: Mat<f64>,
    pub(crate) YrT: Mat<f64>,
    pub(crate) PsiT: Mat<f64>,
    /// What is formed for the configuration `frame`, `q_formed`.
    formed: Formed,
    /// A planar body's $\mathbf x_k$ and $\boldsymbol\Phi_j$, with which [`Self::complete`] forms
    /// the matrices a planar evaluation leaves out ([`Formed::Planar`]).
    source: Option<std::sync::Arc<PlanarSource>>,
    /// $\mathbf q^{jj}$ of the formed configuration (`q_jj` is overwritten by the frame solve
    /// before [`Self::update`]).
    q_formed: Vec<f64>,
}

/// A planar body's $\mathbf x_k$ and $\boldsymbol\Phi_j$ (`Kinematics::source`).
type PlanarSource = (Vec<Vector3<f64>>, Mat<f64>);

/// How much of a configuration [`Kinematics::update`] has formed: the forces need
/// $\mathbf Z_j$, $\mathbf Y$ and $\boldsymbol\Psi$ only; $\mathbf T_j$, $\mathbf B$ and
/// $\mathbf Y_r^T$ serve the tangents and the public accessors.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Formed {
    Nothing,
    Forces,
    All,
    /// A planar evaluation set the frame, $\mathbf R_j$, $\mathbf q^{jj}$, $\mathbf r_k^{jj}$ and
    /// $\boldsymbol\Lambda$ only.
    Planar,
}

/// A block-diagonal operator on $\mathbf q^{jj}$: a $3\times3$ block on each $\mathbf u_k$ and on
/// each $\boldsymbol\theta_k$, zero on $\boldsymbol\eta$.
#[derive(Clone, Debug)]
pub(crate) struct Blocks {
    pub t: Vec<Matrix3<f64>>,
    pub r: Vec<Matrix3<f64>>,
}

impl Blocks {
    pub fn zeros(N: usize) -> Self {
        Self {
            t: vec![Matrix3::zeros(); N],
            r: vec![Matrix3::zeros(); N],
        }
    }
}

/// The block kernels below compiled for the vector instructions of the machine (AVX2 where
/// there is AVX2, through `pulp`'s runtime dispatch; the release target is baseline x86-64
/// with two-wide SSE2): their column loops autovectorise four-wide there. No fused
/// multiply-adds are formed (Rust does not contract `a * b + c`), so the results are the same
/// to the bit as those of the baseline code. Each kernel is a [`pulp::WithSimd`] whose body
/// is inlined into the dispatched function (a closure would not be).
macro_rules! vectorized_kernel {
    ($(#[$doc:meta])* $name:ident<$($lt:lifetime),*> { $($arg:ident: $ty:ty),* $(,)? } => $body:ident) => {
        $(#[$doc])*
        struct $name<$($lt),*> {
            $($arg: $ty),*
        }
        impl pulp::WithSimd for $name<'_, '_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                let Self { $($arg),* } = self;
                $body($($arg),*)
            }
        }
    };
}

vectorized_kernel!(
    /// [`add_mul_blocks_at`].
    AddMulBlocksAt<'a, 'b> { A: MatRef<'a, f64>, blocks: &'a Blocks, out: &'b mut Mat<f64>, c0: usize } => add_mul_blocks_at_body
);
vectorized_kernel!(
    /// [`add_mul_w`].
    AddMulW<'a, 'b> { A: MatRef<'a, f64>, x: &'a [f64], blocks: usize, alpha: f64, out: &'b mut Mat<f64>, c0: usize } => add_mul_w_body
);
vectorized_kernel!(
    /// [`rotate_matrix`].
    RotateMatrix<'a, 'b> { R: &'a Matrix3<f64>, N: usize, K: &'a Mat<f64>, out: &'b mut Mat<f64> } => rotate_matrix_body
);

/// Column `j` of a column-major matrix as a slice.
#[inline]
pub(crate) fn col(A: MatRef<'_, f64>, j: usize) -> &[f64] {
    A.col(j).try_as_col_major().expect("column-major matrix").as_slice()
}

/// `out (+)= A * blocks` for `A` with $n$ columns (eta columns of the product are zero;
/// with `Accum::Add` they are left as they are).
pub(crate) fn mul_blocks(A: MatRef<'_, f64>, blocks: &Blocks, out: &mut Mat<f64>, accum: Accum) {
    if accum == Accum::Replace {
        out.fill(0.0);
    }
    add_mul_blocks_at(A, blocks, out, 0);
}

/// `out[:, c0..c0+n]` += `A * blocks` (as [`mul_blocks`], into the columns from `c0` of a
/// wider matrix).
pub(crate) fn add_mul_blocks_at(A: MatRef<'_, f64>, blocks: &Blocks, out: &mut Mat<f64>, c0: usize) {
    pulp::Arch::new().dispatch(AddMulBlocksAt { A, blocks, out, c0 });
}

#[inline(always)]
fn add_mul_blocks_at_body(A: MatRef<'_, f64>, blocks: &Blocks, out: &mut Mat<f64>, c0: usize) {
    let N = blocks.t.len();
    let r = A.nrows();
    for k in 0..N {
        for (off, B) in [(6 * k, &blocks.t[k]), (6 * k + 3, &blocks.r[k])] {
            // Slices of exactly r entries: no bounds checks in the loop below.
            let (a0, a1, a2) = (&col(A, off)[..r], &col(A, off + 1)[..r], &col(A, off + 2)[..r]);
            for j in 0..3 {
                let (b0, b1, b2) = (B[(0, j)], B[(1, j)], B[(2, j)]);
                let o = &mut out.col_as_slice_mut(c0 + off + j)[..r];
                for i in 0..r {
                    o[i] += a0[i] * b0 + a1[i] * b1 + a2[i] * b2;
                }
            }
        }
    }
}

/// `dst = src` for column-major matrices of the same shape (plain slice copies: faer's generic
/// `copy_from` is several times slower at these sizes).
#[inline]
pub(crate) fn copy_mat(dst: &mut Mat<f64>, src: MatRef<'_, f64>) {
    for j in 0..src.ncols() {
        dst.col_as_slice_mut(j).copy_from_slice(col(src, j));
    }
}

/// `out (+)= alpha * A B` (faer's sequential product: all our matrices are small, and its
/// small-matrix kernels beat hand-written column updates here; measured with
/// `benches/evaluate.rs`).
#[inline]
pub(crate) fn gemm(out: &mut Mat<f64>, A: MatRef<'_, f64>, B: MatRef<'_, f64>, alpha: f64, accum: Accum) {
    matmul(out.as_mut(), accum, A, B, alpha, Par::Seq);
}

/// Rows per strip of [`PackedTall`].
const STRIP: usize = 8;
/// Most columns of a [`PackedTall`] (the right-hand sides live in a stack array).
pub(crate) const PACKED_MAX_K: usize = 32;

/// A tall matrix $\mathbf A$ ($m\times k$, $k \le$ [`PACKED_MAX_K`]) packed for products with
/// at most 3 columns ([`Self::mul`]): strips of 8 rows, each stored column after column (8
/// entries per column), the last strip padded with zero rows. For the inertia contractions
/// of small bodies ([`crate::mass`]): faer's product of such tall, thin operands goes through
/// its general gemm driver, whose fixed cost is about that of the multiply-adds at $n = 14$.
#[derive(Clone, Debug)]
pub(crate) struct PackedTall {
    m: usize,
    k: usize,
    data: Vec<f64>,
}

impl PackedTall {
    /// Packs the $m\times k$ matrix with entries `a(i, j)`.
    pub(crate) fn new(m: usize, k: usize, a: impl Fn(usize, usize) -> f64) -> Self {
        assert!(k <= PACKED_MAX_K, "PackedTall: {k} columns, at most {PACKED_MAX_K}");
        let strips = m.div_ceil(STRIP);
        let mut data = vec![0.0; strips * k * STRIP];
        for (e, x) in data.iter_mut().enumerate() {
            let (s, j, i) = (e / (k * STRIP), (e / STRIP) % k, e % STRIP);
            let r = s * STRIP + i;
            if r < m {
                *x = a(r, j);
            }
        }
        Self { m, k, data }
    }

    /// `out[c]` $= \mathbf A\,$`b[c]` for $c < C \le 3$. Each strip's $8C$ sums stay in
    /// registers over the whole $k$ loop, compiled for the machine's vector instructions like
    /// the block kernels (`vectorized_kernel`). Every entry is the sum in the order of $k$
    /// of fused multiply-adds (`f64::mul_add`, one rounding each: the same result on every
    /// machine, in hardware where there is FMA).
    pub(crate) fn mul<const C: usize>(&self, b: [&[f64]; C], out: [&mut [f64]; C]) {
        struct Mul<'a, 'b, const C: usize> {
            a: &'a PackedTall,
            b: [&'a [f64]; C],
            out: [&'b mut [f64]; C],
        }
        impl<const C: usize> pulp::WithSimd for Mul<'_, '_, C> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                self.a.mul_body(self.b, self.out)
            }
        }
        pulp::Arch::new().dispatch(Mul { a: self, b, out });
    }

    #[inline(always)]
    fn mul_body<const C: usize>(&self, b: [&[f64]; C], out: [&mut [f64]; C]) {
        let (m, k) = (self.m, self.k);
        assert!(b.iter().all(|x| x.len() == k) && out.iter().all(|x| x.len() == m));
        // The right-hand sides by rows, so that the k loop zips without bounds checks.
        let mut bt = [[0.0; C]; PACKED_MAX_K];
        for (j, row) in bt[..k].iter_mut().enumerate() {
            for c in 0..C {
                row[c] = b[c][j];
            }
        }
        if k == 0 {
            for o in out {
                o.fill(0.0);
            }
            return;
        }
        for (s, strip) in self.data.chunks_exact(k * STRIP).enumerate() {
            let mut acc = [[0.0f64; STRIP]; C];
            for (col, bj) in strip.chunks_exact(STRIP).zip(&bt[..k]) {
                for c in 0..C {
                    for (x, a) in acc[c].iter_mut().zip(col) {
                        *x = a.mul_add(bj[c], *x);
                    }
                }
            }
            let r = s * STRIP;
            if r + STRIP <= m {
                // A fixed length: vector stores, not a call to memcpy.
                for c in 0..C {
                    let o: &mut [f64; STRIP] = (&mut out[c][r..r + STRIP]).try_into().expect("a strip");
                    *o = acc[c];
                }
            } else {
                for c in 0..C {
                    out[c][r..].copy_from_slice(&acc[c][..m - r]);
                }
            }
        }
    }
}

impl Kinematics {
    /// An empty configuration for a body with `N` interfaces and `n` CB coordinates; filled by
    /// [`Self::update`]. Lets hot loops reuse the buffers.
    pub(crate) fn empty(N: usize, n: usize) -> Self {
        Self {
            frame: Frame::identity(),
            frame_iterations: 0,
            R_j: Matrix3::identity(),
            q_jj: vec![0.0; n],
            r_loc: vec![Vector3::zeros(); N],
            Lambda: vec![Matrix3::identity(); N],
            G_inv: Matrix6::identity(),
            X: Mat::zeros(6 + n, n),
            P: Mat::zeros(6 + n, n),
            ZT: Mat::zeros(n, 6),
            YrT: Mat::zeros(n, 3),
            PsiT: Mat::zeros(6, 6 * N),
            formed: Formed::Nothing,
            q_formed: vec![0.0; n],
            source: None,
        }
    }

    /// Keeps a planar body's $\mathbf x_k$ and $\boldsymbol\Phi_j$ for [`Self::complete`].
    pub(crate) fn set_source(&mut self, x: &[Vector3<f64>], Phi_j: &Mat<f64>) {
        self.source = Some(std::sync::Arc::new((x.to_vec(), Phi_j.clone())));
    }

    /// The configuration of a planar evaluation: frame, $\mathbf R_j$, $\mathbf q^{jj}$ (the
    /// $6N + m$ layout), $\mathbf r_k^{jj}$ and $\boldsymbol\Lambda$ ([`Formed::Planar`]).
    pub(crate) fn set_planar(&mut self, frame: Frame, frame_iterations: usize, q_jj: &[f64], x: &[Vector3<f64>]) {
        if self.formed != Formed::Planar {
            // Z_j and Y are not formed for a planar configuration: NaN until `complete`, never
            // the numbers of another configuration.
            for j in 0..self.q_jj.len() {
                self.X.col_as_slice_mut(j)[..6].fill(f64::NAN);
                self.P.col_as_slice_mut(j)[..6].fill(f64::NAN);
            }
        }
        self.frame = frame;
        self.frame_iterations = frame_iterations;
        self.R_j = frame.R.to_rotation_matrix().into_inner();
        self.q_jj.copy_from_slice(q_jj);
        for k in 0..x.len() {
            self.r_loc[k] = x[k] + u_of(&self.q_jj, k);
            self.Lambda[k] = so3::left_jacobian_inv(&theta_of(&self.q_jj, k));
        }
        self.formed = Formed::Planar;
    }

    /// Builds the transformation for the converged `frame` and the CB coordinates `q_jj`
    /// (5.4)-(5.5) with the exact factor $\boldsymbol\Lambda$ (module docs).
    pub(crate) fn new(
        frame: Frame,
        frame_iterations: usize,
        q_jj: Vec<f64>,
        x: &[Vector3<f64>],
        Phi_j: MatRef<'_, f64>,
    ) -> Result<Self, SuperelementError> {
        let mut kin = Self::empty(x.len(), q_jj.len());
        kin.q_jj = q_jj;
        kin.update(frame, frame_iterations, x, Phi_j, true)?;
        Ok(kin)
    }

    /// The configuration of `frame` and `self.q_jj` (already filled): $\boldsymbol\Lambda$,
    /// $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$, $\mathbf Z_j$, $\mathbf Y$ and $\boldsymbol\Psi$, and with
    /// `complete` also $\mathbf T_j$, $\mathbf B$ and $\mathbf Y_r^T$ (the forces read none of
    /// these three). When `frame` and $\mathbf q^{jj}$ are those of the last update (to the bit:
    /// a second evaluation of the same state, as for tangents after a forces-only test) only
    /// what is missing is formed. Compiled for the machine's vector instructions like the block
    /// kernels (`vectorized_kernel`).
    pub(crate) fn update(
        &mut self,
        frame: Frame,
        frame_iterations: usize,
        x: &[Vector3<f64>],
        Phi_j: MatRef<'_, f64>,
        complete: bool,
    ) -> Result<(), SuperelementError> {
        struct Update<'a, 'b> {
            kin: &'b mut Kinematics,
            frame: Frame,
            x: &'a [Vector3<f64>],
            Phi_j: MatRef<'a, f64>,
            complete: bool,
        }
        impl pulp::WithSimd for Update<'_, '_> {
            type Output = Result<(), SuperelementError>;
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) -> Self::Output {
                self.kin.update_body(self.frame, self.x, self.Phi_j, self.complete)
            }
        }
        self.frame_iterations = frame_iterations;
        pulp::Arch::new().dispatch(Update {
            kin: self,
            frame,
            x,
            Phi_j,
            complete,
        })
    }

    #[inline(always)]
    fn update_body(
        &mut self,
        frame: Frame,
        x: &[Vector3<f64>],
        Phi_j: MatRef<'_, f64>,
        complete: bool,
    ) -> Result<(), SuperelementError> {
        let bits = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits());
        let same = self.formed != Formed::Nothing
            && bits(self.frame.r.as_slice(), frame.r.as_slice())
            && bits(self.frame.R.coords.as_slice(), frame.R.coords.as_slice())
            && bits(&self.q_jj, &self.q_formed);
        if !same {
            self.formed = Formed::Nothing;
            self.form_forces_part(frame, x, Phi_j)?;
            self.q_formed.copy_from_slice(&self.q_jj);
            self.formed = Formed::Forces;
        }
        if complete && self.formed != Formed::All {
            self.form_tangent_part();
            self.formed = Formed::All;
        }
        Ok(())
    }

    /// $\mathbf R_j$, $\mathbf r_k^{jj}$, $\boldsymbol\Lambda$, $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$,
    /// $\boldsymbol\Psi^T$, the $\mathbf Z_j$ rows of $\mathbf X$ and $\mathbf Z_j^T$,
    /// the $\mathbf Y$ rows of $\mathbf P$.
    #[inline(always)]
    fn form_forces_part(
        &mut self,
        frame: Frame,
        x: &[Vector3<f64>],
        Phi_j: MatRef<'_, f64>,
    ) -> Result<(), SuperelementError> {
        let N = x.len();
        let n = self.q_jj.len();
        self.frame = frame;
        self.R_j = frame.R.to_rotation_matrix().into_inner();
        for k in 0..N {
            self.r_loc[k] = x[k] + u_of(&self.q_jj, k);
            self.Lambda[k] = so3::left_jacobian_inv(&theta_of(&self.q_jj, k));
        }
        let G = phi_j_psi(Phi_j, &self.r_loc, &self.Lambda);
        let (G_inv, rcond) = inverse_with_rcond(&G).ok_or(SuperelementError::SingularFrame { rcond: 0.0 })?;
        if rcond < RCOND_MIN {
            return Err(SuperelementError::SingularFrame { rcond });
        }
        self.G_inv = G_inv;
        // Psi^T: column 6k + a (row u_k,a of Psi) is [e_a; (-r~_k) row a], column 6k + 3 + a
        // (row theta_k,a) is [0; Lambda_k row a].
        for k in 0..N {
            let mr = -skew(&self.r_loc[k]);
            for a in 0..3 {
                let c = self.PsiT.col_as_slice_mut(6 * k + a);
                c[..3].fill(0.0);
                c[a] = 1.0;
                for b in 0..3 {
                    c[3 + b] = mr[(a, b)];
                }
                let c = self.PsiT.col_as_slice_mut(6 * k + 3 + a);
                c[..3].fill(0.0);
                for b in 0..3 {
                    c[3 + b] = self.Lambda[k][(a, b)];
                }
            }
        }
        // Z = G^{-1} Phi_j (and its transpose), Y = Z Lambda.
        // By columns of fixed length: z = sum_c G^{-1}[:, c] phi_c, as nalgebra's product sums.
        let gi: [[f64; 6]; 6] = std::array::from_fn(|c| std::array::from_fn(|a| G_inv[(a, c)]));
        let zt = cols_mut::<6>(self.ZT.as_mut()).map(|c| &mut c[..n]);
        for j in 0..n {
            let phi: &[f64; 6] = col(Phi_j, j)[..6].try_into().expect("6 rows");
            let mut z = [0.0; 6];
            for a in 0..6 {
                z[a] = gi[0][a] * phi[0];
            }
            for c in 1..6 {
                for a in 0..6 {
                    z[a] += gi[c][a] * phi[c];
                }
            }
            self.X.col_as_slice_mut(j)[..6].copy_from_slice(&z);
            self.P.col_as_slice_mut(j)[..6].copy_from_slice(&z);
            for a in 0..6 {
                zt[a][j] = z[a];
            }
        }
        lambda_right_rows(&self.Lambda, &mut self.P, 0..6);
        Ok(())
    }

    /// The $\mathbf T_j = \mathbf I - \boldsymbol\Psi\mathbf Z_j$ rows of $\mathbf X$, the
    /// $\mathbf B = \mathbf T_j\boldsymbol\Lambda$ rows of $\mathbf P$ and $\mathbf Y_r^T$, from the
    /// forces part.
    #[inline(always)]
    fn form_tangent_part(&mut self) {
        let N = self.n_interfaces();
        let n = self.n();
        let (r_loc, Lambda) = (&self.r_loc, &self.Lambda);
        for j in 0..n {
            let (z, t) = self.X.col_as_slice_mut(j)[..6 + n].split_at_mut(6);
            let (z0, z1, z2, w0, w1, w2) = (z[0], z[1], z[2], z[3], z[4], z[5]);
            // Exact 6-chunks (u_k, theta_k): -(z_t + z_r x r_k) and -Lambda_k z_r, no bounds
            // checks; the sums as nalgebra's cross and matrix-vector products form them.
            for ((o, r), L) in t[..6 * N].chunks_exact_mut(6).zip(r_loc).zip(Lambda) {
                o[0] = -(z0 + (w1 * r[2] - w2 * r[1]));
                o[1] = -(z1 + (w2 * r[0] - w0 * r[2]));
                o[2] = -(z2 + (w0 * r[1] - w1 * r[0]));
                for a in 0..3 {
                    o[3 + a] = -(L[(a, 0)] * w0 + L[(a, 1)] * w1 + L[(a, 2)] * w2);
                }
            }
            t[6 * N..].fill(0.0);
            t[j] += 1.0;
            self.P.col_as_slice_mut(j)[6..6 + n].copy_from_slice(t);
        }
        lambda_right_rows(&self.Lambda, &mut self.P, 6..6 + n);
        let yrt = cols_mut::<3>(self.YrT.as_mut());
        for j in 0..n {
            let p = self.P.col_as_slice(j);
            for d in 0..3 {
                yrt[d][j] = p[3 + d];
            }
        }
    }

    /// Number of CB coordinates $n$.
    pub fn n(&self) -> usize {
        self.q_jj.len()
    }

    /// Number of interfaces $N$.
    pub fn n_interfaces(&self) -> usize {
        self.r_loc.len()
    }

    /// $\mathbf Z_j$ (5.4), $6\times n$. After a planar evaluation
    /// ([`crate::Superelement::into_planar`]) NaN until [`Self::complete`].
    pub fn Z(&self) -> MatRef<'_, f64> {
        self.X.as_ref().subrows(0, 6)
    }

    /// $\mathbf T_j$ (5.5), $n\times n$: formed by [`crate::Superelement::kinematics`] and by
    /// evaluations with tangents; `None` after a forces-only evaluation (the forces do not read
    /// it), until [`Self::complete`].
    pub fn T(&self) -> Option<MatRef<'_, f64>> {
        self.is_complete().then(|| self.X.as_ref().subrows(6, self.n()))
    }

    /// $\mathbf Y = \mathbf Z_j\boldsymbol\Lambda$: body-axis frame velocity from body-axis interface velocities.
    /// After a planar evaluation NaN until [`Self::complete`], like [`Self::Z`].
    pub fn Y(&self) -> MatRef<'_, f64> {
        self.P.as_ref().subrows(0, 6)
    }

    /// $\mathbf B = \mathbf T_j\boldsymbol\Lambda = \partial\mathbf q^{jj}/\partial(\bar{\mathbf R}^T\mathbf q)$;
    /// `None` where [`Self::T`] is.
    pub fn B(&self) -> Option<MatRef<'_, f64>> {
        self.is_complete().then(|| self.B_rows())
    }

    /// The rows of $\mathbf B$ for the tangents, which always follow a complete update.
    pub(crate) fn B_rows(&self) -> MatRef<'_, f64> {
        debug_assert!(self.is_complete(), "B read after a forces-only update");
        self.P.as_ref().subrows(6, self.n())
    }

    /// Whether $\mathbf T_j$, $\mathbf B$ and $\mathbf Y_r^T$ are formed (not after a
    /// forces-only evaluation, [`crate::Superelement::residual_into`]).
    pub fn is_complete(&self) -> bool {
        self.formed == Formed::All
    }

    /// Forms $\mathbf T_j$, $\mathbf B$ and $\mathbf Y_r^T$ of the configuration held if a
    /// forces-only evaluation left them out (3.6k instructions for 14 coordinates).
    pub fn complete(&mut self) {
        if self.formed == Formed::Planar {
            if let Some(src) = self.source.clone() {
                self.formed = Formed::Nothing;
                let (frame, it) = (self.frame, self.frame_iterations);
                // Singular only where the planar evaluation was too (it succeeded): then the
                // matrices stay unformed (`T`, `B` None).
                let _ = self.update(frame, it, &src.0, src.1.as_ref(), true);
            }
            return;
        }
        if self.formed == Formed::Forces {
            self.form_tangent_part();
            self.formed = Formed::All;
        }
    }

    /// $\boldsymbol\Phi_{rig}$ (5.2) of this configuration.
    pub fn phi_rig(&self) -> Mat<f64> {
        phi_rig(&self.r_loc, self.n() - 6 * self.n_interfaces())
    }

    /// $\bar{\mathbf R}\mathbf x$: each 3-block of the interface part turned from body axes to
    /// inertial axes, the eta part left.
    pub fn to_inertial(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        self.to_inertial_into(x, &mut out);
        out
    }

    /// [`Self::to_inertial`] into `out`.
    pub fn to_inertial_into(&self, x: &[f64], out: &mut [f64]) {
        self.rotate_blocks(&self.R_j, x, out);
    }

    /// $\bar{\mathbf R}^T\mathbf x$: each 3-block of the interface part turned from inertial axes
    /// to body axes, the eta part left.
    pub fn to_body(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        self.to_body_into(x, &mut out);
        out
    }

    /// [`Self::to_body`] into `out`.
    pub fn to_body_into(&self, x: &[f64], out: &mut [f64]) {
        self.rotate_blocks(&self.R_j.transpose(), x, out);
    }

    /// Each 3-block of the interface part of `x` turned by `R` into `out`, the eta part copied.
    fn rotate_blocks(&self, R: &Matrix3<f64>, x: &[f64], out: &mut [f64]) {
        let m = 6 * self.n_interfaces();
        // Exact 3-chunks: no bounds checks in the block rotations.
        for (o, x) in out[..m].chunks_exact_mut(3).zip(x[..m].chunks_exact(3)) {
            let v = R * Vector3::new(x[0], x[1], x[2]);
            o.copy_from_slice(v.as_slice());
        }
        out[m..].copy_from_slice(&x[m..]);
    }

    /// $\mathbf A$ (5.6) in inertial axes: $(6+n)\times n$, rows $[\delta\mathbf r_j;\ \delta\boldsymbol\pi_j;\ \delta\mathbf q^{jj}]$.
    pub fn velocity_transform(&self) -> Mat<f64> {
        let n = self.n();
        let N = self.n_interfaces();
        let mut A = self.P.clone();
        // Right factor Rbar^T: column block b multiplied by R_j^T.
        for b in 0..2 * N {
            for i in 0..6 + n {
                let row = Vector3::new(A[(i, 3 * b)], A[(i, 3 * b + 1)], A[(i, 3 * b + 2)]);
                let v = self.R_j * row; // (row^T R^T)^T = R row
                for c in 0..3 {
                    A[(i, 3 * b + c)] = v[c];
                }
            }
        }
        // Left factor diag(R_j, R_j, I).
        for blk in 0..2 {
            for j in 0..n {
                let col = Vector3::new(A[(3 * blk, j)], A[(3 * blk + 1, j)], A[(3 * blk + 2, j)]);
                let v = self.R_j * col;
                for c in 0..3 {
                    A[(3 * blk + c, j)] = v[c];
                }
            }
        }
        A
    }

    /// $\mathbf N_{\mathbf y}$ (module docs) for body-axis interface velocities `y`, with
    /// $\boldsymbol\xi = \mathbf Y\mathbf y$: $-\tilde{\boldsymbol\xi}_r$ on each $\mathbf u_k$,
    /// $\mathbf H(\boldsymbol\theta_k, \mathbf y_{\theta_k} - \boldsymbol\xi_r)$ on each $\boldsymbol\theta_k$.
    pub(crate) fn fill_n_y(&self, y: &[f64], xi: &[f64], out: &mut Blocks) {
        let Om = Vector3::new(xi[3], xi[4], xi[5]);
        for k in 0..self.n_interfaces() {
            out.t[k] = -skew(&Om);
            let zeta_r = Vector3::new(y[6 * k + 3], y[6 * k + 4], y[6 * k + 5]) - Om;
            out.r[k] = so3::left_jacobian_inv_derivative(&theta_of(&self.q_jj, k), &zeta_r);
        }
    }

    /// $\partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj}$ for a fixed $\mathbf F \in \mathbb R^{6+n}$, added to `out`.
    ///
    /// # Derivation
    /// $\mathbf y^T\,D(\mathbf P^T\mathbf F)[\boldsymbol\varepsilon] = \mathbf F^T\mathbf X\mathbf N_y\boldsymbol\varepsilon
    /// = \boldsymbol\phi^T\mathbf N_y\boldsymbol\varepsilon$ with $\boldsymbol\phi = \mathbf X^T\mathbf F$; the
    /// form is bilinear in $(\mathbf y, \boldsymbol\varepsilon)$ through $\boldsymbol\xi_r = \mathbf Y_r\mathbf y$
    /// and $\boldsymbol\zeta_{k,r} = (\mathbf E^\theta_k - \mathbf Y_r)\mathbf y$:
    /// $\boldsymbol\phi^T\mathbf N_y\boldsymbol\varepsilon = \sum_k \boldsymbol\xi_r^T\tilde{\boldsymbol\phi}_{k,t}\boldsymbol\varepsilon_{u_k} +
    /// \boldsymbol\zeta_{k,r}^T\mathbf K_k\boldsymbol\varepsilon_{\theta_k}$, where
    /// $\mathbf K_k = \partial(\mathbf J_l^{-T}(\boldsymbol\theta_k)\boldsymbol\phi_{k,r})/\partial\boldsymbol\theta_k
    /// = -\mathbf H(-\boldsymbol\theta_k, \boldsymbol\phi_{k,r})$. Hence
    /// $\partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj} = \sum_k \mathbf Y_r^T\tilde{\boldsymbol\phi}_{k,t}\mathbf E^u_k +
    /// (\mathbf E^\theta_k - \mathbf Y_r)^T\mathbf K_k\mathbf E^\theta_k$.
    /// Every force of the residual goes through it, so every test of
    /// `tests/unit/fd_tangent.rs` checks it.
    /// `phi` is scratch of length $n$. Compiled for the machine's vector instructions like the
    /// block kernels (`vectorized_kernel`).
    pub(crate) fn add_d_pt(&self, F: &[f64], phi: &mut [f64], out: &mut Mat<f64>, alpha: f64) {
        struct AddDPt<'a, 'b> {
            kin: &'a Kinematics,
            F: &'a [f64],
            phi: &'b mut [f64],
            out: &'b mut Mat<f64>,
            alpha: f64,
        }
        impl pulp::WithSimd for AddDPt<'_, '_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                self.kin.add_d_pt_body(self.F, self.phi, self.out, self.alpha)
            }
        }
        pulp::Arch::new().dispatch(AddDPt {
            kin: self,
            F,
            phi,
            out,
            alpha,
        })
    }

    #[inline(always)]
    fn add_d_pt_body(&self, F: &[f64], phi: &mut [f64], out: &mut Mat<f64>, alpha: f64) {
        let N = self.n_interfaces();
        self.xt_vec(F, phi);
        let Yr = [
            col(self.YrT.as_ref(), 0),
            col(self.YrT.as_ref(), 1),
            col(self.YrT.as_ref(), 2),
        ];
        for k in 0..N {
            let pt = skew(&Vector3::new(phi[6 * k], phi[6 * k + 1], phi[6 * k + 2]));
            let pr = Vector3::new(phi[6 * k + 3], phi[6 * k + 4], phi[6 * k + 5]);
            let K = -so3::left_jacobian_inv_derivative(&-theta_of(&self.q_jj, k), &pr);
            // Y_r^T (pt) at columns u_k ; -Y_r^T K at columns theta_k ; K at (theta_k, theta_k).
            for (c0, B, sign) in [(6 * k, &pt, alpha), (6 * k + 3, &K, -alpha)] {
                for c in 0..3 {
                    let (b0, b1, b2) = (sign * B[(0, c)], sign * B[(1, c)], sign * B[(2, c)]);
                    let o = out.col_as_slice_mut(c0 + c);
                    for (((o, x), y), z) in o.iter_mut().zip(Yr[0]).zip(Yr[1]).zip(Yr[2]) {
                        *o += b0 * x + b1 * y + b2 * z;
                    }
                }
            }
            for a in 0..3 {
                for c in 0..3 {
                    out[(6 * k + 3 + a, 6 * k + 3 + c)] += alpha * K[(a, c)];
                }
            }
        }
    }
}

/// $\mathbf A\boldsymbol\Lambda$ in place: the $\boldsymbol\theta_k$ column blocks times $\mathbf J_l^{-1}(\boldsymbol\theta_k)$.
pub(crate) fn lambda_right(Lambda: &[Matrix3<f64>], A: &mut Mat<f64>) {
    let rows = 0..A.nrows();
    pulp::Arch::new().dispatch(LambdaRight { Lambda, A, rows });
}

vectorized_kernel!(
    /// [`lambda_right`].
    LambdaRight<'a, 'b> { Lambda: &'a [Matrix3<f64>], A: &'b mut Mat<f64>, rows: std::ops::Range<usize> } => lambda_right_rows
);

/// [`lambda_right`] on the rows `rows` of `A` only (inlined into its caller's vector code).
#[inline(always)]
fn lambda_right_rows(Lambda: &[Matrix3<f64>], A: &mut Mat<f64>, rows: std::ops::Range<usize>) {
    for (k, L) in Lambda.iter().enumerate() {
        // Row i of the block becomes row_i L: new column c = sum_d L[(d, c)] column d. The
        // entries of L in locals and slices of the same length, so that the loop is a plain
        // vector loop.
        let l: [[f64; 3]; 3] = std::array::from_fn(|c| std::array::from_fn(|d| L[(d, c)]));
        let (c0, rest) = A.as_mut().subcols_mut(6 * k + 3, 3).split_at_col_mut(1);
        let (c1, c2) = rest.split_at_col_mut(1);
        mix3(
            &mut first_col_mut(c0)[rows.clone()],
            &mut first_col_mut(c1)[rows.clone()],
            &mut first_col_mut(c2)[rows.clone()],
            &l,
        );
    }
}

/// Row by row, $[a_0, a_1, a_2] \leftarrow [a_0, a_1, a_2]$ times the $3\times3$ whose column $c$ is `l[c]`.
/// Its own function so that the three columns are distinct arguments, which lets the loop
/// vectorise (as one function body over slices of the same matrix it stayed scalar).
#[inline(always)]
fn mix3(a0: &mut [f64], a1: &mut [f64], a2: &mut [f64], l: &[[f64; 3]; 3]) {
    let r = a0.len();
    let (a1, a2) = (&mut a1[..r], &mut a2[..r]);
    for i in 0..r {
        let (x, y, z) = (a0[i], a1[i], a2[i]);
        a0[i] = l[0][0] * x + l[0][1] * y + l[0][2] * z;
        a1[i] = l[1][0] * x + l[1][1] * y + l[1][2] * z;
        a2[i] = l[2][0] * x + l[2][1] * y + l[2][2] * z;
    }
}

/// `out` $= \mathbf S - \mathbf A\boldsymbol\Psi$ (with `sub` $= \mathbf S$, $r\times6$) or $\mathbf A\boldsymbol\Psi$
/// (without) for $\mathbf A$ ($r\times$ at least $6N$; only its $6N$ interface columns enter),
/// $\boldsymbol\Psi$ by its 3x3 blocks $[\mathbf I,\ -\tilde{\mathbf r}_k;\ \mathbf 0,\ \boldsymbol\Lambda_k]$: per
/// row and interface 3 additions and 15 multiply-adds ($-\tilde{\mathbf r}_k$ has a zero diagonal), in
/// one pass over $\mathbf A$'s columns, compiled for the machine's vector instructions like the block
/// kernels (`vectorized_kernel`). A dense product with the formed $6N\times6$ $\boldsymbol\Psi$ costs
/// twice the multiply-adds and faer's fixed cost of a product.
pub(crate) fn psi_product(
    r_loc: &[Vector3<f64>],
    Lambda: &[Matrix3<f64>],
    A: MatRef<'_, f64>,
    sub: Option<MatRef<'_, f64>>,
    out: MatMut<'_, f64>,
) {
    pulp::Arch::new().dispatch(PsiProduct {
        r_loc,
        Lambda,
        A,
        sub,
        out,
    });
}

/// [`psi_product`].
struct PsiProduct<'a, 'b> {
    r_loc: &'a [Vector3<f64>],
    Lambda: &'a [Matrix3<f64>],
    A: MatRef<'a, f64>,
    sub: Option<MatRef<'a, f64>>,
    out: MatMut<'b, f64>,
}

impl pulp::WithSimd for PsiProduct<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self {
            r_loc,
            Lambda,
            A,
            sub,
            out,
        } = self;
        let r = A.nrows();
        let mut o = cols_mut::<6>(out);
        let sign = match sub {
            Some(S) => {
                for (c, o) in o.iter_mut().enumerate() {
                    o[..r].copy_from_slice(&col(S, c)[..r]);
                }
                -1.0
            }
            None => {
                for o in o.iter_mut() {
                    o[..r].fill(0.0);
                }
                1.0
            }
        };
        let [o0, o1, o2, o3, o4, o5] = &mut o;
        let (o0, o1, o2, o3, o4, o5) = (
            &mut o0[..r],
            &mut o1[..r],
            &mut o2[..r],
            &mut o3[..r],
            &mut o4[..r],
            &mut o5[..r],
        );
        for (k, (x, L)) in r_loc.iter().zip(Lambda).enumerate() {
            // Columns 3 + b of -r~ : (0, -x3, x2), (x3, 0, -x1), (-x2, x1, 0).
            let (x1, x2, x3) = (sign * x[0], sign * x[1], sign * x[2]);
            let l: [[f64; 3]; 3] = std::array::from_fn(|b| std::array::from_fn(|a| sign * L[(a, b)]));
            let a: [&[f64]; 6] = std::array::from_fn(|c| &col(A, 6 * k + c)[..r]);
            for i in 0..r {
                let (u0, u1, u2) = (a[0][i], a[1][i], a[2][i]);
                let (t0, t1, t2) = (a[3][i], a[4][i], a[5][i]);
                o0[i] += sign * u0;
                o1[i] += sign * u1;
                o2[i] += sign * u2;
                o3[i] += u2 * x2 - u1 * x3 + t0 * l[0][0] + t1 * l[0][1] + t2 * l[0][2];
                o4[i] += u0 * x3 - u2 * x1 + t0 * l[1][0] + t1 * l[1][1] + t2 * l[1][2];
                o5[i] += u1 * x1 - u0 * x2 + t0 * l[2][0] + t1 * l[2][1] + t2 * l[2][2];
            }
        }
    }
}

/// `out[:, c0..c0+3]` $\mathrel{+}= \alpha\,\mathbf A\mathbf W(\mathbf x)$ with $\mathbf W(\mathbf x)$ the stack of
/// $\tilde{\mathbf x}_b$ over the first `blocks` 3-blocks of `x` (zero below): column block
/// $b$ of $\mathbf A$ times $\tilde{\mathbf x}_b$, six multiply-adds per row and block, without
/// forming $\mathbf W$ (a dense product with it costs as much in multiply-adds and more in set-up).
pub(crate) fn add_mul_w(A: MatRef<'_, f64>, x: &[f64], blocks: usize, alpha: f64, out: &mut Mat<f64>, c0: usize) {
    pulp::Arch::new().dispatch(AddMulW {
        A,
        x,
        blocks,
        alpha,
        out,
        c0,
    });
}

#[inline(always)]
fn add_mul_w_body(A: MatRef<'_, f64>, x: &[f64], blocks: usize, alpha: f64, out: &mut Mat<f64>, c0: usize) {
    let n = out.nrows();
    let (o0, rest) = out.as_mut().subcols_mut(c0, 3).split_at_col_mut(1);
    let (o1, o2) = rest.split_at_col_mut(1);
    let (o0, o1, o2) = (
        &mut first_col_mut(o0)[..n],
        &mut first_col_mut(o1)[..n],
        &mut first_col_mut(o2)[..n],
    );
    for b in 0..blocks {
        let (x1, x2, x3) = (alpha * x[3 * b], alpha * x[3 * b + 1], alpha * x[3 * b + 2]);
        let (a0, a1, a2) = (&col(A, 3 * b)[..n], &col(A, 3 * b + 1)[..n], &col(A, 3 * b + 2)[..n]);
        add_mul_skew(o0, o1, o2, a0, a1, a2, [x1, x2, x3]);
    }
}

/// $[\mathbf o_0, \mathbf o_1, \mathbf o_2] \mathrel{+}= [\mathbf a_0, \mathbf a_1, \mathbf a_2]\tilde{\mathbf x}$:
/// columns $\mathbf a_1x_3 - \mathbf a_2x_2$, $\mathbf a_2x_1 - \mathbf a_0x_3$, $\mathbf a_0x_2 - \mathbf a_1x_1$
/// (its own function, so that the outputs are distinct arguments and the loop vectorises).
#[inline(always)]
fn add_mul_skew(
    o0: &mut [f64],
    o1: &mut [f64],
    o2: &mut [f64],
    a0: &[f64],
    a1: &[f64],
    a2: &[f64],
    [x1, x2, x3]: [f64; 3],
) {
    let n = o0.len();
    let (o1, o2, a0, a1, a2) = (&mut o1[..n], &mut o2[..n], &a0[..n], &a1[..n], &a2[..n]);
    for i in 0..n {
        o0[i] += a1[i] * x3 - a2[i] * x2;
        o1[i] += a2[i] * x1 - a0[i] * x3;
        o2[i] += a0[i] * x2 - a1[i] * x1;
    }
}

/// `out` $\mathrel{-}= \mathbf A\boldsymbol\Psi$ ($r\times6$) for $\mathbf A$ ($r\times n$, only its $6N$
/// interface columns enter), $\boldsymbol\Psi$ from its blocks (rows $[\mathbf I,\ -\tilde{\mathbf r}_k]$ for
/// $\mathbf u_k$ and $[\mathbf 0,\ \boldsymbol\Lambda_k]$ for $\boldsymbol\theta_k$, `r_loc` and `Lambda` of the
/// configuration): the first three columns are sums of the $\mathbf u_k$ columns, the last three
/// two $3\times3$ block products per interface. Replaces a dense product with $\boldsymbol\Psi$
/// (`Kinematics::mul_psi`) and the subtraction after it where the tangents need
/// $\mathbf B - \mathbf A\boldsymbol\Psi$: a third of its multiply-adds are with the zero and identity
/// blocks, and its fixed cost is that of the rest at $n = 14$.
pub(crate) fn sub_mul_psi(A: MatRef<'_, f64>, r_loc: &[Vector3<f64>], Lambda: &[Matrix3<f64>], out: &mut Mat<f64>) {
    pulp::Arch::new().dispatch(SubMulPsi { A, r_loc, Lambda, out });
}

vectorized_kernel!(
    /// [`sub_mul_psi`].
    SubMulPsi<'a, 'b> { A: MatRef<'a, f64>, r_loc: &'a [Vector3<f64>], Lambda: &'a [Matrix3<f64>], out: &'b mut Mat<f64> } => sub_mul_psi_body
);

#[inline(always)]
fn sub_mul_psi_body(A: MatRef<'_, f64>, r_loc: &[Vector3<f64>], Lambda: &[Matrix3<f64>], out: &mut Mat<f64>) {
    let r = A.nrows();
    for (k, (x, L)) in r_loc.iter().zip(Lambda).enumerate() {
        let mr = -skew(x);
        let (u0, u1, u2) = (col(A, 6 * k), col(A, 6 * k + 1), col(A, 6 * k + 2));
        let (t0, t1, t2) = (col(A, 6 * k + 3), col(A, 6 * k + 4), col(A, 6 * k + 5));
        for (c, u) in [u0, u1, u2].into_iter().enumerate() {
            sub_combination(
                &mut out.col_as_slice_mut(c)[..r],
                [u, u, u, u, u, u],
                [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                1,
            );
        }
        for e in 0..3 {
            sub_combination(
                &mut out.col_as_slice_mut(3 + e)[..r],
                [u0, u1, u2, t0, t1, t2],
                [mr[(0, e)], mr[(1, e)], mr[(2, e)], L[(0, e)], L[(1, e)], L[(2, e)]],
                6,
            );
        }
    }
}

/// `o` $\mathrel{-}= \sum_{a < m} w_a\mathbf x_a$ over the length of `o` ($m$ = 1 or 6); its own function
/// so that the slices are distinct arguments and the loop vectorises without overlap checks.
#[inline(always)]
fn sub_combination(o: &mut [f64], x: [&[f64]; 6], w: [f64; 6], m: usize) {
    let r = o.len();
    let (x0, x1, x2, x3, x4, x5) = (&x[0][..r], &x[1][..r], &x[2][..r], &x[3][..r], &x[4][..r], &x[5][..r]);
    if m == 1 {
        for i in 0..r {
            o[i] -= x0[i];
        }
        return;
    }
    for i in 0..r {
        o[i] -= (x0[i] * w[0] + x1[i] * w[1] + x2[i] * w[2]) + (x3[i] * w[3] + x4[i] * w[4] + x5[i] * w[5]);
    }
}

/// Column `j` of a mutable column-major view as a slice.
#[inline]
pub(crate) fn col_mut(A: MatMut<'_, f64>, j: usize) -> &mut [f64] {
    first_col_mut(A.subcols_mut(j, 1))
}

/// The first `K` columns of a column-major view as slices.
pub(crate) fn cols_mut<const K: usize>(A: MatMut<'_, f64>) -> [&mut [f64]; K] {
    let mut rest = Some(A);
    std::array::from_fn(|_| {
        let (first, others) = rest.take().expect("K columns").split_at_col_mut(1);
        rest = Some(others);
        first_col_mut(first)
    })
}

/// The first column of a column-major view as a slice.
fn first_col_mut<'a>(m: faer::MatMut<'a, f64>) -> &'a mut [f64] {
    m.col_mut(0)
        .try_as_col_major_mut()
        .expect("column-major matrix")
        .as_slice_mut()
}

/// $\boldsymbol\Lambda^T\mathbf A$ in place: the $\boldsymbol\theta_k$ row blocks times $\mathbf J_l^{-T}(\boldsymbol\theta_k)$.
pub(crate) fn lambda_t_left(Lambda: &[Matrix3<f64>], A: &mut Mat<f64>) {
    lambda_t_left_cols(Lambda, A, 0..A.ncols());
}

/// [`lambda_t_left`] on the columns `cols` of `A` only.
pub(crate) fn lambda_t_left_cols(Lambda: &[Matrix3<f64>], A: &mut Mat<f64>, cols: std::ops::Range<usize>) {
    // Block by block, the entries of L^T in locals for all columns.
    for (k, L) in Lambda.iter().enumerate() {
        let l: [f64; 9] = std::array::from_fn(|e| L[(e % 3, e / 3)]);
        for j in cols.clone() {
            let c: &mut [f64; 3] = (&mut A.col_as_slice_mut(j)[6 * k + 3..6 * k + 6])
                .try_into()
                .expect("a 3-block");
            let (x, y, z) = (c[0], c[1], c[2]);
            c[0] = l[0] * x + l[1] * y + l[2] * z;
            c[1] = l[3] * x + l[4] * y + l[5] * z;
            c[2] = l[6] * x + l[7] * y + l[8] * z;
        }
    }
}

impl Kinematics {
    /// `out` $= \mathbf A\boldsymbol\Psi$ ($r\times6$) for $\mathbf A$ ($r\times n$), $\boldsymbol\Psi =
    /// \boldsymbol\Lambda\boldsymbol\Phi_{rig}$ (rows $[\mathbf I,\ -\tilde{\mathbf r}_k]$ and $[\mathbf 0,\
    /// \boldsymbol\Lambda_k]$): only the $6N$ interface columns of $\mathbf A$ enter, by 3x3 blocks
    /// ([`psi_product`]).
    pub(crate) fn mul_psi(&self, A: MatRef<'_, f64>, out: &mut Mat<f64>) {
        psi_product(&self.r_loc, &self.Lambda, A, None, out.as_mut());
    }

    /// `out` $= \boldsymbol\Psi^T\mathbf E$ ($6\times k$) for $\mathbf E$ ($n\times k$).
    pub(crate) fn psi_t_mul(&self, E: MatRef<'_, f64>, out: &mut Mat<f64>) {
        let ni = self.PsiT.ncols();
        gemm(out, self.PsiT.as_ref(), E.subrows(0, ni), 1.0, Accum::Replace);
    }

    /// `start` $- \boldsymbol\Psi^T\mathbf e$ for one column $\mathbf e$ (its interface
    /// entries): $\sum_k[\mathbf e_{u_k};\ \mathbf r_k\times\mathbf e_{u_k} + \boldsymbol\Lambda_k^T\mathbf e_{\theta_k}]$
    /// subtracted block by block.
    #[inline(always)]
    fn psi_t_col(&self, e: &[f64], start: [f64; 6]) -> [f64; 6] {
        let mut t = start;
        // Exact 6-chunks (u_k, theta_k): no bounds checks.
        for ((c, r), L) in e[..6 * self.r_loc.len()]
            .chunks_exact(6)
            .zip(&self.r_loc)
            .zip(&self.Lambda)
        {
            let eu = Vector3::new(c[0], c[1], c[2]);
            let et = Vector3::new(c[3], c[4], c[5]);
            let w = r.cross(&eu) + L.tr_mul(&et);
            for i in 0..3 {
                t[i] -= eu[i];
                t[3 + i] -= w[i];
            }
        }
        t
    }

    /// `out` $= \mathbf A\mathbf X$ ($r\times n$) for $\mathbf A$ ($r\times(6+n)$), with
    /// $\mathbf X = [\mathbf 0; \mathbf I] + [\mathbf I_6; -\boldsymbol\Psi]\mathbf Z_j$:
    /// $\mathbf A_{\cdot q} + (\mathbf A_{\cdot 6} - \mathbf A_{\cdot q}\boldsymbol\Psi)\mathbf Z_j$, the
    /// bracket in one pass of 3x3 blocks ([`psi_product`]). `tmp` is $r\times6$.
    pub(crate) fn mul_x(&self, A: MatRef<'_, f64>, tmp: &mut Mat<f64>, out: &mut Mat<f64>) {
        let n = self.n();
        psi_product(
            &self.r_loc,
            &self.Lambda,
            A.subcols(6, n),
            Some(A.subcols(0, 6)),
            tmp.as_mut(),
        );
        copy_mat(out, A.subcols(6, n));
        gemm(out, tmp.as_ref(), self.Z(), 1.0, Accum::Add);
    }

    /// `out` $= \mathbf X^T\mathbf E$ ($n\times k$) for $\mathbf E$ ($(6+n)\times k$):
    /// $\mathbf E_q + \mathbf Z_j^T(\mathbf E_6 - \boldsymbol\Psi^T\mathbf E_q)$. `tmp` is $6\times k$ (views:
    /// [`crate::forces::Local::apply_x_t`] multiplies a varying number of columns). The bracket
    /// by a product with the formed $\boldsymbol\Psi^T$: column by column in 3x3 blocks
    /// ([`Self::psi_t_col`]) it costs more (rows are not contiguous).
    pub(crate) fn xt_mul(&self, E: MatRef<'_, f64>, mut tmp: MatMut<'_, f64>, mut out: MatMut<'_, f64>) {
        let n = self.n();
        let ni = self.PsiT.ncols();
        matmul(
            tmp.rb_mut(),
            Accum::Replace,
            self.PsiT.as_ref(),
            E.subrows(6, ni),
            1.0,
            Par::Seq,
        );
        for j in 0..E.ncols() {
            let e = col(E, j);
            let t = col_mut(tmp.rb_mut(), j);
            for i in 0..6 {
                t[i] = e[i] - t[i];
            }
            col_mut(out.rb_mut(), j)[..n].copy_from_slice(&e[6..6 + n]);
        }
        matmul(out, Accum::Add, self.ZT.as_ref(), tmp.rb(), 1.0, Par::Seq);
    }

    /// `out` $(+)= \mathbf T_j^T\mathbf A = \mathbf A - \mathbf Z_j^T(\boldsymbol\Psi^T\mathbf A)$ for $\mathbf A$ ($n\times k$); `tmp` is $6\times k$.
    pub(crate) fn tt_mul(&self, A: MatRef<'_, f64>, tmp: &mut Mat<f64>, out: &mut Mat<f64>, accum: Accum) {
        self.psi_t_mul(A, tmp);
        match accum {
            Accum::Replace => copy_mat(out, A),
            Accum::Add => {
                for j in 0..A.ncols() {
                    for (o, a) in out.col_as_slice_mut(j).iter_mut().zip(col(A, j)) {
                        *o += a;
                    }
                }
            }
        }
        gemm(out, self.ZT.as_ref(), tmp.as_ref(), -1.0, Accum::Add);
    }

    /// `out` $= \mathbf A\mathbf T_j = \mathbf A - (\mathbf A\boldsymbol\Psi)\mathbf Z_j$ for $\mathbf A$ ($r\times n$); `tmp` is $r\times6$.
    pub(crate) fn mul_t(&self, A: MatRef<'_, f64>, tmp: &mut Mat<f64>, out: &mut Mat<f64>) {
        self.mul_psi(A, tmp);
        copy_mat(out, A);
        gemm(out, tmp.as_ref(), self.Z(), -1.0, Accum::Add);
    }

    /// $\mathbf X^T\mathbf f$ for a vector $\mathbf f \in \mathbb R^{6+n}$.
    pub(crate) fn xt_vec(&self, f: &[f64], out: &mut [f64]) {
        let n = self.n();
        let t = self.psi_t_col(&f[6..], std::array::from_fn(|i| f[i]));
        // Z_j^T t by the columns of Z_j^T (contiguous, no per-column slice look-up), summed in
        // the order of a as a dot product per row would.
        let zt: [&[f64]; 6] = std::array::from_fn(|a| &col(self.ZT.as_ref(), a)[..n]);
        let (out, f) = (&mut out[..n], &f[6..6 + n]);
        for j in 0..n {
            let z = [zt[0][j], zt[1][j], zt[2][j], zt[3][j], zt[4][j], zt[5][j]];
            out[j] = f[j] + (z[0] * t[0] + z[1] * t[1] + z[2] * t[2] + z[3] * t[3] + z[4] * t[4] + z[5] * t[5]);
        }
    }

    /// $\mathbf P^T\mathbf f = \boldsymbol\Lambda^T\mathbf X^T\mathbf f$.
    pub(crate) fn pt_vec(&self, f: &[f64], out: &mut [f64]) {
        self.xt_vec(f, out);
        for (k, L) in self.Lambda.iter().enumerate() {
            let r = 6 * k + 3;
            let v = L.transpose() * Vector3::new(out[r], out[r + 1], out[r + 2]);
            out[r..r + 3].copy_from_slice(v.as_slice());
        }
    }
}

/// $\bar{\mathbf R}$-rotation of an $n\times n$ matrix: `out` $= \bar{\mathbf R}\mathbf K\bar{\mathbf R}^T$.
///
/// Two passes with no temporary: the interface column blocks of `out` get $\mathbf K$'s times
/// $\mathbf R^T$ (the eta columns are copied), then each interface 3-block of every column of `out` is
/// turned by $\mathbf R$ in place.
pub(crate) fn rotate_matrix(R: &Matrix3<f64>, N: usize, K: &Mat<f64>, out: &mut Mat<f64>) {
    pulp::Arch::new().dispatch(RotateMatrix { R, N, K, out });
}

#[inline(always)]
fn rotate_matrix_body(R: &Matrix3<f64>, N: usize, K: &Mat<f64>, out: &mut Mat<f64>) {
    let n = K.nrows();
    let nb = 2 * N;
    for b in 0..nb {
        let (k0, k1, k2) = (
            K.col_as_slice(3 * b),
            K.col_as_slice(3 * b + 1),
            K.col_as_slice(3 * b + 2),
        );
        for c in 0..3 {
            let o = &mut out.col_as_slice_mut(3 * b + c)[..n];
            let (r0, r1, r2) = (R[(c, 0)], R[(c, 1)], R[(c, 2)]);
            let (k0, k1, k2) = (&k0[..n], &k1[..n], &k2[..n]);
            for i in 0..n {
                o[i] = k0[i] * r0 + k1[i] * r1 + k2[i] * r2;
            }
        }
    }
    for j in 3 * nb..n {
        out.col_as_slice_mut(j).copy_from_slice(K.col_as_slice(j));
    }
    rotate_rows(R, nb, out);
}

/// The second pass of [`rotate_matrix`]: the first `nb` 3-blocks of every column of `out` turned
/// by $\mathbf R$ in place.
#[inline(always)]
fn rotate_rows(R: &Matrix3<f64>, nb: usize, out: &mut Mat<f64>) {
    for j in 0..out.ncols() {
        // Exact 3-chunks: no bounds checks in the block rotations.
        for o in out.col_as_slice_mut(j)[..3 * nb].chunks_exact_mut(3) {
            let v = R * Vector3::new(o[0], o[1], o[2]);
            o.copy_from_slice(v.as_slice());
        }
    }
}

/// The stiffness in absolute axes from its two body-axis parts, `out` $= \bar{\mathbf R}(\mathbf D_q
/// \boldsymbol\Lambda + \mathbf G)\bar{\mathbf R}^T$, without forming $\mathbf D_q\boldsymbol\Lambda + \mathbf G$: the
/// column pass of [`rotate_matrix`] takes both, $\mathbf D_q$'s $\boldsymbol\theta_k$ column blocks times
/// $\boldsymbol\Lambda_k\mathbf R^T$ (its $\mathbf u_k$ blocks and $\mathbf G$'s times $\mathbf R^T$), then the
/// row pass turns the result in place. Saves the copy of $\mathbf D_q$ and the pass of
/// [`lambda_right`] over it.
pub(crate) fn rotate_stiffness(
    R: &Matrix3<f64>,
    Lambda: &[Matrix3<f64>],
    Dq: &Mat<f64>,
    G: &Mat<f64>,
    out: &mut Mat<f64>,
) {
    pulp::Arch::new().dispatch(RotateStiffness { R, Lambda, Dq, G, out });
}

struct RotateStiffness<'a, 'b> {
    R: &'a Matrix3<f64>,
    Lambda: &'a [Matrix3<f64>],
    Dq: &'a Mat<f64>,
    G: &'a Mat<f64>,
    out: &'b mut Mat<f64>,
}

impl pulp::WithSimd for RotateStiffness<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Self { R, Lambda, Dq, G, out } = self;
        let n = Dq.nrows();
        let N = Lambda.len();
        let Rt = R.transpose();
        for b in 0..2 * N {
            // The factor on Dq's block: Lambda_k R^T for theta_k, R^T for u_k.
            let F = if b % 2 == 1 { Lambda[b / 2] * Rt } else { Rt };
            let d = [
                Dq.col_as_slice(3 * b),
                Dq.col_as_slice(3 * b + 1),
                Dq.col_as_slice(3 * b + 2),
            ];
            let g = [
                G.col_as_slice(3 * b),
                G.col_as_slice(3 * b + 1),
                G.col_as_slice(3 * b + 2),
            ];
            for c in 0..3 {
                set_combination(
                    &mut out.col_as_slice_mut(3 * b + c)[..n],
                    [d[0], d[1], d[2], g[0], g[1], g[2]],
                    [F[(0, c)], F[(1, c)], F[(2, c)], Rt[(0, c)], Rt[(1, c)], Rt[(2, c)]],
                );
            }
        }
        for j in 6 * N..n {
            let (d, g) = (&Dq.col_as_slice(j)[..n], &G.col_as_slice(j)[..n]);
            let o = &mut out.col_as_slice_mut(j)[..n];
            for i in 0..n {
                o[i] = d[i] + g[i];
            }
        }
        rotate_rows(R, 2 * N, out);
    }
}

/// `o` $= \sum_{a < 6} w_a\mathbf x_a$ over the length of `o` (its own function, so that the slices
/// are distinct arguments and the loop vectorises without overlap checks).
#[inline(always)]
fn set_combination(o: &mut [f64], x: [&[f64]; 6], w: [f64; 6]) {
    let r = o.len();
    let (x0, x1, x2, x3, x4, x5) = (&x[0][..r], &x[1][..r], &x[2][..r], &x[3][..r], &x[4][..r], &x[5][..r]);
    for i in 0..r {
        o[i] = (x0[i] * w[0] + x1[i] * w[1] + x2[i] * w[2]) + (x3[i] * w[3] + x4[i] * w[4] + x5[i] * w[5]);
    }
}

/// Helper for tests and callers: the frame rotation matrix of a quaternion.
pub fn rotation_matrix(R: &UnitQuaternion<f64>) -> Matrix3<f64> {
    R.to_rotation_matrix().into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numbers in [-1, 1) from a fixed seed (a linear congruential generator: varied values,
    /// not statistical quality).
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut s = seed;
        move || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        }
    }

    /// The frame, $\mathbf q^{jj}$, $\mathbf x_k$, $\boldsymbol\Phi_j$ and the dense
    /// $[\boldsymbol\Psi, \boldsymbol\Lambda, \mathbf X]$ of [`random_configuration`].
    type RandomConfiguration = (Frame, Vec<f64>, Vec<Vector3<f64>>, Mat<f64>, [Mat<f64>; 3]);

    /// A configuration with $N = 2$ interfaces and 3 modes ($n = 15$) from random numbers:
    /// positions of size 1, elastic rotations of about 0.3 rad (so that $\boldsymbol\Lambda$ is
    /// far from the identity), a random $\boldsymbol\Phi_j$; and its dense $\boldsymbol\Psi$
    /// ($n\times6$), $\boldsymbol\Lambda$ ($n\times n$) and $\mathbf X$ ($(6+n)\times n$) formed
    /// entry by entry from their definitions (module docs).
    fn random_configuration(seed: u64) -> RandomConfiguration {
        let (N, m) = (2, 3);
        let n = 6 * N + m;
        let mut r = numbers(seed);
        let x: Vec<Vector3<f64>> = (0..N).map(|_| Vector3::new(r(), r(), r())).collect();
        let q: Vec<f64> = (0..n)
            .map(|i| if i % 6 >= 3 && i < 6 * N { 0.3 * r() } else { 0.1 * r() })
            .collect();
        let Phi_j = Mat::from_fn(6, n, |_, _| r());
        let frame = Frame::new(
            Vector3::new(r(), r(), r()),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.4, -0.7, 0.2)),
        );
        let r_loc: Vec<Vector3<f64>> = (0..N).map(|k| x[k] + u_of(&q, k)).collect();
        let Lam: Vec<Matrix3<f64>> = (0..N).map(|k| so3::left_jacobian_inv(&theta_of(&q, k))).collect();
        let Psi = dense_psi(&r_loc, &Lam, n);
        let mut L = Mat::<f64>::identity(n, n);
        for k in 0..N {
            for a in 0..3 {
                for b in 0..3 {
                    L[(6 * k + 3 + a, 6 * k + 3 + b)] = Lam[k][(a, b)];
                }
            }
        }
        let G = &Phi_j * &Psi;
        let Z = faer::prelude::Solve::solve(&G.as_ref().partial_piv_lu(), &Phi_j);
        let T = Mat::<f64>::identity(n, n) - &Psi * &Z;
        let X = Mat::from_fn(6 + n, n, |i, j| if i < 6 { Z[(i, j)] } else { T[(i - 6, j)] });
        (frame, q, x, Phi_j, [Psi, L, X])
    }

    /// The formed $n\times6$ $\boldsymbol\Psi$: rows $[\mathbf I,\ -\tilde{\mathbf r}_k]$ ($\mathbf u_k$) and
    /// $[\mathbf 0,\ \boldsymbol\Lambda_k]$ ($\boldsymbol\theta_k$) of each interface, zero modal rows.
    fn dense_psi(r_loc: &[Vector3<f64>], Lambda: &[Matrix3<f64>], n: usize) -> Mat<f64> {
        let mut Psi = Mat::<f64>::zeros(n, 6);
        for (k, (r, L)) in r_loc.iter().zip(Lambda).enumerate() {
            let mr = -skew(r);
            for a in 0..3 {
                Psi[(6 * k + a, a)] = 1.0;
                for b in 0..3 {
                    Psi[(6 * k + a, 3 + b)] = mr[(a, b)];
                    Psi[(6 * k + 3 + a, 3 + b)] = L[(a, b)];
                }
            }
        }
        Psi
    }

    fn assert_close(a: MatRef<'_, f64>, b: MatRef<'_, f64>, tol: f64, what: &str) {
        assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()), "{what}: shapes");
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                assert!(
                    (a[(i, j)] - b[(i, j)]).abs() < tol,
                    "{what} ({i}, {j}): {} against {}",
                    a[(i, j)],
                    b[(i, j)]
                );
            }
        }
    }

    /// [`Kinematics::update`] and the products with $\mathbf X$, $\mathbf X^T$, $\mathbf P^T$ and
    /// $\boldsymbol\Psi$ against dense matrices formed from their definitions, on a random
    /// configuration with non-square operands (7 and 11 rows, 4 columns): the forces-only
    /// update forms the $\mathbf Z_j$ and $\mathbf Y$ rows as the complete one does; a complete
    /// update of the same configuration adds the rest to the bit; a new configuration is formed
    /// anew. Entries are sums of at most 20 products of numbers of size about
    /// $\|\mathbf Z_j\| \lesssim 10$, summed in other orders than the dense products (and the
    /// dense $\mathbf Z_j$ from another factorisation): $10^{-12}$ is some 100 times that
    /// round-off.
    #[test]
    fn configuration_products_match_dense() {
        let tol = 1e-12;
        let (frame, q, x, Phi_j, [Psi, L, X]) = random_configuration(31);
        let n = q.len();
        let N = x.len();
        let full = Kinematics::new(frame, 2, q.clone(), &x, Phi_j.as_ref()).unwrap();
        let P = &X * &L;
        assert_close(full.X.as_ref(), X.as_ref(), tol, "X");
        assert_close(full.P.as_ref(), P.as_ref(), tol, "P");
        assert_close(full.ZT.as_ref(), X.as_ref().subrows(0, 6).transpose(), tol, "Z^T");
        assert_close(full.YrT.as_ref(), P.as_ref().subrows(3, 3).transpose(), tol, "Y_r^T");
        assert_close(
            full.PsiT.as_ref(),
            Psi.as_ref().subrows(0, 6 * N).transpose(),
            tol,
            "Psi^T",
        );
        // Forces-only, then complete, then a new configuration.
        let mut kin = Kinematics::empty(N, n);
        kin.q_jj.copy_from_slice(&q);
        kin.update(frame, 2, &x, Phi_j.as_ref(), false).unwrap();
        assert_eq!(kin.formed, Formed::Forces);
        assert_close(
            kin.X.as_ref().subrows(0, 6),
            X.as_ref().subrows(0, 6),
            tol,
            "Z (forces)",
        );
        assert_close(
            kin.P.as_ref().subrows(0, 6),
            P.as_ref().subrows(0, 6),
            tol,
            "Y (forces)",
        );
        kin.update(frame, 0, &x, Phi_j.as_ref(), true).unwrap();
        assert_eq!(kin.formed, Formed::All);
        assert_eq!(kin.frame_iterations, 0);
        for (a, b) in [
            (&kin.X, &full.X),
            (&kin.P, &full.P),
            (&kin.ZT, &full.ZT),
            (&kin.YrT, &full.YrT),
        ] {
            assert!(a == b, "the completed configuration differs from the complete one");
        }
        // Another frame and q (same x and Phi_j): formed anew, as a fresh configuration.
        let (frame2, q2, ..) = random_configuration(32);
        kin.q_jj.copy_from_slice(&q2);
        kin.update(frame2, 1, &x, Phi_j.as_ref(), false).unwrap();
        assert_eq!(kin.formed, Formed::Forces);
        let fresh = Kinematics::new(frame2, 1, q2, &x, Phi_j.as_ref()).unwrap();
        assert!(kin.X.as_ref().subrows(0, 6) == fresh.X.as_ref().subrows(0, 6));
        assert!(kin.P.as_ref().subrows(0, 6) == fresh.P.as_ref().subrows(0, 6));
        assert!(kin.ZT == fresh.ZT && kin.PsiT == fresh.PsiT && kin.G_inv == fresh.G_inv);

        // Products, on the complete configuration.
        let mut r = numbers(33);
        let kin = &full;
        for rows in [7, 11] {
            let A = Mat::from_fn(rows, 6 + n, |_, _| r());
            let mut tmp = Mat::zeros(rows, 6);
            psi_product(&kin.r_loc, &kin.Lambda, A.as_ref().subcols(6, n), None, tmp.as_mut());
            assert_close(tmp.as_ref(), (A.as_ref().subcols(6, n) * &Psi).as_ref(), tol, "A Psi");
            let mut out = Mat::zeros(rows, n);
            kin.mul_x(A.as_ref(), &mut tmp, &mut out);
            assert_close(out.as_ref(), (&A * &X).as_ref(), tol, "A X");
        }
        let E = Mat::from_fn(6 + n, 4, |_, _| r());
        let (mut tmp, mut out) = (Mat::zeros(6, 4), Mat::zeros(n, 4));
        kin.xt_mul(E.as_ref(), tmp.as_mut(), out.as_mut());
        assert_close(out.as_ref(), (X.transpose() * &E).as_ref(), tol, "X^T E");
        let f: Vec<f64> = (0..6 + n).map(|_| r()).collect();
        let fm = Mat::from_fn(6 + n, 1, |i, _| f[i]);
        let mut v = vec![0.0; n];
        kin.xt_vec(&f, &mut v);
        assert_close(
            Mat::from_fn(n, 1, |i, _| v[i]).as_ref(),
            (X.transpose() * &fm).as_ref(),
            tol,
            "X^T f",
        );
        kin.pt_vec(&f, &mut v);
        assert_close(
            Mat::from_fn(n, 1, |i, _| v[i]).as_ref(),
            (P.transpose() * &fm).as_ref(),
            tol,
            "P^T f",
        );
        // to_inertial_into, to_body_into: Rbar x and Rbar^T x.
        let R = kin.R_j;
        for forward in [true, false] {
            let Rb = if forward { R } else { R.transpose() };
            if forward {
                kin.to_inertial_into(&f[..n], &mut v);
            } else {
                kin.to_body_into(&f[..n], &mut v);
            }
            for i in 0..n {
                let expected = if i < 6 * N {
                    let b = i / 3;
                    (0..3).map(|c| Rb[(i % 3, c)] * f[3 * b + c]).sum::<f64>()
                } else {
                    f[i]
                };
                assert!((v[i] - expected).abs() < 1e-15, "rotate_into {forward} entry {i}");
            }
        }
    }

    /// [`inverse_with_rcond`] by blocks against nalgebra's LU inverse: random 6x6 matrices with a
    /// leading block near the identity (as $\boldsymbol\Phi_j\boldsymbol\Psi$) and with a general
    /// well-conditioned one agree within $10^{-13}$ (entries of size 1, condition numbers below
    /// 100: some 100 times round-off); a matrix with a singular leading block (a block
    /// permutation) takes the LU path and is inverted exactly; a singular matrix gives `None`.
    #[test]
    fn block_inverse_matches_lu() {
        let mut r = numbers(41);
        for near_identity in [true, false, true, false] {
            let G = Matrix6::from_fn(|i, j| {
                let base = if near_identity && i < 3 && j < 3 && i == j {
                    1.0
                } else {
                    0.0
                };
                let scale = if near_identity && i < 3 && j < 3 { 1e-3 } else { 0.5 };
                base + scale * r() + if i == j { 2.0 } else { 0.0 }
            });
            let (Gi, rcond) = inverse_with_rcond(&G).unwrap();
            let lu = G.try_inverse().unwrap();
            assert!((Gi - lu).abs().max() < 1e-13, "{G}");
            assert!(rcond > 1e-2 && rcond <= 1.0);
        }
        let mut P = Matrix6::zeros();
        for i in 0..3 {
            P[(i, 3 + i)] = 1.0;
            P[(3 + i, i)] = 2.0;
        }
        assert!(block_inverse(&P).is_none());
        let (Pi, _) = inverse_with_rcond(&P).unwrap();
        assert_eq!(P * Pi, Matrix6::identity());
        let mut S = Matrix6::identity();
        S[(5, 5)] = 0.0;
        S[(4, 5)] = 1.0;
        assert!(inverse_with_rcond(&S).is_none_or(|(_, rcond)| rcond < RCOND_MIN));
    }

    /// [`PackedTall::mul`] against faer's product on non-square inputs: $m = 37$ rows (four
    /// strips of 8 and a padded strip of 5), 5 and 14 columns, 1, 2 and 3 right-hand sides, and
    /// an empty product. Both sides sum $k \le 14$ products of numbers of size 1 per entry, in
    /// a different order and rounding (fused multiply-adds here): $10^{-14}$ is some 20 times
    /// that round-off.
    #[test]
    fn packed_tall_product_matches_faer() {
        for (m, k, seed) in [(37, 5, 21), (37, 14, 22), (8, 3, 23)] {
            let mut r = numbers(seed);
            let A = Mat::from_fn(m, k, |_, _| r());
            let B = Mat::from_fn(k, 3, |_, _| r());
            let packed = PackedTall::new(m, k, |i, j| A[(i, j)]);
            let AB = &A * &B;
            let check = |out: &[Vec<f64>]| {
                for (c, o) in out.iter().enumerate() {
                    for (i, x) in o.iter().enumerate() {
                        assert!((x - AB[(i, c)]).abs() < 1e-14, "m {m} k {k}: column {c} row {i}");
                    }
                }
            };
            let b = |c: usize| B.col_as_slice(c);
            let mut o = vec![vec![f64::NAN; m]; 3];
            let [o0, o1, o2] = &mut o[..] else { unreachable!() };
            packed.mul([b(0), b(1), b(2)], [&mut o0[..], o1, o2]);
            check(&o);
            let mut o = vec![vec![f64::NAN; m]; 2];
            let [o0, o1] = &mut o[..] else { unreachable!() };
            packed.mul([b(0), b(1)], [&mut o0[..], o1]);
            check(&o);
            let mut o = vec![vec![f64::NAN; m]; 1];
            packed.mul([b(0)], [&mut o[0][..]]);
            check(&o);
        }
        // No columns: every entry is the empty sum.
        let mut o = [f64::NAN; 6];
        PackedTall::new(6, 0, |_, _| 1.0).mul([&[][..]], [&mut o[..]]);
        assert!(o.iter().all(|&x| x == 0.0));
    }

    /// The dispatched block kernels against straightforward dense products with the formed
    /// block-diagonal or stacked operators, on non-square inputs (11 rows, 2 interfaces and 3
    /// modes: 15 columns; 7 and 5 rows for the odd remainders of the vector loops). Both sides
    /// sum at most 3 products of numbers of size 1 per entry, in a different order:
    /// $10^{-14}$ is some 20 times that round-off.
    #[test]
    fn vectorized_kernels_match_dense_products() {
        let tol = 1e-14;
        for (rows, seed) in [(11, 1), (7, 2), (5, 3)] {
            let (N, m) = (2, 3);
            let n = 6 * N + m;
            let mut r = numbers(seed);
            let A = Mat::from_fn(rows, n, |_, _| r());
            let m3 = |r: &mut dyn FnMut() -> f64| Matrix3::from_fn(|_, _| r());
            let blocks = Blocks {
                t: (0..N).map(|_| m3(&mut r)).collect(),
                r: (0..N).map(|_| m3(&mut r)).collect(),
            };
            let close = |a: &Mat<f64>, b: &Mat<f64>, what: &str| {
                for j in 0..a.ncols() {
                    for i in 0..a.nrows() {
                        assert!((a[(i, j)] - b[(i, j)]).abs() < tol, "{what} rows {rows} ({i}, {j})");
                    }
                }
            };
            // add_mul_blocks_at: out[:, c0..c0 + n] += A diag(blocks) (eta columns unchanged).
            let c0 = 2;
            let mut D = Mat::<f64>::zeros(n, n);
            for k in 0..N {
                for (off, B) in [(6 * k, &blocks.t[k]), (6 * k + 3, &blocks.r[k])] {
                    for a in 0..3 {
                        for b in 0..3 {
                            D[(off + a, off + b)] = B[(a, b)];
                        }
                    }
                }
            }
            let start = Mat::from_fn(rows, c0 + n + 1, |_, _| r());
            let mut out = start.clone();
            add_mul_blocks_at(A.as_ref(), &blocks, &mut out, c0);
            let mut expected = start.clone();
            let AD = &A * &D;
            for j in 0..n {
                for i in 0..rows {
                    expected[(i, c0 + j)] += AD[(i, j)];
                }
            }
            close(&out, &expected, "add_mul_blocks_at");
            // add_mul_w: out[:, c0..c0 + 3] += alpha A W(x), W the stack of x_b~ over 2N blocks.
            let x: Vec<f64> = (0..n).map(|_| r()).collect();
            let alpha = 0.7;
            let mut W = Mat::<f64>::zeros(n, 3);
            for b in 0..2 * N {
                let S = skew(&Vector3::new(x[3 * b], x[3 * b + 1], x[3 * b + 2]));
                for a in 0..3 {
                    for c in 0..3 {
                        W[(3 * b + a, c)] = S[(a, c)];
                    }
                }
            }
            let mut out = start.clone();
            add_mul_w(A.as_ref(), &x, 2 * N, alpha, &mut out, c0);
            let mut expected = start.clone();
            let AW = &A * &W;
            for j in 0..3 {
                for i in 0..rows {
                    expected[(i, c0 + j)] += alpha * AW[(i, j)];
                }
            }
            close(&out, &expected, "add_mul_w");
            // lambda_right: the theta_k column blocks times Lambda_k.
            let mut L = Mat::<f64>::identity(n, n);
            for k in 0..N {
                for a in 0..3 {
                    for b in 0..3 {
                        L[(6 * k + 3 + a, 6 * k + 3 + b)] = blocks.r[k][(a, b)];
                    }
                }
            }
            let mut out = A.clone();
            lambda_right(&blocks.r, &mut out);
            close(&out, &(&A * &L), "lambda_right");
            // lambda_t_left_cols: Lambda^T from the left on columns 1..4 of an n-row matrix.
            let B = Mat::from_fn(n, 5, |_, _| r());
            let mut out = B.clone();
            lambda_t_left_cols(&blocks.r, &mut out, 1..4);
            let LtB = L.transpose() * &B;
            let mut expected = B.clone();
            for j in 1..4 {
                for i in 0..n {
                    expected[(i, j)] = LtB[(i, j)];
                }
            }
            close(&out, &expected, "lambda_t_left_cols");
            // sub_mul_psi: out -= A Psi, Psi's rows [I, -r~_k] (u_k) and [0, Lambda_k] (theta_k).
            let r_loc: Vec<Vector3<f64>> = (0..N).map(|_| Vector3::new(r(), r(), r())).collect();
            let Psi = dense_psi(&r_loc, &blocks.r[..N], n);
            let start6 = Mat::from_fn(rows, 6, |_, _| r());
            let mut out = start6.clone();
            sub_mul_psi(A.as_ref(), &r_loc, &blocks.r, &mut out);
            close(&out, &(&start6 - &A * &Psi), "sub_mul_psi");
        }
        // rotate_matrix: Rbar K Rbar^T for a square K (n x n, not symmetric).
        let (N, m) = (2, 3);
        let n = 6 * N + m;
        let mut r = numbers(9);
        let K = Mat::from_fn(n, n, |_, _| r());
        let R = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.8, 0.5))
            .to_rotation_matrix()
            .into_inner();
        let mut Rbar = Mat::<f64>::identity(n, n);
        for b in 0..2 * N {
            for a in 0..3 {
                for c in 0..3 {
                    Rbar[(3 * b + a, 3 * b + c)] = R[(a, c)];
                }
            }
        }
        let mut out = Mat::from_fn(n, n, |_, _| f64::NAN);
        rotate_matrix(&R, N, &K, &mut out);
        let expected = &Rbar * &K * Rbar.transpose();
        for j in 0..n {
            for i in 0..n {
                assert!(
                    (out[(i, j)] - expected[(i, j)]).abs() < 1e-14,
                    "rotate_matrix ({i}, {j})"
                );
            }
        }
        // rotate_stiffness: Rbar (Dq Lambda + G) Rbar^T.
        let G = Mat::from_fn(n, n, |_, _| r());
        let Lambda: Vec<Matrix3<f64>> = (0..N).map(|_| Matrix3::from_fn(|_, _| r())).collect();
        let mut L = Mat::<f64>::identity(n, n);
        for k in 0..N {
            for a in 0..3 {
                for b in 0..3 {
                    L[(6 * k + 3 + a, 6 * k + 3 + b)] = Lambda[k][(a, b)];
                }
            }
        }
        let mut out = Mat::from_fn(n, n, |_, _| f64::NAN);
        rotate_stiffness(&R, &Lambda, &K, &G, &mut out);
        let expected = &Rbar * (&K * &L + &G) * Rbar.transpose();
        for j in 0..n {
            for i in 0..n {
                assert!(
                    (out[(i, j)] - expected[(i, j)]).abs() < 1e-14,
                    "rotate_stiffness ({i}, {j})"
                );
            }
        }
    }
}
