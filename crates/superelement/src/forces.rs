//! Generalised forces of the superelement in body axes, and their partial derivatives:
//! elastic (6.5), inertial in the two variants (6.4)/(6.6), gravity and damping.
//!
//! # Body-axis form
//!
//! Every force is $\mathbf f = \bar{\mathbf R}\boldsymbol\rho(\mathbf q^{jj}, \mathbf y, \mathbf a, \mathbf g^L)$
//! with body-axis interface velocities $\mathbf y = \bar{\mathbf R}^T\dot{\mathbf q}$, accelerations
//! $\mathbf a = \bar{\mathbf R}^T\ddot{\mathbf q}$ and gravity $\mathbf g^L = \mathbf R_j^T\mathbf g$:
//! the body-axis force depends on the configuration only through $\mathbf q^{jj}$. This module
//! computes $\boldsymbol\rho$ and $\partial\boldsymbol\rho/\partial\mathbf q^{jj}$,
//! $\partial\boldsymbol\rho/\partial\mathbf y$, $\partial\boldsymbol\rho/\partial\mathbf a$,
//! $\partial\boldsymbol\rho/\partial\mathbf g^L$; [`crate::tangent`] chains them into the
//! tangents in absolute coordinates.
//!
//! Notation as in [`crate::transform`]: $\boldsymbol\xi = \mathbf Y\mathbf y = [\mathbf V;\ \boldsymbol\Omega]$
//! (frame velocity, body axes), $\dot{\mathbf q}^{jj} = \mathbf B\mathbf y$, $\mathbf N_y$,
//! $\boldsymbol\Omega_q = \partial\boldsymbol\Omega/\partial\mathbf q^{jj} = (\mathbf Z_j\mathbf N_y)_r$.
//!
//! # Cost
//!
//! No product here is dense in $(6+n)^3$: $\mathbf X = [\mathbf 0; \mathbf I] + [\mathbf I_6; -\boldsymbol\Psi]\mathbf Z_j$
//! is the identity plus rank 6, $\boldsymbol\Psi$ and $\mathbf N_y$ are block-sparse, so every
//! product with $\mathbf X$, $\mathbf P$, $\mathbf T_j$ or $\mathbf B$ costs $O(n^2)$ times 6
//! ([`Kinematics`]`::mul_x`, `xt_mul`, `mul_t`, `tt_mul`).

#![allow(non_snake_case)]

use crate::body::{GeometricStiffness, Superelement};
use crate::mass::{add_mul3t, matvec, mul3, FfrForce, FfrScratch};
use crate::so3::{self, skew};
use crate::transform::{
    add_mul_blocks_at, col, copy_mat, gemm, lambda_right, lambda_t_left, lambda_t_left_cols, mul_blocks, sub_mul_psi,
    Blocks, Kinematics,
};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::Vector3;

/// What one evaluation forms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Level {
    /// The residual and its force parts only (`Superelement::residual_into`): no mass matrix,
    /// no $n\times n$ work beyond $\mathbf M_{CB}\ddot{\mathbf q}$, $\mathbf K_{CB}\mathbf q^{jj}$ and the
    /// inertia contractions.
    Forces,
    /// The forces and the mass matrix (`Superelement::forces_into`).
    Mass,
    /// The forces, the mass matrix and the tangents $\mathbf K_t$, $\mathbf C_t$.
    Tangents,
}

impl Level {
    pub fn tangents(self) -> bool {
        self == Level::Tangents
    }
    pub fn mass(self) -> bool {
        self != Level::Forces
    }
}

/// Velocity-level quantities shared by all forces of one evaluation.
#[derive(Clone, Debug)]
pub(crate) struct Motion {
    /// $\mathbf y = \bar{\mathbf R}^T\dot{\mathbf q}$.
    pub y: Vec<f64>,
    /// $\mathbf a = \bar{\mathbf R}^T\ddot{\mathbf q}$.
    pub a: Vec<f64>,
    /// $\mathbf g^L = \mathbf R_j^T\mathbf g$.
    pub g: Vector3<f64>,
    /// $\boldsymbol\xi = \mathbf Y\mathbf y$.
    pub xi: [f64; 6],
    /// $\dot{\mathbf q}^{jj} = \mathbf B\mathbf y$.
    pub c: Vec<f64>,
    /// $\mathbf N_y$.
    pub n_y: Blocks,
}

impl Motion {
    pub fn new(N: usize, n: usize) -> Self {
        Self {
            y: vec![0.0; n],
            a: vec![0.0; n],
            g: Vector3::zeros(),
            xi: [0.0; 6],
            c: vec![0.0; n],
            n_y: Blocks::zeros(N),
        }
    }

    pub fn update(&mut self, kin: &Kinematics, qd: &[f64], qdd: &[f64], g: &Vector3<f64>, tangents: bool) {
        let N = kin.n_interfaces();
        kin.to_body_into(qd, &mut self.y);
        kin.to_body_into(qdd, &mut self.a);
        self.g = kin.R_j.transpose() * g;
        // The sums in a local array (in registers, not through `self`), column slices of fixed
        // length.
        let mut xi = [0.0; 6];
        for (j, yj) in self.y.iter().enumerate() {
            let p: &[f64; 6] = kin.P.col_as_slice(j)[..6].try_into().expect("6 frame rows");
            for i in 0..6 {
                xi[i] += p[i] * yj;
            }
        }
        self.xi = xi;
        // c = Lambda y - Psi xi, block by block.
        let (xt, xr) = (
            Vector3::new(self.xi[0], self.xi[1], self.xi[2]),
            Vector3::new(self.xi[3], self.xi[4], self.xi[5]),
        );
        for k in 0..N {
            let yu = Vector3::new(self.y[6 * k], self.y[6 * k + 1], self.y[6 * k + 2]);
            let yt = Vector3::new(self.y[6 * k + 3], self.y[6 * k + 4], self.y[6 * k + 5]);
            let cu = yu - xt - xr.cross(&kin.r_loc[k]);
            let ct = kin.Lambda[k] * (yt - xr);
            self.c[6 * k..6 * k + 3].copy_from_slice(cu.as_slice());
            self.c[6 * k + 3..6 * k + 6].copy_from_slice(ct.as_slice());
        }
        self.c[6 * N..].copy_from_slice(&self.y[6 * N..]);
        if tangents {
            kin.fill_n_y(&self.y, &self.xi, &mut self.n_y);
        }
    }

    pub fn omega(&self) -> Vector3<f64> {
        Vector3::new(self.xi[3], self.xi[4], self.xi[5])
    }
}

