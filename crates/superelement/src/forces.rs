//! Generalised forces of the superelement in body axes, and their partial derivatives:
//! elastic (4.4), inertial in the two variants (4.3)/(4.4), gravity and damping.
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

#![allow(non_snake_case)]

use crate::body::Superelement;
use crate::so3::{self, skew};
use crate::transform::{gemm, mul_blocks, w_stack, Blocks, Kinematics};
use faer::{Accum, Mat};
use nalgebra::{Matrix3, Vector3};

/// Velocity-level quantities shared by all forces of one evaluation.
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
    /// $\mathbf N_y$ and $\mathbf X\mathbf N_y$ (only with tangents).
    pub n_y: Blocks,
    pub XNy: Mat<f64>,
}

impl Motion {
    pub fn new(kin: &Kinematics, qd: &[f64], qdd: &[f64], g: &Vector3<f64>, tangents: bool) -> Self {
        let n = kin.n();
        let y = kin.rotate(qd, false);
        let a = kin.rotate(qdd, false);
        let P = &kin.P;
        let mut xi = [0.0; 6];
        let mut c = vec![0.0; n];
        for j in 0..n {
            let yj = y[j];
            for i in 0..6 {
                xi[i] += P[(i, j)] * yj;
            }
            for i in 0..n {
                c[i] += P[(6 + i, j)] * yj;
            }
        }
        let (n_y, XNy) = if tangents {
            let nb = kin.n_y(&y, &xi);
            let mut XNy = Mat::zeros(6 + n, n);
            mul_blocks(kin.X.as_ref(), &nb, &mut XNy, Accum::Replace);
            (nb, XNy)
        } else {
            (Blocks::zeros(0), Mat::zeros(0, 0))
        };
        Self { y, a, g: kin.R_j.transpose() * g, xi, c, n_y, XNy }
    }

    pub fn omega(&self) -> Vector3<f64> {
        Vector3::new(self.xi[3], self.xi[4], self.xi[5])
    }
}

/// Body-axis forces and their partials, accumulated over the force kinds.
pub(crate) struct Local {
    pub rho_in: Vec<f64>,
    pub rho_el: Vec<f64>,
    pub rho_d: Vec<f64>,
    pub rho_g: Vec<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf a$: the body-axis mass matrix.
    pub M: Mat<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf q^{jj}$ of the residual $\boldsymbol\rho_{in} +
    /// \boldsymbol\rho_{el} + \boldsymbol\rho_d - \boldsymbol\rho_g$.
    pub Dq: Mat<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf y$ of the residual.
    pub Dy: Mat<f64>,
    /// $\partial\boldsymbol\rho/\partial\mathbf g^L$ of the residual ($n\times3$).
    pub Dg: Mat<f64>,
}

impl Local {
    pub fn new(n: usize, tangents: bool) -> Self {
        let t = if tangents { n } else { 0 };
        Self {
            rho_in: vec![0.0; n],
            rho_el: vec![0.0; n],
            rho_d: vec![0.0; n],
            rho_g: vec![0.0; n],
            M: Mat::zeros(n, n),
            Dq: Mat::zeros(t, t),
            Dy: Mat::zeros(t, t),
            Dg: Mat::zeros(t, if tangents { 3 } else { 0 }),
        }
    }
}

/// $\mathbf P^T\mathbf F$ into `out` (overwrites).
fn pt_mul(kin: &Kinematics, F: &[f64], out: &mut [f64]) {
    let n = kin.n();
    for j in 0..n {
        out[j] = (0..6 + n).map(|i| kin.P[(i, j)] * F[i]).sum();
    }
}

/// $\mathbf F = [\mathbf 0_6;\ \mathbf f]$.
fn lift(f: &[f64]) -> Vec<f64> {
    let mut F = vec![0.0; 6 + f.len()];
    F[6..].copy_from_slice(f);
    F
}

