//! The velocity transformation: $\boldsymbol\Phi_{rig}$ (3.6), $\mathbf Z_j$ and $\mathbf T_j$
//! (3.9)-(3.10), $\mathbf A$ (3.11), with the exact rotation factor $\boldsymbol\Lambda$, and the
//! derivatives of these maps with respect to the CB coordinates that the tangents need.
//!
//! # Exact variations
//!
//! The CB rotation coordinates are rotation vectors, $\boldsymbol\theta_k = \log(\mathbf R_j^T\mathbf R_k)$,
//! whose variation is $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ times the virtual rotation of (3.4)
//! ([`crate::local_coordinates::elastic_rotation`]). So the exact form of (3.7) is
//! $\delta\mathbf q^{jj} = \boldsymbol\Lambda(\bar{\mathbf R}^T\delta\mathbf q^{OO} - \boldsymbol\Phi_{rig}\delta\boldsymbol\Xi)$,
//! $\delta\boldsymbol\Xi = [\mathbf R_j^T\delta\mathbf r_j;\ \mathbf R_j^T\delta\boldsymbol\pi_j]$, and
//! (2.6) gives, with $\boldsymbol\Psi = \boldsymbol\Lambda\boldsymbol\Phi_{rig}$,
//!
//! $$\mathbf Z_j = (\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}\boldsymbol\Phi_j,\quad
//! \mathbf T_j = \mathbf I - \boldsymbol\Psi\mathbf Z_j,\quad
//! \delta\boldsymbol\Xi = \mathbf Z_j\boldsymbol\Lambda\bar{\mathbf R}^T\delta\mathbf q,\quad
//! \delta\mathbf q^{jj} = \mathbf T_j\boldsymbol\Lambda\bar{\mathbf R}^T\delta\mathbf q.$$
//!
//! For $\boldsymbol\Lambda = \mathbf I$ (undeformed, or small elastic rotations) these are the
//! seed's (3.9)-(3.10) exactly. Here $\delta\mathbf q = [\delta\mathbf r_1, \delta\boldsymbol\pi_1, \dots,
//! \delta\mathbf r_N, \delta\boldsymbol\pi_N, \delta\boldsymbol\eta]$ are the superelement's
//! coordinates: $\boldsymbol\eta$ is independent, so $\boldsymbol\Phi_j$, $\mathbf Z_j$ and
//! $\mathbf T_j$ carry eta columns and $\bar{\mathbf R}$, $\boldsymbol\Lambda$ an identity eta block.
//!
//! We write $\mathbf X = [\mathbf Z_j;\ \mathbf T_j]$ and $\mathbf P = \mathbf X\boldsymbol\Lambda =
//! [\mathbf Y;\ \mathbf B]$ ($\mathbf Y = \mathbf Z_j\boldsymbol\Lambda$, $\mathbf B = \mathbf T_j\boldsymbol\Lambda$):
//! $\mathbf A = \mathrm{diag}(\mathbf R_j, \mathbf R_j, \mathbf I)\,\mathbf P\,\bar{\mathbf R}^T$ (3.11),
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

use crate::frame::Frame;
use crate::local_coordinates::{theta_of, u_of};
use crate::so3::{self, skew};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use nalgebra::{Matrix3, Matrix6, UnitQuaternion, Vector3};

/// $\boldsymbol\Phi_{rig}$ (3.6): the $n\times6$ rigid-body modes of the interface set about the
/// frame origin, on the *deformed* local positions $\mathbf r_k^{jj} = \mathbf x_k + \mathbf u_k$:
/// block rows $[\mathbf I,\ -\tilde{\mathbf r}_k^{jj}]$ (translation) and $[\mathbf 0,\ \mathbf I]$
/// (rotation) per interface, zero rows for $\boldsymbol\eta$.
pub fn phi_rig(r_loc: &[Vector3<f64>], n_modes: usize) -> Mat<f64> {
    let N = r_loc.len();
    let mut P = Mat::zeros(6 * N + n_modes, 6);
    for (k, r) in r_loc.iter().enumerate() {
        let mr = -skew(r);
        for i in 0..3 {
            P[(6 * k + i, i)] = 1.0;
            P[(6 * k + 3 + i, 3 + i)] = 1.0;
            for j in 0..3 {
                P[(6 * k + i, 3 + j)] = mr[(i, j)];
            }
        }
    }
    P
}