/// Body-axis forces and their partials, accumulated over the force kinds.
#[derive(Clone, Debug)]
pub(crate) struct Local {
    pub rho_in: Vec<f64>,
    pub rho_el: Vec<f64>,
    pub rho_d: Vec<f64>,
    pub rho_g: Vec<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf a$: the body-axis mass matrix.
    pub M: Mat<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf q^{jj}$ of the residual $\boldsymbol\rho_{in} +
    /// \boldsymbol\rho_{el} + \boldsymbol\rho_d - \boldsymbol\rho_g$. Every term of the elastic,
    /// damping, gravity and `Exact` inertia forces has the left factor $\boldsymbol\Lambda^T$
    /// (from $\mathbf P^T = \boldsymbol\Lambda^T\mathbf X^T$): those forces accumulate their terms
    /// without it, and [`Local::apply_lambda_t`] applies it once to the sum (one pass over
    /// the matrix instead of one per term).
    pub Dq: Mat<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf y$ of the residual (same deferred $\boldsymbol\Lambda^T$ as `Dq`).
    pub Dy: Mat<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf g^L$ of the residual ($n\times3$); left at zero
    /// without gravity, where its only use, the term $\partial\boldsymbol\rho/\partial\mathbf g^L\,\tilde{\mathbf g}^L$
    /// of $\mathbf K_t$, vanishes anyway.
    pub Dg: Mat<f64>,
    /// $\sum\alpha_i\mathbf F_i$ of every term $\mathbf P^T\mathbf F_i$ of the residual: their
    /// $\partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj}|_{\mathbf F}$ is linear in $\mathbf F$, so one
    /// call of [`Kinematics`]`::add_d_pt` serves them all.
    pub F_sum: Vec<f64>,
    /// $[\mathbf E_q\ \mathbf E_y]$ ($(6+n)\times2n$): terms of `Dq` and `Dy` still to be multiplied by
    /// $\mathbf X^T$ (the elastic, gravity and `Exact` inertia terms, all of the form
    /// $\mathbf X^T\mathbf E$, with $\mathbf T_j^T\mathbf K = \mathbf X^T[\mathbf 0;\ \mathbf K]$):
    /// [`Local::apply_x_t`] multiplies them in one pass, one pair of products instead of one per term.
    /// With tangents the same pass takes two more blocks after these $2n$ columns (`extra` of
    /// them in use, in the order they were added): $\mathbf M_{ffr}\mathbf X$ of the `Exact` mass
    /// $\boldsymbol\Lambda^T\mathbf X^T(\mathbf M_{ffr}\mathbf X)\boldsymbol\Lambda$ (`m_col`, $n$ columns) and
    /// $[\mathbf 0;\ \mathbf S_t^T]$ of the gravity partial $-\boldsymbol\Lambda^T\mathbf T_j^T\mathbf S_t^T$ in `Dg`
    /// (`g_col`, 3 columns). Width $3n + 3$.
    pub XE: Mat<f64>,
    pub extra: usize,
    pub m_col: Option<usize>,
    pub g_col: Option<usize>,
}

impl Local {
    pub fn new(n: usize) -> Self {
        Self {
            rho_in: vec![0.0; n],
            rho_el: vec![0.0; n],
            rho_d: vec![0.0; n],
            rho_g: vec![0.0; n],
            M: Mat::zeros(n, n),
            Dq: Mat::zeros(n, n),
            Dy: Mat::zeros(n, n),
            Dg: Mat::zeros(n, 3),
            F_sum: vec![0.0; 6 + n],
            XE: Mat::zeros(6 + n, 3 * n + 3),
            extra: 0,
            m_col: None,
            g_col: None,
        }
    }

    /// `Dq` += $\mathbf X^T\mathbf E_q$, `Dy` += $\mathbf X^T\mathbf E_y$ and, when their blocks are
    /// in use, `M` $= \boldsymbol\Lambda^T\mathbf X^T(\mathbf M_{ffr}\mathbf X)\boldsymbol\Lambda$ and `Dg`
    /// $\mathrel{-}= \boldsymbol\Lambda^T\mathbf T_j^T\mathbf S_t^T$ (`XE`); `tmp` is $6\times(3n+3)$, `out`
    /// $n\times(3n+3)$.
    pub fn apply_x_t(&mut self, kin: &Kinematics, tmp: &mut Mat<f64>, out: &mut Mat<f64>) {
        let n = kin.n();
        let width = 2 * n + self.extra;
        kin.xt_mul(
            self.XE.as_ref().subcols(0, width),
            tmp.as_mut().subcols_mut(0, width),
            out.as_mut().subcols_mut(0, width),
        );
        for j in 0..n {
            add_to(self.Dq.col_as_slice_mut(j), out.col_as_slice(j), 1.0);
            add_to(self.Dy.col_as_slice_mut(j), out.col_as_slice(n + j), 1.0);
        }
        lambda_t_left_cols(&kin.Lambda, out, 2 * n..width);
        if let Some(c) = self.m_col {
            for j in 0..n {
                self.M.col_as_slice_mut(j).copy_from_slice(out.col_as_slice(c + j));
            }
            lambda_right(&kin.Lambda, &mut self.M);
        }
        if let Some(c) = self.g_col {
            for i in 0..3 {
                add_to(self.Dg.col_as_slice_mut(i), out.col_as_slice(c + i), -1.0);
            }
        }
    }

    /// The next `k` free columns of `XE` after $[\mathbf E_q\ \mathbf E_y]$ (their docs): the
    /// index of the first.
    fn take_columns(&mut self, n: usize, k: usize) -> usize {
        let c = 2 * n + self.extra;
        self.extra += k;
        c
    }

    /// Applies the deferred left factor $\boldsymbol\Lambda^T$ to `Dq` and `Dy` (their docs).
    pub fn apply_lambda_t(&mut self, Lambda: &[nalgebra::Matrix3<f64>]) {
        lambda_t_left(Lambda, &mut self.Dq);
        lambda_t_left(Lambda, &mut self.Dy);
    }

    pub fn clear(&mut self, tangents: bool) {
        for v in [&mut self.rho_in, &mut self.rho_el, &mut self.rho_d, &mut self.rho_g] {
            v.iter_mut().for_each(|x| *x = 0.0);
        }
        if tangents {
            self.F_sum.fill(0.0);
            self.Dq.fill(0.0);
            self.Dy.fill(0.0);
            self.Dg.fill(0.0);
            // The extra blocks are written in full when taken.
            let n = self.Dq.ncols();
            for j in 0..2 * n {
                self.XE.col_as_slice_mut(j).fill(0.0);
            }
            self.extra = 0;
            self.m_col = None;
            self.g_col = None;
        }
    }
}

/// Buffers of one evaluation, sized once for a body ([`crate::Workspace`] holds it).
#[derive(Clone, Debug)]
pub(crate) struct Scratch {
    pub ffr: FfrForce,
    pub ffr_scratch: FfrScratch,
    /// $(6+n)\times n$.
    pub MX: Mat<f64>,
    pub FX: Mat<f64>,
    /// $(6+n)\times6$.
    pub t6: Mat<f64>,
    /// $n\times6$, $6\times n$, $(6+n)\times3$.
    pub n6: Mat<f64>,
    pub six_n: Mat<f64>,
    /// $6\times(3n+3)$ and $n\times(3n+3)$ for [`Local::apply_x_t`].
    pub six_2n: Mat<f64>,
    pub n_2n: Mat<f64>,
    /// $n\times n$.
    pub nn1: Mat<f64>,
    pub nn2: Mat<f64>,
    /// $n\times3$, $3\times n$.
    pub n3a: Mat<f64>,
    pub n3b: Mat<f64>,
    pub n3c: Mat<f64>,
    pub three_n: Mat<f64>,
    pub blocks: Blocks,
    pub blocks2: Blocks,
    /// Vectors of length $n$ and $6+n$.
    pub v1: Vec<f64>,
    pub v2: Vec<f64>,
    pub F6: Vec<f64>,
    pub nu: Vec<f64>,
    pub nu_dot: Vec<f64>,
    /// Geometric stiffening ([`GeometricScratch`]; empty for a body without $\mathbf G$).
    pub geometric: GeometricScratch,
}

impl Scratch {
    /// Buffers for a body with `N` interfaces and `n` coordinates; `geometric`: the body has
    /// a geometric stiffness (else its buffers are empty).
    pub fn new(N: usize, n: usize, geometric: bool) -> Self {
        let m6 = || Mat::zeros(6 + n, n);
        let ng = if geometric { n } else { 0 };
        Self {
            ffr: FfrForce::zeros(n),
            ffr_scratch: FfrScratch::new(n),
            MX: m6(),
            FX: m6(),
            t6: Mat::zeros(6 + n, 6),
            n6: Mat::zeros(n, 6),
            six_n: Mat::zeros(6, n),
            six_2n: Mat::zeros(6, 3 * n + 3),
            n_2n: Mat::zeros(n, 3 * n + 3),
            nn1: Mat::zeros(n, n),
            nn2: Mat::zeros(n, n),
            n3a: Mat::zeros(n, 3),
            n3b: Mat::zeros(n, 3),
            n3c: Mat::zeros(n, 3),
            three_n: Mat::zeros(3, n),
            blocks: Blocks::zeros(N),
            blocks2: Blocks::zeros(N),
            v1: vec![0.0; n],
            v2: vec![0.0; n],
            F6: vec![0.0; 6 + n],
            nu: vec![0.0; 6 + n],
            nu_dot: vec![0.0; 6 + n],
            geometric: GeometricScratch::new(ng),
        }
    }
}