impl Superelement {
    /// Elastic force (4.4) in body axes, $\boldsymbol\rho_{el} = \mathbf B^T\mathbf K_{CB}\mathbf q^{jj}$
    /// ($\mathbf B = \mathbf T_j\boldsymbol\Lambda$; the seed's $\mathbf T_j^T\mathbf K_{CB}\mathbf q^{jj}$ with
    /// the exact rotation factor), so $\mathbf f_{el} = \bar{\mathbf R}\boldsymbol\Lambda^T\mathbf T_j^T\mathbf K_{CB}\mathbf q^{jj}$.
    ///
    /// # Derivation
    /// $\mathbf f_{el}$ is the gradient of $U = \tfrac12\mathbf q^{jjT}\mathbf K_{CB}\mathbf q^{jj}$ in the
    /// absolute coordinates, because $\delta\mathbf q^{jj} = \mathbf B\bar{\mathbf R}^T\delta\mathbf q$
    /// exactly ([`crate::transform`]). Its derivative: $\partial\boldsymbol\rho_{el}/\partial\mathbf q^{jj}
    /// = \partial(\mathbf P^T[\mathbf 0;\mathbf f])/\partial\mathbf q^{jj} + \mathbf B^T\mathbf K_{CB}$,
    /// $\mathbf f = \mathbf K_{CB}\mathbf q^{jj}$ ([`Kinematics`]`::add_d_pt`). Tested by
    /// `tests/unit/fd_tangent.rs::tangents_match_fd` and `tests/unit/invariance.rs`.
    pub(crate) fn elastic(&self, kin: &Kinematics, loc: &mut Local, tangents: bool) {
        let n = self.n;
        let mut f = vec![0.0; n];
        crate::mass::matvec(&self.K_CB, &kin.q_jj, &mut f);
        let F = lift(&f);
        pt_mul(kin, &F, &mut loc.rho_el);
        if tangents {
            kin.add_d_pt(&F, &mut loc.Dq, 1.0);
            gemm(&mut loc.Dq, kin.B().transpose(), self.K_CB.as_ref(), 1.0, Accum::Add);
        }
    }