/// Everything about one configuration that does not depend on velocities: the frame, the CB
/// coordinates and the transformation matrices in body axes (module docs).
#[derive(Clone, Debug)]
pub struct Kinematics {
    /// The frame solving (2.6).
    pub frame: Frame,
    /// Newton iterations the frame took (0 for explicit frames).
    pub frame_iterations: usize,
    /// $\mathbf R_j$ as a matrix.
    pub R_j: Matrix3<f64>,
    /// $\mathbf q^{jj}$ (2.3).
    pub q_jj: Vec<f64>,
    /// Deformed local interface positions $\mathbf r_k^{jj} = \mathbf x_k + \mathbf u_k$.
    pub r_loc: Vec<Vector3<f64>>,
    /// Blocks $\mathbf J_l^{-1}(\boldsymbol\theta_k)$ of $\boldsymbol\Lambda$.
    pub Lambda: Vec<Matrix3<f64>>,
    /// $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$.
    pub G_inv: Matrix6<f64>,
    /// $\mathbf X = [\mathbf Z_j;\ \mathbf T_j]$, $(6+n)\times n$.
    pub X: Mat<f64>,
    /// $\mathbf P = \mathbf X\boldsymbol\Lambda = [\mathbf Y;\ \mathbf B]$, $(6+n)\times n$.
    pub P: Mat<f64>,
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
        Self { t: vec![Matrix3::zeros(); N], r: vec![Matrix3::zeros(); N] }
    }
}

/// `out (+)= A * blocks` for `A` with $n$ columns (eta columns of the product are zero).
pub(crate) fn mul_blocks(A: MatRef<'_, f64>, blocks: &Blocks, out: &mut Mat<f64>, accum: Accum) {
    let N = blocks.t.len();
    if accum == Accum::Replace {
        out.fill(0.0);
    }
    for k in 0..N {
        for (off, B) in [(6 * k, &blocks.t[k]), (6 * k + 3, &blocks.r[k])] {
            for j in 0..3 {
                for i in 0..A.nrows() {
                    out[(i, off + j)] += A[(i, off)] * B[(0, j)] + A[(i, off + 1)] * B[(1, j)] + A[(i, off + 2)] * B[(2, j)];
                }
            }
        }
    }
}

/// `out += alpha * A B` (sequential faer product; all our matrices are small).
#[inline]
pub(crate) fn gemm(out: &mut Mat<f64>, A: MatRef<'_, f64>, B: MatRef<'_, f64>, alpha: f64, accum: Accum) {
    matmul(out.as_mut(), accum, A, B, alpha, Par::Seq);
}

impl Kinematics {
    /// Builds the transformation for the converged `frame` and the CB coordinates `q_jj`
    /// (3.9)-(3.10) with the exact factor $\boldsymbol\Lambda$ (module docs).
    pub(crate) fn new(
        frame: Frame,
        frame_iterations: usize,
        q_jj: Vec<f64>,
        x: &[Vector3<f64>],
        Phi_j: MatRef<'_, f64>,
    ) -> Result<Self, crate::SuperelementError> {
        let N = x.len();
        let n = q_jj.len();
        let r_loc: Vec<Vector3<f64>> = (0..N).map(|k| x[k] + u_of(&q_jj, k)).collect();
        let Lambda: Vec<Matrix3<f64>> = (0..N).map(|k| so3::left_jacobian_inv(&theta_of(&q_jj, k))).collect();
        let G = crate::frame::phi_j_psi(Phi_j, &r_loc, &Lambda);
        let (G_inv, rcond) =
            crate::frame::inverse_with_rcond(&G).ok_or(crate::SuperelementError::SingularFrame { rcond: 0.0 })?;
        if rcond < crate::frame::RCOND_MIN {
            return Err(crate::SuperelementError::SingularFrame { rcond });
        }
        // Z = G^{-1} Phi_j ; T = I - Psi Z.
        let mut X = Mat::zeros(6 + n, n);
        for j in 0..n {
            for a in 0..6 {
                X[(a, j)] = (0..6).map(|b| G_inv[(a, b)] * Phi_j[(b, j)]).sum();
            }
        }
        for j in 0..n {
            X[(6 + j, j)] = 1.0;
        }
        for k in 0..N {
            let mr = -skew(&r_loc[k]);
            for j in 0..n {
                let zt = Vector3::new(X[(0, j)], X[(1, j)], X[(2, j)]);
                let zr = Vector3::new(X[(3, j)], X[(4, j)], X[(5, j)]);
                let pu = zt + mr * zr;
                let pr = Lambda[k] * zr;
                for i in 0..3 {
                    X[(6 + 6 * k + i, j)] -= pu[i];
                    X[(6 + 6 * k + 3 + i, j)] -= pr[i];
                }
            }
        }
        let mut P = X.clone();
        for k in 0..N {
            for i in 0..6 + n {
                let row = Vector3::new(X[(i, 6 * k + 3)], X[(i, 6 * k + 4)], X[(i, 6 * k + 5)]);
                let v = Lambda[k].transpose() * row;
                for c in 0..3 {
                    P[(i, 6 * k + 3 + c)] = v[c];
                }
            }
        }
        Ok(Self {
            R_j: frame.R.to_rotation_matrix().into_inner(),
            frame,
            frame_iterations,
            q_jj,
            r_loc,
            Lambda,
            G_inv,
            X,
            P,
        })
    }