/// Buffers of [`GeometricStiffness`]`::gradient_into` for $n$ coordinates (all empty for $n = 0$).
#[derive(Clone, Debug)]
pub(crate) struct GeometricScratch {
    /// $\mathbf C = [\mathbf G_0\mathbf q, \dots, \mathbf G_{n-1}\mathbf q]$ and $\mathbf S = \sum_k w_k\mathbf G_k$,
    /// column-major ($n^2$).
    pub C: Vec<f64>,
    pub S: Vec<f64>,
    /// In: $\mathbf K_{CB}$; out: $\mathbf K_{CB} + \mathbf H_G$ ($n\times n$).
    pub K_g: Mat<f64>,
    /// $n\times n$ scratch.
    pub T1: Mat<f64>,
    pub T2: Mat<f64>,
    /// $\mathbf b$, $\mathbf p$, $\mathbf w = \mathbf q + \mathbf p$, $\mathbf g_G$ ($n$).
    pub b: Vec<f64>,
    pub p: Vec<f64>,
    pub w: Vec<f64>,
    pub g_G: Vec<f64>,
}

impl GeometricScratch {
    pub fn new(n: usize) -> Self {
        Self {
            C: vec![0.0; n * n],
            S: vec![0.0; n * n],
            K_g: Mat::zeros(n, n),
            T1: Mat::zeros(n, n),
            T2: Mat::zeros(n, n),
            b: vec![0.0; n],
            p: vec![0.0; n],
            w: vec![0.0; n],
            g_G: vec![0.0; n],
        }
    }
}

impl GeometricStiffness {
    /// The gradient $\mathbf g_G = \partial(U_3 + U_4)/\partial\mathbf q$ of the geometric strain energy
    /// ([`GeometricStiffness`]) into `s.g_G` and, with `hessian`, its Hessian $\mathbf H_G$ added to
    /// `s.K_g`. With $\mathbf C = [\mathbf G_0\mathbf q, \dots, \mathbf G_{n-1}\mathbf q]$, $\mathbf b = \tfrac12\mathbf C^T\mathbf q$,
    /// $\mathbf p = \mathbf F\mathbf b$ and $\mathbf w = \mathbf q + \mathbf p$ (all left in `s`):
    ///
    /// $$\mathbf g_G = \mathbf b + \mathbf C\mathbf w,\qquad
    /// \mathbf H_G = \mathbf C + \mathbf C^T + \sum_k w_k\mathbf G_k + \mathbf C\mathbf F\mathbf C^T.$$
    ///
    /// Cost: two column-major matrix-vector products with the $n^3$ entries of $\mathbf G$ (`stack_t`
    /// for $\mathbf C$, `stack` for $\sum_k w_k\mathbf G_k$; only the first without `hessian`) and two
    /// $n\times n$ products; no allocation.
    ///
    /// # Derivation
    /// By the symmetry of each $\mathbf G_k$, $(\mathbf G_k\mathbf q)_m = C_{mk}$, so
    /// $U_3 = \tfrac12\mathbf q^T\mathbf C\mathbf q$ and $\partial U_3/\partial q_m = \tfrac12\mathbf q^T\mathbf G_m\mathbf q +
    /// \sum_k q_k(\mathbf G_k\mathbf q)_m = b_m + (\mathbf C\mathbf q)_m$, with Hessian
    /// $(\mathbf G_m\mathbf q)_n + (\mathbf G_n\mathbf q)_m + (\sum_k q_k\mathbf G_k)_{mn}$. For
    /// $U_4 = \tfrac12\mathbf b^T\mathbf F\mathbf b$: $\partial\mathbf b/\partial\mathbf q = \mathbf C^T$, so the gradient is
    /// $\mathbf C\mathbf F\mathbf b = \mathbf C\mathbf p$ and the Hessian $\mathbf C\mathbf F\mathbf C^T + \sum_m p_m\mathbf G_m$.
    /// Tested by `tests/unit/geometric.rs::elastic_force_is_the_gradient_of_the_strain_energy` and
    /// `::tangents_match_fd`.
    pub(crate) fn gradient_into(&self, q: &[f64], s: &mut GeometricScratch, hessian: bool) {
        let GeometricScratch {
            C,
            S,
            K_g: K,
            T1,
            T2,
            b,
            p,
            w,
            g_G: g,
        } = s;
        let n = q.len();
        if self.compressed {
            self.gradient_compressed(q, s, hessian);
            return;
        }
        let nn = n * n;
        // vec C: entry j + n m is (G_m q)_j = sum_i (G_m)_ji q_i, a product with `stack_t`.
        matmul(
            MatMut::from_column_major_slice_mut(C, nn, 1),
            Accum::Replace,
            MatRef::from_column_major_slice(&self.stack_t, nn, n),
            MatRef::from_column_major_slice(q, n, 1),
            1.0,
            Par::Seq,
        );
        for (m, bm) in b.iter_mut().enumerate() {
            *bm = 0.5 * C[n * m..n * (m + 1)].iter().zip(q).map(|(c, x)| c * x).sum::<f64>();
        }
        matvec(&self.F, b, p);
        for ((wi, qi), pi) in w.iter_mut().zip(q).zip(p.iter()) {
            *wi = qi + pi;
        }
        // g = b + C w.
        g.copy_from_slice(b);
        for (m, wm) in w.iter().enumerate() {
            for (gi, c) in g.iter_mut().zip(&C[n * m..n * (m + 1)]) {
                *gi += c * wm;
            }
        }
        if hessian {
            // vec S = [vec G_0 ... vec G_{n-1}] w = vec(sum_k w_k G_k).
            matmul(
                MatMut::from_column_major_slice_mut(S, nn, 1),
                Accum::Replace,
                MatRef::from_column_major_slice(&self.stack, nn, n),
                MatRef::from_column_major_slice(w, n, 1),
                1.0,
                Par::Seq,
            );
            for j in 0..n {
                let col = K.col_as_slice_mut(j);
                for (i, k) in col.iter_mut().enumerate() {
                    *k += S[i + n * j] + C[i + n * j] + C[j + n * i];
                }
            }
            // C F C^T = C (F C^T).
            let Cm = MatRef::from_column_major_slice(C.as_slice(), n, n);
            gemm(T1, self.F.as_ref(), Cm.transpose(), 1.0, Accum::Replace);
            gemm(T2, Cm, T1.as_ref(), 1.0, Accum::Replace);
            add_scaled(K, T2, 1.0);
        }
    }