    /// Damping force $\boldsymbol\rho_d = \mathbf B^T\mathbf D\,\dot{\mathbf q}^{jj}$, $\dot{\mathbf q}^{jj} =
    /// \mathbf B\mathbf y$ (the elastic velocity, (3.10)); [`crate::Damping`] defines $\mathbf D$.
    ///
    /// # Derivation
    /// The Rayleigh dissipation function $\tfrac12\dot{\mathbf q}^{jjT}\mathbf D\dot{\mathbf q}^{jj}$
    /// differentiated by $\dot{\mathbf q}$. $\partial/\partial\mathbf y = \mathbf B^T\mathbf D\mathbf B$;
    /// $\partial/\partial\mathbf q^{jj} = \partial(\mathbf P^T[\mathbf 0;\mathbf D\dot{\mathbf q}^{jj}])/\partial\mathbf q^{jj}
    /// + \mathbf B^T\mathbf D\,\mathbf T_j\mathbf N_y$ (since $D(\mathbf B\mathbf y) = \mathbf T_j\mathbf N_y$).
    /// Tested by `tests/unit/fd_tangent.rs::tangents_match_fd` (damped bodies).
    pub(crate) fn damping_force(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, tangents: bool) {
        if !self.damped {
            return;
        }
        let n = self.n;
        let mut f = vec![0.0; n];
        crate::mass::matvec(&self.D, &mo.c, &mut f);
        let F = lift(&f);
        pt_mul(kin, &F, &mut loc.rho_d);
        if tangents {
            kin.add_d_pt(&F, &mut loc.Dq, 1.0);
            let mut DB = Mat::zeros(n, n);
            gemm(&mut DB, self.D.as_ref(), kin.B(), 1.0, Accum::Replace);
            gemm(&mut loc.Dy, kin.B().transpose(), DB.as_ref(), 1.0, Accum::Add);
            let mut DTN = Mat::zeros(n, n);
            gemm(&mut DTN, self.D.as_ref(), mo.XNy.as_ref().subrows(6, n), 1.0, Accum::Replace);
            gemm(&mut loc.Dq, kin.B().transpose(), DTN.as_ref(), 1.0, Accum::Add);
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
    /// $\mathbf P$ ((3.11) in body axes). Partials: $\partial\mathbf Q_g/\partial\mathbf q^{jj} =
    /// [\mathbf 0;\ -\tilde{\mathbf g}^L\mathbf S_t;\ \mathbf 0]$, $\partial\mathbf Q_g/\partial\mathbf g^L =
    /// [m\mathbf I;\ \tilde{\mathbf s};\ \mathbf S_t^T]$. Tested by `tests/unit/fd_tangent.rs::tangents_match_fd`
    /// and `tests/unit/energy.rs::gravity_is_the_gradient_of_its_potential`.
    pub(crate) fn gravity(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, tangents: bool) {
        let n = self.n;
        let I = &self.inertia;
        let g = mo.g;
        if g == Vector3::zeros() && !tangents {
            return;
        }
        let s = I.d * I.mass + crate::mass::mul3(&I.S_t, &kin.q_jj);
        let mut Q = vec![0.0; 6 + n];
        let sg = s.cross(&g);
        for i in 0..3 {
            Q[i] = I.mass * g[i];
            Q[3 + i] = sg[i];
        }
        crate::mass::add_mul3t(&mut Q[6..], &I.S_t, &g, 1.0);
        pt_mul(kin, &Q, &mut loc.rho_g);
        if tangents {
            kin.add_d_pt(&Q, &mut loc.Dq, -1.0);
            let Y = kin.Y();
            let gt = skew(&g);
            // - Y_r^T (-g~ S_t) = Y_r^T g~ S_t
            let mut GS = Mat::zeros(3, n);
            for j in 0..n {
                let v = gt * Vector3::new(I.S_t[(0, j)], I.S_t[(1, j)], I.S_t[(2, j)]);
                for i in 0..3 {
                    GS[(i, j)] = v[i];
                }
            }
            gemm(&mut loc.Dq, Y.subrows(3, 3).transpose(), GS.as_ref(), 1.0, Accum::Add);
            // Dg -= Y_t^T m + Y_r^T s~ + B^T S_t^T
            let st = skew(&s);
            for j in 0..n {
                let yt = Vector3::new(Y[(0, j)], Y[(1, j)], Y[(2, j)]);
                let yr = Vector3::new(Y[(3, j)], Y[(4, j)], Y[(5, j)]);
                let v = yt * I.mass + st.transpose() * yr;
                for i in 0..3 {
                    loc.Dg[(j, i)] -= v[i];
                }
            }
            gemm(&mut loc.Dg, kin.B().transpose(), I.S_t.as_ref().transpose(), -1.0, Accum::Add);
        }
    }

    /// Inertia force of the `Exact` variant: $\boldsymbol\rho_{in} = \mathbf P^T\mathbf F(\mathbf q^{jj},
    /// \boldsymbol\nu, \dot{\boldsymbol\nu})$ ([`crate::mass`]), $\boldsymbol\nu = \mathbf P\mathbf y$,
    /// $\dot{\boldsymbol\nu} = \mathbf P\dot{\mathbf y} + \mathbf X\mathbf N_y\dot{\mathbf q}^{jj}$, and the body-axis
    /// mass $\mathbf P^T\mathbf M_{ffr}\mathbf P$. In inertial axes this is (4.3):
    /// $\mathbf A^T\mathbf M_{ffr}\mathbf A\ddot{\mathbf q} + \mathbf A^T(\mathbf M_{ffr}\dot{\mathbf A}\dot{\mathbf q} + \mathbf h)$.
    ///
    /// # Derivation
    /// $\dot{\mathbf y} = \mathbf a + \mathbf W(\mathbf y)\boldsymbol\Omega$ (the body axes turn with
    /// $\boldsymbol\Omega$; $\mathbf W$ stacks $\tilde{\mathbf y}_b$) and $\frac{d}{dt}\mathbf P =
    /// D\mathbf P[\dot{\mathbf q}^{jj}]$, so $\dot{\boldsymbol\nu} = \mathbf P\dot{\mathbf y} + \mathbf X\mathbf N_y\dot{\mathbf q}^{jj}$
    /// is $\mathbf A\ddot{\mathbf q} + \dot{\mathbf A}\dot{\mathbf q}$ of (4.2) in body axes. The partials,
    /// with $\mathbf s = \mathbf Z_j\mathbf N_y\dot{\mathbf q}^{jj}$, $\mathbf c = \dot{\mathbf q}^{jj}$ and
    /// $\mathbf U$ the $n\times3$ stack of $\tilde{\mathbf c}_{u_k}$ and $-D\mathbf J_l^{-1}(\boldsymbol\theta_k)[\mathbf c_{\theta_k}]$:
    ///
    /// * $\partial\boldsymbol\rho/\partial\mathbf q^{jj} = \partial(\mathbf P^T\mathbf F)/\partial\mathbf q^{jj}|_{\mathbf F}
    ///   + \mathbf P^T[\mathbf F_q + \mathbf F_\nu\mathbf X\mathbf N_y + \mathbf M_{ffr}\boldsymbol\Xi]$,
    ///   $\boldsymbol\Xi = \mathbf X(\mathbf N_{\dot y} - \tilde{\mathbf N}_s + \mathbf Q_c) + (\mathbf X\mathbf U +
    ///   \mathbf P\mathbf W(\mathbf y))\boldsymbol\Omega_q + \mathbf X\mathbf N_y\mathbf T_j\mathbf N_y$, where
    ///   $\mathbf Q_c$ has the blocks $\mathbf Q(\boldsymbol\theta_k, \boldsymbol\zeta_{k,r}, \mathbf c_{\theta_k})$
    ///   ([`so3::left_jacobian_inv_second`]) on $\boldsymbol\theta_k$: the second derivative of
    ///   $\mathbf P\mathbf y$ along $\dot{\mathbf q}^{jj}$;
    /// * $\partial\boldsymbol\rho/\partial\mathbf y = \mathbf P^T[\mathbf F_\nu\mathbf P + \mathbf M_{ffr}\boldsymbol\Sigma]$,
    ///   $\boldsymbol\Sigma = -\mathbf P\,\mathrm{diag}(\tilde{\boldsymbol\Omega}) + \mathbf X\,\mathrm{diag}_\theta(D\mathbf J_l^{-1}[\mathbf c_{\theta_k}])
    ///   + (\mathbf X\mathbf U + \mathbf P\mathbf W(\mathbf y))\mathbf Y_r + \mathbf X\mathbf N_y\mathbf B$.
    ///
    /// Tested by `tests/unit/fd_tangent.rs::tangents_match_fd` (Exact, every frame choice) and
    /// `tests/unit/energy.rs` (power balance, rigid kinetic energy).
    pub(crate) fn exact_inertia(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, tangents: bool) {
        let n = self.n;
        let N = self.n_interfaces;
        let Om = mo.omega();
        let P = &kin.P;
        // nu = [xi; c]; ydot = a + W(y) Om.
        let mut nu = vec![0.0; 6 + n];
        nu[..6].copy_from_slice(&mo.xi);
        nu[6..].copy_from_slice(&mo.c);
        let mut ydot = mo.a.clone();
        for b in 0..2 * N {
            let yb = Vector3::new(mo.y[3 * b], mo.y[3 * b + 1], mo.y[3 * b + 2]);
            let v = yb.cross(&Om);
            for i in 0..3 {
                ydot[3 * b + i] += v[i];
            }
        }
        // nu_dot = P ydot + X N_y c. N_y is needed even without tangents: build it locally.
        let mut nu_dot = vec![0.0; 6 + n];
        for j in 0..n {
            for i in 0..6 + n {
                nu_dot[i] += P[(i, j)] * ydot[j];
            }
        }
        let (nb_owned, XNy_owned);
        let (nb, XNy) = if tangents {
            (&mo.n_y, &mo.XNy)
        } else {
            nb_owned = kin.n_y(&mo.y, &mo.xi);
            let mut m = Mat::zeros(6 + n, n);
            mul_blocks(kin.X.as_ref(), &nb_owned, &mut m, Accum::Replace);
            XNy_owned = m;
            (&nb_owned, &XNy_owned)
        };
        let _ = nb;
        for j in 0..n {
            for i in 0..6 + n {
                nu_dot[i] += XNy[(i, j)] * mo.c[j];
            }
        }
        let ffr = self.inertia.force(&kin.q_jj, &nu, &nu_dot, tangents);
        pt_mul(kin, &ffr.F, &mut loc.rho_in);
        if !tangents {
            let M = self.inertia.mass_matrix(&kin.q_jj);
            let mut MP = Mat::zeros(6 + n, n);
            gemm(&mut MP, M.as_ref(), P.as_ref(), 1.0, Accum::Replace);
            gemm(&mut loc.M, P.as_ref().transpose(), MP.as_ref(), 1.0, Accum::Replace);
            return;
        }
        let Mf = &ffr.M;
        let mut MP = Mat::zeros(6 + n, n);
        gemm(&mut MP, Mf.as_ref(), P.as_ref(), 1.0, Accum::Replace);
        gemm(&mut loc.M, P.as_ref().transpose(), MP.as_ref(), 1.0, Accum::Replace);

        let c = &mo.c;
        // s = Z N_y c (first six rows of XNy c).
        let mut s = [0.0; 6];
        for j in 0..n {
            for i in 0..6 {
                s[i] += XNy[(i, j)] * c[j];
            }
        }
        let mut xi_yd = [0.0; 6];
        for j in 0..n {
            for i in 0..6 {
                xi_yd[i] += P[(i, j)] * ydot[j];
            }
        }
        let Om_yd = Vector3::new(xi_yd[3], xi_yd[4], xi_yd[5]);
        let s_r = Vector3::new(s[3], s[4], s[5]);
        let mut blocks = Blocks::zeros(N);
        let mut dj = Blocks::zeros(N);
        let mut U = Mat::zeros(n, 3);
        for k in 0..N {
            let th = crate::local_coordinates::theta_of(&kin.q_jj, k);
            let yr = Vector3::new(mo.y[6 * k + 3], mo.y[6 * k + 4], mo.y[6 * k + 5]);
            let ydr = Vector3::new(ydot[6 * k + 3], ydot[6 * k + 4], ydot[6 * k + 5]);
            let cu = Vector3::new(c[6 * k], c[6 * k + 1], c[6 * k + 2]);
            let cth = Vector3::new(c[6 * k + 3], c[6 * k + 4], c[6 * k + 5]);
            blocks.t[k] = -skew(&Om_yd) - skew(&s_r);
            blocks.r[k] = so3::left_jacobian_inv_derivative(&th, &(ydr - Om_yd))
                - so3::left_jacobian_inv_derivative(&th, &s_r)
                + so3::left_jacobian_inv_second(&th, &(yr - Om), &cth);
            let DJ = so3::left_jacobian_inv_directional(&th, &cth);
            dj.r[k] = DJ;
            let cut = skew(&cu);
            for a in 0..3 {
                for b in 0..3 {
                    U[(6 * k + a, b)] = cut[(a, b)];
                    U[(6 * k + 3 + a, b)] = -DJ[(a, b)];
                }
            }
        }
        // XU + P W(y): (6+n) x 3.
        let W = w_stack(&mo.y, N);
        let mut XUPW = Mat::zeros(6 + n, 3);
        gemm(&mut XUPW, kin.X.as_ref(), U.as_ref(), 1.0, Accum::Replace);
        gemm(&mut XUPW, P.as_ref(), W.as_ref(), 1.0, Accum::Add);
        let Om_q = XNy.as_ref().subrows(3, 3);
        let TNy = XNy.as_ref().subrows(6, n);

        // Xi.
        let mut Xi = Mat::zeros(6 + n, n);
        mul_blocks(kin.X.as_ref(), &blocks, &mut Xi, Accum::Replace);
        gemm(&mut Xi, XUPW.as_ref(), Om_q, 1.0, Accum::Add);
        gemm(&mut Xi, XNy.as_ref(), TNy, 1.0, Accum::Add);
        // E = F_q + F_nu XNy + M_ffr Xi ; Dq += P^T E + d(P^T F).
        let mut E = ffr.F_q.clone();
        gemm(&mut E, ffr.F_nu.as_ref(), XNy.as_ref(), 1.0, Accum::Add);
        gemm(&mut E, Mf.as_ref(), Xi.as_ref(), 1.0, Accum::Add);
        gemm(&mut loc.Dq, P.as_ref().transpose(), E.as_ref(), 1.0, Accum::Add);
        kin.add_d_pt(&ffr.F, &mut loc.Dq, 1.0);

        // Sigma for d/dy.
        let mut om_blocks = Blocks::zeros(N);
        for k in 0..N {
            om_blocks.t[k] = -skew(&Om);
            om_blocks.r[k] = -skew(&Om);
        }
        let mut Sigma = Mat::zeros(6 + n, n);
        mul_blocks(P.as_ref(), &om_blocks, &mut Sigma, Accum::Replace);
        mul_blocks(kin.X.as_ref(), &dj, &mut Sigma, Accum::Add);
        gemm(&mut Sigma, XUPW.as_ref(), kin.Y().subrows(3, 3), 1.0, Accum::Add);
        gemm(&mut Sigma, XNy.as_ref(), kin.B(), 1.0, Accum::Add);
        let mut E2 = Mat::zeros(6 + n, n);
        gemm(&mut E2, ffr.F_nu.as_ref(), P.as_ref(), 1.0, Accum::Replace);
        gemm(&mut E2, Mf.as_ref(), Sigma.as_ref(), 1.0, Accum::Add);
        gemm(&mut loc.Dy, P.as_ref().transpose(), E2.as_ref(), 1.0, Accum::Add);
    }

    /// Inertia force of the `Lumped` variant.
    ///
    /// # Derivation
    /// The seed's (4.4) gives the mass matrix $\bar{\mathbf R}\mathbf M_{CB}\bar{\mathbf R}^T$ and
    /// leaves $\mathbf Q_v$ to "lumping" the reduced mass. We read this as: the reduced mass is
    /// carried by the interface coordinates themselves, measured in the body axes, i.e. the
    /// kinetic energy is $T_L = \tfrac12\mathbf y^T\mathbf M_{CB}\mathbf y$ with $\mathbf y =
    /// \bar{\mathbf R}^T\dot{\mathbf q}$ (the absolute interface velocities, not the elastic ones).
    /// Its mass matrix is the seed's, it is exact for any rigid motion (the CB basis reproduces
    /// rigid motions, so $\boldsymbol\Phi_{rig}^T\mathbf M_{CB}\boldsymbol\Phi_{rig}$ is the rigid
    /// mass matrix), and it differs from the exact $T$ only in how the convective velocity of
    /// the deformed body is interpolated (by the constraint modes from the interfaces). The
    /// quadratic velocity force then follows from Lagrange's equations on $(\mathbb R^3\times SO(3))^N$
    /// with spatial angular velocities, $\mathbf f = \dot{\mathbf p} + [\mathbf p_{\omega_k}\times\boldsymbol\omega_k]
    /// - \partial T/\partial\mathbf q$ (the middle term from $\delta\boldsymbol\omega = \delta\dot{\boldsymbol\pi} - \boldsymbol\omega\times\delta\boldsymbol\pi$),
    /// with $\mathbf p = \bar{\mathbf R}\mathbf M_{CB}\mathbf y$ and $T_L$ depending on $\mathbf q$ only
    /// through $\mathbf R_j$ ($\delta\boldsymbol\Pi = \mathbf Y_r\bar{\mathbf R}^T\delta\mathbf q$). In body axes,
    /// with $\boldsymbol\Omega = \mathbf Y_r\mathbf y$ and $\mathbf p^L = \mathbf M_{CB}\mathbf y$:
    ///
    /// $$\boldsymbol\rho_{in} = \mathbf M_{CB}\mathbf a + \mathbf M_{CB}\mathbf W(\mathbf y)\boldsymbol\Omega
    /// + [\boldsymbol\Omega\times\mathbf p^L_b]_b + [\mathbf p^L_{\theta_k}\times\mathbf y_{\theta_k}]_k
    /// - \mathbf Y_r^T\mathbf W(\mathbf y)^T\mathbf p^L.$$
    ///
    /// A single rigid body at its interface gives $m\mathbf R^T\ddot{\mathbf r}$ and Euler's
    /// $\mathbf J\dot{\boldsymbol\Omega} + \boldsymbol\Omega\times\mathbf J\boldsymbol\Omega$; the power
    /// $\mathbf y^T\boldsymbol\rho_{in} = \dot T_L$ (the last three terms do no work). Partials:
    /// $\partial/\partial\mathbf q^{jj} = (\mathbf M_{CB}\mathbf W(\mathbf y) - \mathbf W(\mathbf p^L))\boldsymbol\Omega_q
    /// - \partial(\mathbf Y_r^T\mathbf w)/\partial\mathbf q^{jj}|_{\mathbf w = \mathbf W^T\mathbf p^L}$ and
    /// $\partial/\partial\mathbf y = -\mathbf M_{CB}\,\mathrm{diag}(\tilde{\boldsymbol\Omega}) + \mathrm{diag}(\tilde{\boldsymbol\Omega})\mathbf M_{CB}
    /// + (\mathbf M_{CB}\mathbf W(\mathbf y) - \mathbf W(\mathbf p^L))\mathbf Y_r + [-\tilde{\mathbf y}_{\theta_k}(\mathbf M_{CB})_{\theta_k\cdot}
    /// + \tilde{\mathbf p}^L_{\theta_k}\mathbf E^\theta_k]_k + \mathbf Y_r^T(\mathbf W(\mathbf p^L)^T - \mathbf W(\mathbf y)^T\mathbf M_{CB})$.
    /// Tested by `tests/unit/fd_tangent.rs::tangents_match_fd` (Lumped) and `tests/unit/energy.rs`.
    pub(crate) fn lumped_inertia(&self, kin: &Kinematics, mo: &Motion, loc: &mut Local, tangents: bool) {
        let n = self.n;
        let N = self.n_interfaces;
        let M = &self.M_CB;
        let Om = mo.omega();
        let y = &mo.y;
        let mut p = vec![0.0; n];
        crate::mass::matvec(M, y, &mut p);
        // W(y) Om : block b = y_b x Om.
        let mut wo = vec![0.0; n];
        for b in 0..2 * N {
            let yb = Vector3::new(y[3 * b], y[3 * b + 1], y[3 * b + 2]);
            let v = yb.cross(&Om);
            wo[3 * b..3 * b + 3].copy_from_slice(v.as_slice());
        }
        let mut rho = vec![0.0; n];
        let mut tmp = vec![0.0; n];
        crate::mass::matvec(M, &mo.a, &mut rho);
        crate::mass::matvec(M, &wo, &mut tmp);
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
            rho[j] += tmp[j] - (Y[(3, j)] * wtp[0] + Y[(4, j)] * wtp[1] + Y[(5, j)] * wtp[2]);
        }
        loc.rho_in.copy_from_slice(&rho);
        for j in 0..n {
            for i in 0..n {
                loc.M[(i, j)] = M[(i, j)];
            }
        }
        if !tangents {
            return;
        }
        let Wy = w_stack(y, N);
        let Wp = w_stack(&p, N);
        // MW - W(p): n x 3.
        let mut MWW = Wp.clone();
        gemm(&mut MWW, M.as_ref(), Wy.as_ref(), 1.0, Accum::Replace);
        for j in 0..3 {
            for i in 0..n {
                MWW[(i, j)] -= Wp[(i, j)];
            }
        }
        let Om_q = mo.XNy.as_ref().subrows(3, 3);
        gemm(&mut loc.Dq, MWW.as_ref(), Om_q, 1.0, Accum::Add);
        let mut F = vec![0.0; 6 + n];
        F[3..6].copy_from_slice(wtp.as_slice());
        kin.add_d_pt(&F, &mut loc.Dq, -1.0);

        // d/dy.
        let Yr = Y.subrows(3, 3);
        gemm(&mut loc.Dy, MWW.as_ref(), Yr, 1.0, Accum::Add);
        let Ot = skew(&Om);
        let mut ob = Blocks::zeros(N);
        for k in 0..N {
            ob.t[k] = -Ot;
            ob.r[k] = -Ot;
        }
        // -M diag(Om~)
        mul_blocks(M.as_ref(), &ob, &mut loc.Dy, Accum::Add);
        // diag(Om~) M
        for b in 0..2 * N {
            for j in 0..n {
                let col = Vector3::new(M[(3 * b, j)], M[(3 * b + 1, j)], M[(3 * b + 2, j)]);
                let v = Ot * col;
                for i in 0..3 {
                    loc.Dy[(3 * b + i, j)] += v[i];
                }
            }
        }
        for k in 0..N {
            let yr = skew(&Vector3::new(y[6 * k + 3], y[6 * k + 4], y[6 * k + 5]));
            let pr = skew(&Vector3::new(p[6 * k + 3], p[6 * k + 4], p[6 * k + 5]));
            for j in 0..n {
                let col = Vector3::new(M[(6 * k + 3, j)], M[(6 * k + 4, j)], M[(6 * k + 5, j)]);
                let v = yr * col;
                for i in 0..3 {
                    loc.Dy[(6 * k + 3 + i, j)] -= v[i];
                }
            }
            for a in 0..3 {
                for b in 0..3 {
                    loc.Dy[(6 * k + 3 + a, 6 * k + 3 + b)] += pr[(a, b)];
                }
            }
        }
        // Y_r^T (W(p)^T - W(y)^T M)
        let mut R3 = Wp.transpose().to_owned();
        gemm(&mut R3, Wy.as_ref().transpose(), M.as_ref(), -1.0, Accum::Add);
        gemm(&mut loc.Dy, Yr.transpose(), R3.as_ref(), 1.0, Accum::Add);
        let _ = Matrix3::<f64>::zeros();
    }
}