    /// Number of CB coordinates $n$.
    pub fn n(&self) -> usize {
        self.q_jj.len()
    }

    /// Number of interfaces $N$.
    pub fn n_interfaces(&self) -> usize {
        self.r_loc.len()
    }

    /// $\mathbf Z_j$ (3.9), $6\times n$.
    pub fn Z(&self) -> MatRef<'_, f64> {
        self.X.as_ref().subrows(0, 6)
    }

    /// $\mathbf T_j$ (3.10), $n\times n$.
    pub fn T(&self) -> MatRef<'_, f64> {
        self.X.as_ref().subrows(6, self.n())
    }

    /// $\mathbf Y = \mathbf Z_j\boldsymbol\Lambda$: body-axis frame velocity from body-axis interface velocities.
    pub fn Y(&self) -> MatRef<'_, f64> {
        self.P.as_ref().subrows(0, 6)
    }

    /// $\mathbf B = \mathbf T_j\boldsymbol\Lambda = \partial\mathbf q^{jj}/\partial(\bar{\mathbf R}^T\mathbf q)$.
    pub fn B(&self) -> MatRef<'_, f64> {
        self.P.as_ref().subrows(6, self.n())
    }

    /// $\boldsymbol\Phi_{rig}$ (3.6) of this configuration.
    pub fn phi_rig(&self) -> Mat<f64> {
        phi_rig(&self.r_loc, self.n() - 6 * self.n_interfaces())
    }

    /// $\bar{\mathbf R}^T\mathbf x$ (or $\bar{\mathbf R}\mathbf x$ with `forward`): rotates each 3-block of
    /// the interface part, leaves the eta part.
    pub fn rotate(&self, x: &[f64], forward: bool) -> Vec<f64> {
        let mut out = x.to_vec();
        let R = if forward { self.R_j } else { self.R_j.transpose() };
        for b in 0..2 * self.n_interfaces() {
            let v = R * Vector3::new(x[3 * b], x[3 * b + 1], x[3 * b + 2]);
            out[3 * b..3 * b + 3].copy_from_slice(v.as_slice());
        }
        out
    }

    /// $\mathbf A$ (3.11) in inertial axes: $(6+n)\times n$, rows $[\delta\mathbf r_j;\ \delta\boldsymbol\pi_j;\ \delta\mathbf q^{jj}]$.
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
    /// $\boldsymbol\xi = \mathbf Y\mathbf y$.
    pub(crate) fn n_y(&self, y: &[f64], xi: &[f64]) -> Blocks {
        let N = self.n_interfaces();
        let Om = Vector3::new(xi[3], xi[4], xi[5]);
        let mut b = Blocks::zeros(N);
        for k in 0..N {
            b.t[k] = -skew(&Om);
            let zeta_r = Vector3::new(y[6 * k + 3], y[6 * k + 4], y[6 * k + 5]) - Om;
            b.r[k] = so3::left_jacobian_inv_derivative(&theta_of(&self.q_jj, k), &zeta_r);
        }
        b
    }

    /// $\partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj}$ for a fixed $\mathbf F \in \mathbb R^{6+n}$, added to `out`.
    ///
    /// # Derivation
    /// $\mathbf y^T\,D(\mathbf P^T\mathbf F)[\boldsymbol\varepsilon] = \mathbf F^T\mathbf X\mathbf N_y\boldsymbol\varepsilon
    /// = \boldsymbol\phi^T\mathbf N_y\boldsymbol\varepsilon$ with $\boldsymbol\phi = \mathbf X^T\mathbf F$; the
    /// form is bilinear in $(\mathbf y, \boldsymbol\varepsilon)$ through $\boldsymbol\xi_r = \mathbf Y_r\mathbf y$
    /// and $\boldsymbol\zeta_{k,r} = (\mathbf E^\theta_k - \mathbf Y_r)\mathbf y$:
    /// $\boldsymbol\phi^T\mathbf N_y\boldsymbol\varepsilon = \sum_k \boldsymbol\xi_r^T\tilde{\boldsymbol\phi}_{k,t}\boldsymbol\varepsilon_{u_k}
    /// + \boldsymbol\zeta_{k,r}^T\mathbf K_k\boldsymbol\varepsilon_{\theta_k}$, where
    /// $\mathbf K_k = \partial(\mathbf J_l^{-T}(\boldsymbol\theta_k)\boldsymbol\phi_{k,r})/\partial\boldsymbol\theta_k
    /// = -\mathbf H(-\boldsymbol\theta_k, \boldsymbol\phi_{k,r})$. Hence
    /// $\partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj} = \sum_k \mathbf Y_r^T\tilde{\boldsymbol\phi}_{k,t}\mathbf E^u_k
    /// + (\mathbf E^\theta_k - \mathbf Y_r)^T\mathbf K_k\mathbf E^\theta_k$.
    pub(crate) fn add_d_pt(&self, F: &[f64], out: &mut Mat<f64>, alpha: f64) {
        let n = self.n();
        let N = self.n_interfaces();
        let mut phi = vec![0.0; n];
        for j in 0..n {
            phi[j] = (0..6 + n).map(|i| self.X[(i, j)] * F[i]).sum();
        }
        let Y = self.Y();
        for k in 0..N {
            let pt = skew(&Vector3::new(phi[6 * k], phi[6 * k + 1], phi[6 * k + 2]));
            let pr = Vector3::new(phi[6 * k + 3], phi[6 * k + 4], phi[6 * k + 5]);
            let K = -so3::left_jacobian_inv_derivative(&-theta_of(&self.q_jj, k), &pr);
            // Y_r^T (pt) at columns u_k ; -Y_r^T K at columns theta_k ; K at (theta_k, theta_k).
            for i in 0..n {
                let yr = Vector3::new(Y[(3, i)], Y[(4, i)], Y[(5, i)]);
                let a = pt.transpose() * yr;
                let b = K.transpose() * yr;
                for c in 0..3 {
                    out[(i, 6 * k + c)] += alpha * a[c];
                    out[(i, 6 * k + 3 + c)] -= alpha * b[c];
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

/// $\bar{\mathbf R}$-rotation of an $n\times n$ matrix: `out` $= \bar{\mathbf R}\mathbf K\bar{\mathbf R}^T$.
pub(crate) fn rotate_matrix(R: &Matrix3<f64>, N: usize, K: &Mat<f64>, out: &mut Mat<f64>) {
    let n = K.nrows();
    let nb = 2 * N;
    let block_of = |i: usize| if i < 3 * nb { Some(i / 3) } else { None };
    // First K Rbar^T (columns), then Rbar (rows).
    let mut tmp = K.clone();
    for b in 0..nb {
        for i in 0..n {
            let row = Vector3::new(K[(i, 3 * b)], K[(i, 3 * b + 1)], K[(i, 3 * b + 2)]);
            let v = R * row;
            for c in 0..3 {
                tmp[(i, 3 * b + c)] = v[c];
            }
        }
    }
    for j in 0..n {
        for i in 0..n {
            if block_of(i).is_none() {
                out[(i, j)] = tmp[(i, j)];
            }
        }
        for b in 0..nb {
            let col = Vector3::new(tmp[(3 * b, j)], tmp[(3 * b + 1, j)], tmp[(3 * b + 2, j)]);
            let v = R * col;
            for c in 0..3 {
                out[(3 * b + c, j)] = v[c];
            }
        }
    }
}

/// $\mathbf W(\mathbf x)$: the $n\times3$ stack of $\tilde{\mathbf x}_b$ over the $2N$ interface
/// 3-blocks (zero eta rows), so that $\delta(\bar{\mathbf R}^T\mathbf x_{spatial}) = \mathbf W(\bar{\mathbf R}^T\mathbf x)\,\delta\boldsymbol\Pi$
/// for a fixed spatial vector, $\delta\boldsymbol\Pi = \mathbf R_j^T\delta\boldsymbol\pi_j$.
pub(crate) fn w_stack(x: &[f64], N: usize) -> Mat<f64> {
    let n = x.len();
    let mut W = Mat::zeros(n, 3);
    for b in 0..2 * N {
        let S = skew(&Vector3::new(x[3 * b], x[3 * b + 1], x[3 * b + 2]));
        for i in 0..3 {
            for j in 0..3 {
                W[(3 * b + i, j)] = S[(i, j)];
            }
        }
    }
    W
}

/// Helper for tests and callers: the frame rotation matrix of a quaternion.
pub fn rotation_matrix(R: &UnitQuaternion<f64>) -> Matrix3<f64> {
    R.to_rotation_matrix().into_inner()
}