    /// [`Self::gradient_into`] through the nonzero $\mathbf G_k$ only, each on its nonzero rows and
    /// columns ([`Compressed`](crate::compressed::Compressed)): the columns $\mathbf C_m$, the entries $b_m$ of the zero
    /// $\mathbf G_m$ are zero, so $\mathbf p = \sum_{m \in nz}\mathbf F_{\cdot m}b_m$,
    /// $\mathbf g_G = \mathbf b + \sum_{m \in nz}\mathbf C_m w_m$ and $\mathbf C\mathbf F\mathbf C^T =
    /// \sum_{l \in nz}\mathbf D_l\mathbf C_l^T$ with $\mathbf D_l = \sum_{m \in nz}\mathbf C_m F_{ml}$.
    /// Equal to the dense path to round-off (`tests/unit/compressed.rs`).
    fn gradient_compressed(&self, q: &[f64], s: &mut GeometricScratch, hessian: bool) {
        let GeometricScratch {
            C,
            K_g: K,
            T1,
            b,
            p,
            w,
            g_G: g,
            ..
        } = s;
        let n = q.len();
        b.fill(0.0);
        for (m, Gm) in &self.nonzero {
            let Cm = &mut C[n * m..n * (m + 1)];
            Gm.mul_into(q, Cm);
            b[*m] = 0.5 * Cm.iter().zip(q).map(|(c, x)| c * x).sum::<f64>();
        }
        p.fill(0.0);
        for (m, _) in &self.nonzero {
            add_to(p, self.F.col_as_slice(*m), b[*m]);
        }
        for ((wi, qi), pi) in w.iter_mut().zip(q).zip(p.iter()) {
            *wi = qi + pi;
        }
        g.copy_from_slice(b);
        for (m, _) in &self.nonzero {
            add_to(g, &C[n * m..n * (m + 1)], w[*m]);
        }
        if !hessian {
            return;
        }
        for (k, Gk) in &self.nonzero {
            Gk.scatter_add(w[*k], K);
        }
        // C + C^T on the nonzero columns m and rows m; D_l = sum_m C_m F_ml in T1's column l.
        for (m, _) in &self.nonzero {
            let Cm = &C[n * m..n * (m + 1)];
            add_to(K.col_as_slice_mut(*m), Cm, 1.0);
            for (j, c) in Cm.iter().enumerate() {
                K[(*m, j)] += c;
            }
        }
        for (l, _) in &self.nonzero {
            let D = T1.col_as_slice_mut(*l);
            D.fill(0.0);
            for (m, _) in &self.nonzero {
                add_to(D, &C[n * m..n * (m + 1)], self.F[(*m, *l)]);
            }
        }
        for j in 0..n {
            let Kj = K.col_as_slice_mut(j);
            for (l, _) in &self.nonzero {
                let c = C[n * l + j];
                if c != 0.0 {
                    add_to(Kj, T1.col_as_slice(*l), c);
                }
            }
        }
    }

    /// $U_3 + U_4$ at $\mathbf q$ ([`GeometricStiffness`]); allocates (energy checks, sensors).
    pub(crate) fn energy(&self, q: &[f64]) -> f64 {
        let mut s = GeometricScratch::new(q.len());
        self.gradient_into(q, &mut s, false);
        let (b, p) = (&s.b, &s.p);
        // U_3 = (1/2) q^T C q = q . b ; U_4 = (1/2) b . p.
        q.iter().zip(b).map(|(x, y)| x * y).sum::<f64>() + 0.5 * b.iter().zip(p).map(|(x, y)| x * y).sum::<f64>()
    }
}

/// `out += alpha * x` for vectors.
fn add_to(out: &mut [f64], x: &[f64], alpha: f64) {
    for (o, v) in out.iter_mut().zip(x) {
        *o += alpha * v;
    }
}

/// `out += alpha * A` for matrices of the same shape.
fn add_scaled(out: &mut Mat<f64>, A: &Mat<f64>, alpha: f64) {
    for j in 0..A.ncols() {
        for (o, a) in out.col_as_slice_mut(j).iter_mut().zip(A.col_as_slice(j)) {
            *o += alpha * a;
        }
    }
}

/// $\mathbf W(\mathbf x)$ into `out` ($n\times3$): the stack of $\tilde{\mathbf x}_b$ over the $2N$
/// interface 3-blocks, zero eta rows.
pub(crate) fn w_into(x: &[f64], N: usize, out: &mut Mat<f64>) {
    out.fill(0.0);
    for b in 0..2 * N {
        let S = skew(&Vector3::new(x[3 * b], x[3 * b + 1], x[3 * b + 2]));
        for i in 0..3 {
            for j in 0..3 {
                out[(3 * b + i, j)] = S[(i, j)];
            }
        }
    }
}

impl Superelement {
    /// Elastic force (6.5) in body axes, $\boldsymbol\rho_{el} = \mathbf B^T\mathbf f$ with the local
    /// elastic force $\mathbf f = \mathbf K_{CB}\mathbf q^{jj}$, plus $\mathbf g_G$ with geometric stiffening
    /// ($\mathbf B = \mathbf T_j\boldsymbol\Lambda$; the AIC-FFR paper's $\mathbf T_j^T\mathbf K_{CB}\mathbf q^{jj}$ with
    /// the exact rotation factor), so $\mathbf f_{el} = \bar{\mathbf R}\boldsymbol\Lambda^T\mathbf T_j^T\mathbf f$.
    ///
    /// # Derivation
    /// $\mathbf f_{el}$ is the gradient of the strain energy $U(\mathbf q^{jj})$ in the absolute
    /// coordinates, because $\delta\mathbf q^{jj} = \mathbf B\bar{\mathbf R}^T\delta\mathbf q$ exactly
    /// ([`crate::transform`]): $\mathbf f = \partial U/\partial\mathbf q^{jj}$. Its derivative:
    /// $\partial\boldsymbol\rho_{el}/\partial\mathbf q^{jj} = \partial(\mathbf P^T[\mathbf 0;\mathbf f])/\partial\mathbf q^{jj}
    /// + \mathbf B^T\,\partial\mathbf f/\partial\mathbf q^{jj}$ ([`Kinematics`]`::add_d_pt` for the first term).
    ///
    /// * Linear elastic field: $U = \tfrac12\mathbf q^{jjT}\mathbf K_{CB}\mathbf q^{jj}$, $\mathbf f = \mathbf K_{CB}\mathbf q^{jj}$,
    ///   $\partial\mathbf f/\partial\mathbf q^{jj} = \mathbf K_{CB}$.
    /// * Geometric stiffening ([`GeometricStiffness`]): $U$ gains $U_3 + U_4$, so
    ///   $\mathbf f = \mathbf K_{CB}\mathbf q^{jj} + \mathbf g_G$ and $\partial\mathbf f/\partial\mathbf q^{jj} =
    ///   \mathbf K_{CB} + \mathbf H_G$ ([`GeometricStiffness`]`::gradient_into`). The projector terms are
    ///   unchanged: they only see $\mathbf f$.
    ///
    /// Tested by `tests/unit/fd_tangent.rs::elastic_tangent_matches_fd`, `tests/unit/invariance.rs`,
    /// `tests/unit/energy.rs::gravity_is_the_gradient_of_its_potential` and, with $\mathbf G$,
    /// `tests/unit/geometric.rs`.
    pub(crate) fn elastic(&self, kin: &Kinematics, loc: &mut Local, w: &mut Scratch, tangents: bool) {
        matvec(&self.K_CB, &kin.q_jj, &mut w.v1);
        if let Some(G) = &self.geometric {
            if tangents {
                copy_mat(&mut w.geometric.K_g, self.K_CB.as_ref());
            }
            G.gradient_into(&kin.q_jj, &mut w.geometric, tangents);
            add_to(&mut w.v1, &w.geometric.g_G, 1.0);
        }
        w.F6[..6].fill(0.0);
        w.F6[6..].copy_from_slice(&w.v1);
        kin.pt_vec(&w.F6, &mut loc.rho_el);
        if tangents {
            add_to(&mut loc.F_sum, &w.F6, 1.0);
            // T^T df/dq_jj; Lambda^T comes once for all terms (`Local::Dq`).
            let K = if self.geometric.is_some() {
                w.geometric.K_g.as_ref()
            } else {
                self.K_CB.as_ref()
            };
            for j in 0..self.n {
                add_to(&mut loc.XE.col_as_slice_mut(j)[6..], col(K, j), 1.0);
            }
        }
    }

    /// Damping force $\boldsymbol\rho_d = \mathbf B^T\mathbf D\,\dot{\mathbf q}^{jj}$, $\dot{\mathbf q}^{jj} =
    /// \mathbf B\mathbf y$ (the elastic velocity, (5.5)); [`crate::Damping`] defines $\mathbf D$.
    ///
    /// # Derivation
    /// The Rayleigh dissipation function $\tfrac12\dot{\mathbf q}^{jjT}\mathbf D\dot{\mathbf q}^{jj}$
    /// differentiated by $\dot{\mathbf q}$. $\partial/\partial\mathbf y = \mathbf B^T\mathbf D\mathbf B$;
    /// $\partial/\partial\mathbf q^{jj} = \partial(\mathbf P^T[\mathbf 0;\mathbf D\dot{\mathbf q}^{jj}])/\partial\mathbf q^{jj} +
    /// \mathbf B^T\mathbf D\,\mathbf T_j\mathbf N_y$ (since $D(\mathbf B\mathbf y) = \mathbf T_j\mathbf N_y$).
    /// Tested by `tests/unit/fd_tangent.rs::damping_tangents_match_fd`.
    pub(crate) fn damping_force(
        &self,
        kin: &Kinematics,
        mo: &Motion,
        loc: &mut Local,
        w: &mut Scratch,
        tangents: bool,
    ) {
        if !self.damped {
            return;
        }
        matvec(&self.D, &mo.c, &mut w.v1);
        w.F6[..6].fill(0.0);
        w.F6[6..].copy_from_slice(&w.v1);
        kin.pt_vec(&w.F6, &mut loc.rho_d);
        if tangents {
            add_to(&mut loc.F_sum, &w.F6, 1.0);
            // S = T^T D T (Lambda^T comes once for all terms, `Local::Dq`).
            kin.mul_t(self.D.as_ref(), &mut w.n6, &mut w.nn1);
            kin.tt_mul(w.nn1.as_ref(), &mut w.six_n, &mut w.nn2, Accum::Replace);
            mul_blocks(w.nn2.as_ref(), &mo.n_y, &mut loc.Dq, Accum::Add);
            lambda_right(&kin.Lambda, &mut w.nn2);
            add_scaled(&mut loc.Dy, &w.nn2, 1.0);
        }
    }

    /// Gravity: the body force of the mass distribution in a uniform field $\mathbf g$,
    /// $\boldsymbol\rho_g = \mathbf P^T\mathbf Q_g$, $\mathbf Q_g = [m\mathbf g^L;\ \mathbf s\times\mathbf g^L;\ \mathbf S_t^T\mathbf g^L]$,
    /// $\mathbf s = m\mathbf d + \mathbf S_t\mathbf q^{jj}$. Used by both inertia variants.
    ///
    /// # Derivation
    /// The potential is $V = -\mathbf g\cdot(m\mathbf r_j + \mathbf R_j\mathbf s)$ (the deformed centre
    /// of mass is $\mathbf r_j + \mathbf R_j\mathbf s/m$). Its variation in the FFR coordinates is
    /// $-\mathbf Q_g^T[\delta\mathbf r_j^L;\ \delta\boldsymbol\Pi;\ \delta\mathbf q^{jj}]$, transformed by
    /// $\mathbf P$ ((5.6) in body axes). Partials: $\partial\mathbf Q_g/\partial\mathbf q^{jj} =
    /// [\mathbf 0;\ -\tilde{\mathbf g}^L\mathbf S_t;\ \mathbf 0]$, $\partial\mathbf Q_g/\partial\mathbf g^L =
    /// [m\mathbf I;\ \tilde{\mathbf s};\ \mathbf S_t^T]$. Tested by `tests/unit/fd_tangent.rs::gravity_tangent_matches_fd`
    /// and `tests/unit/energy.rs::gravity_is_the_gradient_of_its_potential`.
    pub(crate) fn gravity(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, w: &mut Scratch, tangents: bool) {
        let n = self.n;
        let I = &self.inertia;
        let g = mo.g;
        if g == Vector3::zeros() {
            // Zero force and zero derivatives: the partial in g itself, `Local::Dg`, only enters
            // K_t as Dg g~ (`tangent.rs`), which vanishes too, so it stays at zero.
            return;
        }
        let s = I.d * I.mass + mul3(&I.S_t, &kin.q_jj);
        let Q = &mut w.F6;
        let sg = s.cross(&g);
        for i in 0..3 {
            Q[i] = I.mass * g[i];
            Q[3 + i] = sg[i];
        }
        Q[6..].fill(0.0);
        add_mul3t(&mut Q[6..], &I.S_t, &g, 1.0);
        kin.pt_vec(Q, &mut loc.rho_g);
        if tangents {
            add_to(&mut loc.F_sum, &w.F6, -1.0);
            // - Y_r^T (-g~ S_t) = Lambda^T Z_r^T g~ S_t (Lambda^T comes once for all terms, `Local::Dq`).
            let gt = skew(&g);
            for j in 0..n {
                let v = gt * Vector3::new(I.S_t[(0, j)], I.S_t[(1, j)], I.S_t[(2, j)]);
                for i in 0..3 {
                    w.three_n[(i, j)] = v[i];
                }
            }
            // Z_r^T g~ S_t = X^T [0; g~ S_t; 0]: rows 3..6 of E_q.
            for j in 0..n {
                let e = loc.XE.col_as_slice_mut(j);
                for i in 0..3 {
                    e[3 + i] += w.three_n[(i, j)];
                }
            }
            self.gravity_dg(kin, loc, &s);
        }
    }

    /// $\partial\boldsymbol\rho/\partial\mathbf g^L$ of the residual: $-\mathbf P^T[m\mathbf I;\ \tilde{\mathbf s};\ \mathbf S_t^T]$.
    fn gravity_dg(&self, kin: &Kinematics, loc: &mut Local, s: &Vector3<f64>) {
        let n = self.n;
        let I = &self.inertia;
        let Y = kin.Y();
        let st = skew(s);
        for j in 0..n {
            let yt = Vector3::new(Y[(0, j)], Y[(1, j)], Y[(2, j)]);
            let yr = Vector3::new(Y[(3, j)], Y[(4, j)], Y[(5, j)]);
            let v = yt * I.mass + st.transpose() * yr;
            for i in 0..3 {
                loc.Dg[(j, i)] -= v[i];
            }
        }
        // - B^T S_t^T = - Lambda^T T^T S_t^T = - Lambda^T X^T [0; S_t^T], in `Local::apply_x_t`.
        let c = loc.take_columns(n, 3);
        loc.g_col = Some(c);
        for i in 0..3 {
            let e = loc.XE.col_as_slice_mut(c + i);
            e[..6].fill(0.0);
            for j in 0..n {
                e[6 + j] = I.S_t[(i, j)];
            }
        }
    }

    /// Inertia force of the `Exact` variant: $\boldsymbol\rho_{in} = \mathbf P^T\mathbf F(\mathbf q^{jj},
    /// \boldsymbol\nu, \dot{\boldsymbol\nu})$ ([`crate::mass`]), $\boldsymbol\nu = \mathbf P\mathbf y$,
    /// $\dot{\boldsymbol\nu} = \mathbf P\dot{\mathbf y} + \mathbf X\mathbf N_y\dot{\mathbf q}^{jj}$, and the body-axis
    /// mass $\mathbf P^T\mathbf M_{ffr}\mathbf P$. In inertial axes this is (6.4):
    /// $\mathbf A^T\mathbf M_{ffr}\mathbf A\ddot{\mathbf q} + \mathbf A^T(\mathbf M_{ffr}\dot{\mathbf A}\dot{\mathbf q} + \mathbf h)$.
    ///
    /// # Derivation
    /// $\dot{\mathbf y} = \mathbf a + \mathbf W(\mathbf y)\boldsymbol\Omega$ (the body axes turn with
    /// $\boldsymbol\Omega$; $\mathbf W$ stacks $\tilde{\mathbf y}_b$) and $\frac{d}{dt}\mathbf P =
    /// D\mathbf P[\dot{\mathbf q}^{jj}]$, so $\dot{\boldsymbol\nu} = \mathbf P\dot{\mathbf y} + \mathbf X\mathbf N_y\dot{\mathbf q}^{jj}$
    /// is $\mathbf A\ddot{\mathbf q} + \dot{\mathbf A}\dot{\mathbf q}$ of (5.7) in body axes. The partials,
    /// with $\mathbf s = \mathbf Z_j\mathbf N_y\dot{\mathbf q}^{jj}$, $\mathbf c = \dot{\mathbf q}^{jj}$ and
    /// $\mathbf U$ the $n\times3$ stack of $\tilde{\mathbf c}_{u_k}$ and $-D\mathbf J_l^{-1}(\boldsymbol\theta_k)[\mathbf c_{\theta_k}]$:
    ///
    /// * $\partial\boldsymbol\rho/\partial\mathbf q^{jj} = \partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj}|_{\mathbf F} +
    ///   \mathbf P^T[\mathbf F_q + \mathbf F_\nu\mathbf X\mathbf N_y + \mathbf M_{ffr}\boldsymbol\Xi]$,
    ///   $\boldsymbol\Xi = \mathbf X(\mathbf N_{\dot y} - \tilde{\mathbf N}_s + \mathbf Q_c) + \mathbf X(\mathbf U +
    ///   \boldsymbol\Lambda\mathbf W(\mathbf y))\boldsymbol\Omega_q + \mathbf X\mathbf N_y\mathbf T_j\mathbf N_y$, where
    ///   $\mathbf Q_c$ has the blocks $\mathbf Q(\boldsymbol\theta_k, \boldsymbol\zeta_{k,r}, \mathbf c_{\theta_k})$
    ///   ([`so3::left_jacobian_inv_second`]) on $\boldsymbol\theta_k$: the second derivative of
    ///   $\mathbf P\mathbf y$ along $\dot{\mathbf q}^{jj}$;
    /// * $\partial\boldsymbol\rho/\partial\mathbf y = \mathbf P^T[\mathbf F_\nu\mathbf P + \mathbf M_{ffr}\boldsymbol\Sigma]$,
    ///   $\boldsymbol\Sigma = -\mathbf P\,\mathrm{diag}(\tilde{\boldsymbol\Omega}) + \mathbf X\,\mathrm{diag}_\theta(D\mathbf J_l^{-1}[\mathbf c_{\theta_k}]) +
    ///   \mathbf X(\mathbf U + \boldsymbol\Lambda\mathbf W(\mathbf y))\mathbf Y_r + \mathbf X\mathbf N_y\mathbf B$.
    ///
    /// All products go through $\mathbf M_{ffr}\mathbf X$ and $\mathbf F_\nu\mathbf X$ (module docs, Cost).
    /// At [`Level::Forces`] only $\boldsymbol\rho_{in} = \mathbf P^T\mathbf F$ is formed
    /// ([`crate::mass::FfrInertia::force_only_into`]): no $\mathbf M_{ffr}$, no body-axis mass.
    /// Tested by `tests/unit/fd_tangent.rs::tangents_match_fd` and `::inertia_tangents_match_fd`
    /// (Exact, every frame choice) and `tests/unit/energy.rs` (power balance, rigid kinetic energy).
    pub(crate) fn exact_inertia(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, w: &mut Scratch, level: Level) {
        let tangents = level.tangents();
        let n = self.n;
        let N = self.n_interfaces;
        let Om = mo.omega();
        // ydot = a + W(y) Om  (in v2); Lambda ydot (in v1).
        for b in 0..2 * N {
            let yb = Vector3::new(mo.y[3 * b], mo.y[3 * b + 1], mo.y[3 * b + 2]);
            let v = yb.cross(&Om);
            for i in 0..3 {
                w.v2[3 * b + i] = mo.a[3 * b + i] + v[i];
            }
        }
        w.v2[6 * N..].copy_from_slice(&mo.a[6 * N..]);
        // nu = [xi; c]; nu_dot = P ydot + X (N_y c).
        w.nu[..6].copy_from_slice(&mo.xi);
        w.nu[6..].copy_from_slice(&mo.c);
        let mut xi_yd = [0.0; 6];
        for (j, yj) in w.v2.iter().enumerate() {
            let p: &[f64; 6] = kin.P.col_as_slice(j)[..6].try_into().expect("6 frame rows");
            for i in 0..6 {
                xi_yd[i] += p[i] * yj;
            }
        }
        // N_y c and its Z-image s.
        let mut s = [0.0; 6];
        let Ot = skew(&Om);
        {
            let th = |k| crate::local_coordinates::theta_of(&kin.q_jj, k);
            let c = &mo.c;
            for k in 0..N {
                let cu = Vector3::new(c[6 * k], c[6 * k + 1], c[6 * k + 2]);
                let ct = Vector3::new(c[6 * k + 3], c[6 * k + 4], c[6 * k + 5]);
                let yr = Vector3::new(mo.y[6 * k + 3], mo.y[6 * k + 4], mo.y[6 * k + 5]);
                let nu = -(Ot * cu);
                let nr = so3::left_jacobian_inv_derivative(&th(k), &(yr - Om)) * ct;
                w.v1[6 * k..6 * k + 3].copy_from_slice(nu.as_slice());
                w.v1[6 * k + 3..6 * k + 6].copy_from_slice(nr.as_slice());
            }
            w.v1[6 * N..].fill(0.0);
        }
        for (j, vj) in w.v1[..6 * N].iter().enumerate() {
            let z: &[f64; 6] = kin.X.col_as_slice(j)[..6].try_into().expect("6 frame rows");
            for i in 0..6 {
                s[i] += z[i] * vj;
            }
        }
        // nu_dot: top = xi_yd + s ; bottom = Lambda ydot - Psi xi_yd + (N_y c) - Psi s.
        let (t6, r6) = (
            Vector3::new(xi_yd[0] + s[0], xi_yd[1] + s[1], xi_yd[2] + s[2]),
            Vector3::new(xi_yd[3] + s[3], xi_yd[4] + s[4], xi_yd[5] + s[5]),
        );
        w.nu_dot[..6].copy_from_slice(&[t6.x, t6.y, t6.z, r6.x, r6.y, r6.z]);
        for k in 0..N {
            let yu = Vector3::new(w.v2[6 * k], w.v2[6 * k + 1], w.v2[6 * k + 2]);
            let yt = kin.Lambda[k] * Vector3::new(w.v2[6 * k + 3], w.v2[6 * k + 4], w.v2[6 * k + 5]);
            let bu = yu - t6 - r6.cross(&kin.r_loc[k]);
            let bt = yt - kin.Lambda[k] * r6;
            for i in 0..3 {
                w.nu_dot[6 + 6 * k + i] = bu[i] + w.v1[6 * k + i];
                w.nu_dot[6 + 6 * k + 3 + i] = bt[i] + w.v1[6 * k + 3 + i];
            }
        }
        w.nu_dot[6 + 6 * N..].copy_from_slice(&w.v2[6 * N..]);

        if !level.mass() {
            self.inertia
                .force_only_into(&kin.q_jj, &w.nu, &w.nu_dot, &mut w.ffr, &mut w.ffr_scratch);
            kin.pt_vec(&w.ffr.F, &mut loc.rho_in);
            return;
        }
        if tangents {
            self.inertia
                .force_with_partials_into(&kin.q_jj, &w.nu, &w.nu_dot, &mut w.ffr, &mut w.ffr_scratch);
        } else {
            self.inertia
                .force_into(&kin.q_jj, &w.nu, &w.nu_dot, &mut w.ffr, &mut w.ffr_scratch);
        }
        kin.pt_vec(&w.ffr.F, &mut loc.rho_in);
        // Body-axis mass P^T M_ffr P = Lambda^T X^T (M_ffr X) Lambda.
        kin.mul_x(w.ffr.M.as_ref(), &mut w.t6, &mut w.MX);
        if !tangents {
            kin.xt_mul(w.MX.as_ref(), w.six_n.as_mut(), loc.M.as_mut());
            lambda_t_left(&kin.Lambda, &mut loc.M);
            lambda_right(&kin.Lambda, &mut loc.M);
            return;
        }
        // With tangents X^T (M_ffr X) comes with the other X^T products (`Local::XE`).
        let c = loc.take_columns(n, n);
        loc.m_col = Some(c);
        for j in 0..n {
            loc.XE.col_as_slice_mut(c + j).copy_from_slice(w.MX.col_as_slice(j));
        }
        let c = &mo.c;
        let Om_yd = Vector3::new(xi_yd[3], xi_yd[4], xi_yd[5]);
        let s_r = Vector3::new(s[3], s[4], s[5]);
        // blocks: N_ydot - N~_s + Q_c ; blocks2: Lambda diag(-Om~) + diag_theta(DJ) ; U + Lambda W(y) in n3a.
        w.n3a.fill(0.0);
        for k in 0..N {
            let th = crate::local_coordinates::theta_of(&kin.q_jj, k);
            let yr = Vector3::new(mo.y[6 * k + 3], mo.y[6 * k + 4], mo.y[6 * k + 5]);
            let ydr = Vector3::new(w.v2[6 * k + 3], w.v2[6 * k + 4], w.v2[6 * k + 5]);
            let cu = Vector3::new(c[6 * k], c[6 * k + 1], c[6 * k + 2]);
            let cth = Vector3::new(c[6 * k + 3], c[6 * k + 4], c[6 * k + 5]);
            w.blocks.t[k] = -skew(&Om_yd) - skew(&s_r);
            w.blocks.r[k] = so3::left_jacobian_inv_derivative(&th, &(ydr - Om_yd))
                - so3::left_jacobian_inv_derivative(&th, &s_r)
                + so3::left_jacobian_inv_second(&th, &(yr - Om), &cth);
            let DJ = so3::left_jacobian_inv_directional(&th, &cth);
            w.blocks2.t[k] = -Ot;
            w.blocks2.r[k] = -(kin.Lambda[k] * Ot) + DJ;
            let yu = Vector3::new(mo.y[6 * k], mo.y[6 * k + 1], mo.y[6 * k + 2]);
            let ut = skew(&cu) + skew(&yu);
            let ur = -DJ + kin.Lambda[k] * skew(&yr);
            for a in 0..3 {
                for b in 0..3 {
                    w.n3a[(6 * k + a, b)] = ut[(a, b)];
                    w.n3a[(6 * k + 3 + a, b)] = ur[(a, b)];
                }
            }
        }
        // With Om_q = Z_r N_y and Y_r = Z_r Lambda, both partials share (F_nu X written FX,
        // M_ffr X written MX, U the stack of block 3x3s in n3a)
        // H = FX + MX N_y - (MX N_y Psi) Z + (MX U) Z_r:
        //   E  = F_q + FX N_y + MX blocks + (MX U) Om_q + MX N_y N_y - (MX N_y Psi) Z N_y
        //      = F_q + MX blocks + H N_y,
        //   E2 = (FX + MX N_y - (MX N_y Psi) Z) Lambda + MX blocks2 + (MX U) Y_r = H Lambda + MX blocks2,
        // and Dq += Lambda^T X^T E, Dy += Lambda^T X^T E2 (`Local::XE`; Lambda^T deferred, `Local::Dq`).
        // With FX = F_nu_q + (F_nu_6 - F_nu_q Psi) Z, H = F_nu_q + MX N_y + t6 Z where
        // t6 = F_nu_6 - (F_nu_q + MX N_y) Psi + [0, MX U]: one product with Z, and one with
        // Psi for both F_nu_q and MX N_y (F_nu_q + MX N_y is the first part of FX anyway).
        copy_mat(&mut w.FX, w.ffr.F_nu.as_ref().subcols(6, n));
        mul_blocks(w.MX.as_ref(), &mo.n_y, &mut w.FX, Accum::Add);
        copy_mat(&mut w.t6, w.ffr.F_nu.as_ref().subcols(0, 6));
        sub_mul_psi(w.FX.as_ref(), &kin.r_loc, &kin.Lambda, &mut w.t6);
        matmul(
            w.t6.as_mut().subcols_mut(3, 3),
            Accum::Add,
            w.MX.as_ref(),
            w.n3a.as_ref(),
            1.0,
            Par::Seq,
        );
        gemm(&mut w.FX, w.t6.as_ref(), kin.Z(), 1.0, Accum::Add);

        // E_q += F_q + MX blocks + H N_y ; E_y += H Lambda + MX blocks2 (X^T in `Local::apply_x_t`).
        // Both straight into their columns of XE; FX is not needed after E_q.
        for j in 0..n {
            add_to(loc.XE.col_as_slice_mut(j), w.ffr.F_q.col_as_slice(j), 1.0);
        }
        add_mul_blocks_at(w.MX.as_ref(), &w.blocks, &mut loc.XE, 0);
        add_mul_blocks_at(w.FX.as_ref(), &mo.n_y, &mut loc.XE, 0);
        add_to(&mut loc.F_sum, &w.ffr.F, 1.0);

        lambda_right(&kin.Lambda, &mut w.FX);
        for j in 0..n {
            add_to(loc.XE.col_as_slice_mut(n + j), w.FX.col_as_slice(j), 1.0);
        }
        add_mul_blocks_at(w.MX.as_ref(), &w.blocks2, &mut loc.XE, n);
    }

    /// Inertia force of the `Lumped` variant.
    ///
    /// # Derivation
    /// The AIC-FFR paper's (6.5) gives the mass matrix $\bar{\mathbf R}\mathbf M_{CB}\bar{\mathbf R}^T$ and
    /// leaves $\mathbf Q_v$ to "lumping" the reduced mass. We read this as: the reduced mass is
    /// carried by the interface coordinates themselves, measured in the body axes, i.e. the
    /// kinetic energy is $T_L = \tfrac12\mathbf y^T\mathbf M_{CB}\mathbf y$ with $\mathbf y =
    /// \bar{\mathbf R}^T\dot{\mathbf q}$ (the absolute interface velocities, not the elastic ones).
    /// Its mass matrix is the AIC-FFR paper's, it is exact for any rigid motion (the CB basis reproduces
    /// rigid motions, so $\boldsymbol\Phi_{rig}^T\mathbf M_{CB}\boldsymbol\Phi_{rig}$ is the rigid
    /// mass matrix), and it differs from the exact $T$ only in how the convective velocity of
    /// the deformed body is interpolated (by the constraint modes from the interfaces). The
    /// quadratic velocity force then follows from Lagrange's equations on $(\mathbb R^3\times SO(3))^N$
    /// with spatial angular velocities, $\mathbf f = \dot{\mathbf p} + [\mathbf p_{\omega_k}\times\boldsymbol\omega_k] -
    /// \partial T/\partial\mathbf q$ (the middle term from $\delta\boldsymbol\omega = \delta\dot{\boldsymbol\pi} - \boldsymbol\omega\times\delta\boldsymbol\pi$),
    /// with $\mathbf p = \bar{\mathbf R}\mathbf M_{CB}\mathbf y$ and $T_L$ depending on $\mathbf q$ only
    /// through $\mathbf R_j$ ($\delta\boldsymbol\Pi = \mathbf Y_r\bar{\mathbf R}^T\delta\mathbf q$). In body axes,
    /// with $\boldsymbol\Omega = \mathbf Y_r\mathbf y$ and $\mathbf p^L = \mathbf M_{CB}\mathbf y$:
    ///
    /// $$\boldsymbol\rho_{in} = \mathbf M_{CB}\mathbf a + \mathbf M_{CB}\mathbf W(\mathbf y)\boldsymbol\Omega +
    /// [\boldsymbol\Omega\times\mathbf p^L_b]_b + [\mathbf p^L_{\theta_k}\times\mathbf y_{\theta_k}]_k -
    /// \mathbf Y_r^T\mathbf W(\mathbf y)^T\mathbf p^L.$$
    ///
    /// A single rigid body at its interface gives $m\mathbf R^T\ddot{\mathbf r}$ and Euler's
    /// $\mathbf J\dot{\boldsymbol\Omega} + \boldsymbol\Omega\times\mathbf J\boldsymbol\Omega$; the power
    /// $\mathbf y^T\boldsymbol\rho_{in} = \dot T_L$ (the last three terms do no work). Partials:
    /// $\partial/\partial\mathbf q^{jj} = (\mathbf M_{CB}\mathbf W(\mathbf y) - \mathbf W(\mathbf p^L))\boldsymbol\Omega_q -
    /// \partial(\mathbf Y_r^T\mathbf w)/\partial\mathbf q^{jj}|_{\mathbf w = \mathbf W^T\mathbf p^L}$ and
    /// $\partial/\partial\mathbf y = -\mathbf M_{CB}\,\mathrm{diag}(\tilde{\boldsymbol\Omega}) + \mathrm{diag}(\tilde{\boldsymbol\Omega})\mathbf M_{CB} +
    /// (\mathbf M_{CB}\mathbf W(\mathbf y) - \mathbf W(\mathbf p^L))\mathbf Y_r + [-\tilde{\mathbf y}_{\theta_k}(\mathbf M_{CB})_{\theta_k\cdot} +
    /// \tilde{\mathbf p}^L_{\theta_k}\mathbf E^\theta_k]_k + \mathbf Y_r^T(\mathbf W(\mathbf p^L)^T - \mathbf W(\mathbf y)^T\mathbf M_{CB})$.
    /// Tested by `tests/unit/fd_tangent.rs::tangents_match_fd`, `::inertia_tangents_match_fd`
    /// (Lumped) and `tests/unit/energy.rs`.
    pub(crate) fn lumped_inertia(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, w: &mut Scratch, level: Level) {
        let n = self.n;
        let N = self.n_interfaces;
        let M = &self.M_CB;
        let Om = mo.omega();
        let y = &mo.y;
        // p = M y (v1); W(y) Om (v2): block b = y_b x Om.
        matvec(M, y, &mut w.v1);
        for b in 0..2 * N {
            let yb = Vector3::new(y[3 * b], y[3 * b + 1], y[3 * b + 2]);
            let v = yb.cross(&Om) + Vector3::new(mo.a[3 * b], mo.a[3 * b + 1], mo.a[3 * b + 2]);
            w.v2[3 * b..3 * b + 3].copy_from_slice(v.as_slice());
        }
        w.v2[6 * N..].copy_from_slice(&mo.a[6 * N..]);
        // M (a + W(y) Om)
        matvec(M, &w.v2, &mut loc.rho_in);
        let p = &w.v1;
        let rho = &mut loc.rho_in;
        // W(y)^T p = sum_b p_b x y_b.
        let mut wtp = Vector3::zeros();
        for b in 0..2 * N {
            let pb = Vector3::new(p[3 * b], p[3 * b + 1], p[3 * b + 2]);
            let yb = Vector3::new(y[3 * b], y[3 * b + 1], y[3 * b + 2]);
            wtp += pb.cross(&yb);
            let v = Om.cross(&pb);
            for i in 0..3 {
                rho[3 * b + i] += v[i];
            }
        }
        for k in 0..N {
            let pr = Vector3::new(p[6 * k + 3], p[6 * k + 4], p[6 * k + 5]);
            let yr = Vector3::new(y[6 * k + 3], y[6 * k + 4], y[6 * k + 5]);
            let v = pr.cross(&yr);
            for i in 0..3 {
                rho[6 * k + 3 + i] += v[i];
            }
        }
        let Y = kin.Y();
        for j in 0..n {
            rho[j] -= Y[(3, j)] * wtp[0] + Y[(4, j)] * wtp[1] + Y[(5, j)] * wtp[2];
        }
        if level.mass() {
            copy_mat(&mut loc.M, M.as_ref());
        }
        if !level.tangents() {
            return;
        }
        // n3a = W(y), n3b = W(p), n3c = M W(y) - W(p).
        w_into(y, N, &mut w.n3a);
        w_into(p, N, &mut w.n3b);
        gemm(&mut w.n3c, M.as_ref(), w.n3a.as_ref(), 1.0, Accum::Replace);
        add_scaled(&mut w.n3c, &w.n3b, -1.0);
        // Om_q = (Z_j N_y)_r.
        mul_blocks(kin.Z().subrows(3, 3), &mo.n_y, &mut w.three_n, Accum::Replace);
        gemm(&mut loc.Dq, w.n3c.as_ref(), w.three_n.as_ref(), 1.0, Accum::Add);
        w.F6.fill(0.0);
        w.F6[3..6].copy_from_slice(wtp.as_slice());
        add_to(&mut loc.F_sum, &w.F6, -1.0);

        // d/dy.
        let Yr = Y.subrows(3, 3);
        gemm(&mut loc.Dy, w.n3c.as_ref(), Yr, 1.0, Accum::Add);
        let Ot = skew(&Om);
        for k in 0..N {
            w.blocks.t[k] = -Ot;
            w.blocks.r[k] = -Ot;
        }
        // -M diag(Om~)
        mul_blocks(M.as_ref(), &w.blocks, &mut loc.Dy, Accum::Add);
        // diag(Om~) M and the rotation rows -y_r~ M_r.
        for j in 0..n {
            let col = M.col_as_slice(j);
            let o = loc.Dy.col_as_slice_mut(j);
            for b in 0..2 * N {
                let mc = Vector3::new(col[3 * b], col[3 * b + 1], col[3 * b + 2]);
                let mut v = Ot * mc;
                if b % 2 == 1 {
                    let yr = Vector3::new(y[3 * b], y[3 * b + 1], y[3 * b + 2]);
                    v -= yr.cross(&mc);
                }
                for i in 0..3 {
                    o[3 * b + i] += v[i];
                }
            }
        }
        for k in 0..N {
            let pr = skew(&Vector3::new(p[6 * k + 3], p[6 * k + 4], p[6 * k + 5]));
            for a in 0..3 {
                for b in 0..3 {
                    loc.Dy[(6 * k + 3 + a, 6 * k + 3 + b)] += pr[(a, b)];
                }
            }
        }
        // Y_r^T (W(p)^T - W(y)^T M)
        for j in 0..n {
            for i in 0..3 {
                w.three_n[(i, j)] = w.n3b[(j, i)];
            }
        }
        gemm(&mut w.three_n, w.n3a.as_ref().transpose(), M.as_ref(), -1.0, Accum::Add);
        gemm(&mut loc.Dy, kin.YrT.as_ref(), w.three_n.as_ref(), 1.0, Accum::Add);
    }
}
