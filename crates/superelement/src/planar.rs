//! The planar AIC-FFR body: the superelement evaluated in its FE model's xy-plane
//! ([`crate::Superelement::into_planar`]; theory guide, "Planar bodies").
//!
//! # Coordinates
//!
//! A planar body keeps, of the $6N + m$ coordinates of the spatial one, the index set
//! $\mathcal I$ = {x, y and the rotation about z of every interface} $\cup$ {modes}: $3N + m$
//! coordinates $\mathbf q = [\mathbf r_1, \varphi_1, \dots, \mathbf r_N, \varphi_N, \boldsymbol\eta]$,
//! $\mathbf r_k \in \mathbb R^2$, $\varphi_k$ the angle of $\mathbf R_k$ about z. The floating frame
//! is $\mathbf r_j \in \mathbb R^2$, $\varphi_j$, with $\mathbf R_j = \mathbf R(\varphi_j)$, and the
//! local CB coordinates are
//!
//! $$\mathbf u_k = \mathbf R_j^T(\mathbf r_k - \mathbf r_j) - \mathbf x_k,\qquad
//! \theta_k = \varphi_k - \varphi_j \ \text{(wrapped to } (-\pi, \pi]),$$
//!
//! so $\boldsymbol\Lambda = \mathbf I$ exactly. With $\boldsymbol\rho_k = \mathbf x_k + \mathbf u_k$,
//! $\mathbf E = [0, -1; 1, 0]$ and the local frame variation $\delta\boldsymbol\Xi =
//! [\mathbf R_j^T\delta\mathbf r_j;\ \delta\varphi_j]$: $\delta\mathbf q^{jj} = \bar{\mathbf R}^T\delta\mathbf q -
//! \boldsymbol\Psi\delta\boldsymbol\Xi$, $\boldsymbol\Psi$ with rows $[\mathbf I_2,\ \mathbf E\boldsymbol\rho_k]$
//! on $\mathbf u_k$ and $[0, 0, 1]$ on $\theta_k$ (the planar $\boldsymbol\Phi_{rig}$ of (5.2)); (4.4)
//! (3 rows of $\boldsymbol\Phi_j$) gives $\mathbf Z_j = (\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}\boldsymbol\Phi_j$,
//! $\mathbf T_j = \mathbf I - \boldsymbol\Psi\mathbf Z_j$ and $\mathbf P = [\mathbf Z_j; \mathbf T_j]$ as in 3D.
//!
//! # Accelerations
//!
//! With $\mathbf y = \bar{\mathbf R}^T\dot{\mathbf q}$, $\boldsymbol\nu = [\mathbf V; \Omega; \dot{\mathbf q}^{jj}]
//! = \mathbf P\mathbf y$. Differentiating in time ($\dot{\boldsymbol\Psi}$ holds $\mathbf E\dot{\mathbf u}_k$,
//! $\dot{\mathbf R}_j^T = -\Omega\mathbf E\mathbf R_j^T$) gives $\dot{\mathbf P}\mathbf y = -\mathbf P\mathbf w$,
//! $\mathbf w_{u_k} = \Omega\mathbf E\dot{\mathbf u}_k$, hence
//!
//! $$\dot{\boldsymbol\nu} = \mathbf P\bar{\mathbf y},\qquad \bar{\mathbf y}_{u_k} = \mathbf R_j^T\mathbf a_k -
//! \Omega\mathbf E(\mathbf y_{u_k} + \dot{\mathbf u}_k),\quad \bar{\mathbf y}_{\theta_k} = \ddot\varphi_k,\quad
//! \bar{\mathbf y}_\eta = \ddot{\boldsymbol\eta}.$$
//!
//! # Forces
//!
//! The kinetic energy is the spatial one (`crate::mass`) restricted to planar motion:
//! $T = \tfrac12 m|\mathbf V|^2 + \Omega\,\mathbf V\cdot\mathbf E\mathbf s + \mathbf V\cdot\mathbf S_t\dot{\mathbf q} +
//! \tfrac12 J\Omega^2 + \Omega\,\mathbf c\cdot\dot{\mathbf q} + \tfrac12\dot{\mathbf q}^T\mathbf M_{CB}\dot{\mathbf q}$
//! with $\mathbf s = m\mathbf d + \mathbf S_t\mathbf q$ (x, y rows), $J = J_{0,zz} + 2\mathbf a\cdot\mathbf q +
//! \mathbf q^T\mathbf W\mathbf q$ ($\mathbf a = (\mathbf S_x)_{xx} + (\mathbf S_x)_{yy}$, $\mathbf W = \bar{\mathbf S}_{xx} +
//! \bar{\mathbf S}_{yy}$), $\mathbf c = (\mathbf S_r)_z^T - \tilde{\mathbf S}_z\mathbf q$. Lagrange's equations in
//! $(\mathbf r_j, \varphi_j, \mathbf q^{jj})$ (true coordinates in the plane) give the body-axis force
//!
//! * $F_V = m\dot{\mathbf V} + \mathbf E\mathbf s\,\dot\Omega + \mathbf E\dot{\mathbf s}\,\Omega + \mathbf S_t\ddot{\mathbf q} + \Omega\mathbf E\mathbf p_V$, $\mathbf p_V = m\mathbf V + \mathbf E\mathbf s\,\Omega + \dot{\mathbf s}$,
//! * $F_\Omega = \dot{\mathbf V}\cdot\mathbf E\mathbf s + J\dot\Omega + \mathbf c\cdot\ddot{\mathbf q} + \dot J\Omega + \Omega\,\mathbf V\cdot\mathbf s$,
//! * $\mathbf F_q = \mathbf S_t^T(\dot{\mathbf V} + \Omega\mathbf E\mathbf V) + \mathbf c\,\dot\Omega + \mathbf M_{CB}\ddot{\mathbf q} - 2\Omega\tilde{\mathbf S}_z\dot{\mathbf q} - \Omega^2(\mathbf a + \mathbf W\mathbf q)$,
//!
//! the z rows of (6.4) on a planar motion. With the elastic force $\mathbf K_{CB}\mathbf q + \mathbf g_G$
//! (7.4)-(7.5), damping $\mathbf D\dot{\mathbf q}^{jj}$ (6.8) and gravity (x, y components; a z
//! component does no work in the plane and is ignored), the residual is $\bar{\mathbf R}\mathbf P^T\mathbf F$.
//!
//! # Tangents
//!
//! The residual is one generic function of $(\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q})$
//! (`PlanarBody::core` over the scalar trait `Scalar`: `f64` for the forces, the dual numbers of
//! `dual.rs` for $\mathbf K_t$, exact to round-off). The frame enters through the implicit
//! function: one Newton correction $\delta\boldsymbol\Xi = (\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}\boldsymbol\Phi_j\mathbf q^{jj}$
//! in dual numbers at the converged frame (value part zero) carries its exact derivative.
//! $\mathbf F$ is linear in $\dot{\boldsymbol\nu}$ with the matrix $\mathbf M_{ffr}$ (theory guide
//! (7.7)), so $\mathbf M = \bar{\mathbf R}\mathbf P^T\mathbf M_{ffr}\mathbf P\bar{\mathbf R}^T$, and $\mathbf C_t$
//! follows from the velocity terms of $\mathbf F$ and $\partial\bar{\mathbf y}/\partial\mathbf y$: both in
//! closed form (`PlanarBody::mass_damping`), cheaper than a dual pass each. Checked
//! against the spatial body (`tests/unit/planar.rs`) and central differences.

#![allow(non_snake_case)]

use crate::dual::{Dual, Scalar};
use crate::error::SuperelementError;
use crate::frame::{FrameChoice, FrameSettings, FrameSolve};
use crate::mass::{FfrInertia, MassVariant};
use crate::transform::RCOND_MIN;
use faer::Mat;
use nalgebra::{UnitQuaternion, Vector3};
use reduction::ReducedBody;
use std::f64::consts::PI;

/// Width of the dual numbers of the tangent passes: directions per pass.
const WIDTH: usize = 8;

/// Width of the single tangent pass of a body with more than [`WIDTH`] and at most this many
/// planar coordinates (one pass of 12 directions costs less than two of 8; every direction is
/// computed alike whatever the width, so $\mathbf K_t$ is the same to the bit).
const WIDE: usize = 12;

/// Relative size of a coupling between the in-plane and out-of-plane sets accepted by
/// [`crate::Superelement::into_planar`] (against the largest entry of the matrix).
pub const COUPLING_TOL: f64 = 1e-9;

/// Out-of-plane tilt of an interface orientation (about the x or y axis, radians) and offset of
/// an interface from the plane (relative to the body size) accepted in a state.
pub const STATE_TOL: f64 = 1e-9;

/// The 3D dof of in-plane interface dof `c` (x, y, rotation about z).
const IN_PLANE: [usize; 3] = [0, 1, 5];

/// The in-plane data of a planar body, precomputed by [`crate::Superelement::into_planar`].
#[derive(Clone, Debug)]
pub(crate) struct PlanarBody {
    pub N: usize,
    pub n: usize,
    /// Planar index -> index of the $6N + m$ layout.
    pub index: Vec<usize>,
    /// $\mathbf x_k$ (x, y).
    pub x: Vec<[f64; 2]>,
    /// Columns of $\boldsymbol\Phi_j$ (rows x, y, rz).
    pub Phi: Vec<[f64; 3]>,
    /// $\sum_k$ of the $u_{k,x}$ and $u_{k,y}$ columns of $\boldsymbol\Phi_j$.
    pub sum_u: [[f64; 3]; 2],
    /// Column-major $n\times n$.
    pub K: Vec<f64>,
    pub M: Vec<f64>,
    pub D: Vec<f64>,
    pub damped: bool,
    pub mass: f64,
    pub d: [f64; 2],
    pub J0: f64,
    /// $\mathbf S_t$ x, y rows by column.
    pub St: Vec<[f64; 2]>,
    /// $(\mathbf S_r)_z$.
    pub Srz: Vec<f64>,
    /// $(\mathbf S_x)_{xx} + (\mathbf S_x)_{yy}$.
    pub a: Vec<f64>,
    /// $\bar{\mathbf S}_{xx} + \bar{\mathbf S}_{yy}$, column-major.
    pub W: Vec<f64>,
    /// $\tilde{\mathbf S}_z = \bar{\mathbf S}_{xy} - \bar{\mathbf S}_{yx}$, column-major.
    pub Sz: Vec<f64>,
    pub geometric: Option<PlanarGeometric>,
}

/// A planar frame: position (x, y) and angle about z.
pub(crate) type Frame2 = ([f64; 2], f64);

/// A solved planar frame: the frame, the iterations and, after a Newton solve, $(\sin, \cos)$
/// of its angle.
pub(crate) type Solved2 = (Frame2, usize, Option<(f64, f64)>);

/// The nonzero entries $(i, j, (\mathbf G_k)_{ij})$ of one $\mathbf G_k$.
pub(crate) type Entries = Vec<(u32, u32, f64)>;

/// The planar $\mathbf G_k$ ($k \in \mathcal I$, restricted to $\mathcal I\times\mathcal I$) by their
/// nonzero entries, and $\mathbf F$ = the pseudo-inverse of the planar $\mathbf K_{CB}$.
#[derive(Clone, Debug)]
pub(crate) struct PlanarGeometric {
    /// The nonzero $\mathbf G_k$: $k$ and its entries $(i, j, (\mathbf G_k)_{ij})$.
    pub groups: Vec<(usize, Entries)>,
    pub F: Vec<f64>,
}

impl PlanarGeometric {
    /// $\mathbf g_G$ of $U_3 + U_4$ added to `fe`, with $\mathbf b$ and $\mathbf p = \mathbf F\mathbf b$ into `b`,
    /// `p`: $\mathbf g_G = \mathbf b + \sum_k (q_k + p_k)\mathbf G_k\mathbf q$, $b_k = \tfrac12\mathbf q^T\mathbf G_k\mathbf q$,
    /// with the products $\mathbf G_k\mathbf q$ of the nonzero $\mathbf G_k$ formed once (`gq`, one $n$-block
    /// each).
    #[inline(always)]
    fn gradient<S: Scalar>(&self, q: &[S], b: &mut [S], p: &mut [S], gq: &mut [S], fe: &mut [S]) {
        let n = q.len();
        b.fill(S::cst(0.0));
        for ((k, entries), g) in self.groups.iter().zip(gq.chunks_exact_mut(n)) {
            g.fill(S::cst(0.0));
            for &(i, j, v) in entries {
                let (i, j) = (i as usize, j as usize);
                g[i] = g[i].mul_add_f(q[j], v);
            }
            b[*k] = dot(q, g) * 0.5;
        }
        p.fill(S::cst(0.0));
        for (k, _) in &self.groups {
            let col = &self.F[n * k..n * (k + 1)];
            for (pi, f) in p.iter_mut().zip(col) {
                *pi = pi.mul_add_f(b[*k], *f);
            }
        }
        for (k, _) in &self.groups {
            fe[*k] += b[*k];
        }
        for ((k, _), g) in self.groups.iter().zip(gq.chunks_exact(n)) {
            let t = q[*k] + p[*k];
            for (f, gi) in fe.iter_mut().zip(g) {
                *f += t * *gi;
            }
        }
    }
}

/// Buffers of one generic evaluation.
#[derive(Clone, Debug)]
pub(crate) struct Buf<S> {
    pub q: Vec<S>,
    pub qd: Vec<S>,
    pub qdd: Vec<S>,
    pub qjj: Vec<S>,
    pub rho: Vec<[S; 2]>,
    pub y: Vec<S>,
    pub ybar: Vec<S>,
    pub zeta: Vec<S>,
    pub zetad: Vec<S>,
    pub Wq: Vec<S>,
    pub Sq: Vec<S>,
    pub Sz: Vec<S>,
    pub fq: Vec<S>,
    pub fe: Vec<S>,
    pub fd: Vec<S>,
    pub fg: Vec<S>,
    pub b: Vec<S>,
    pub p: Vec<S>,
    /// $\mathbf G_k\mathbf q$ of the nonzero $\mathbf G_k$ ([`PlanarGeometric::gradient`]).
    pub gq: Vec<S>,
    pub out: Vec<S>,
    /// The parts (f64 pass only): inertia, elastic, damping, gravity.
    pub parts: [Vec<S>; 4],
    pub Gi: [[S; 3]; 3],
    /// $\boldsymbol\xi = [\mathbf V; \Omega]$, $\mathbf s$, $\dot{\mathbf s}$, $J$, $\dot J$ of the
    /// last evaluation (the closed-form $\mathbf M$ and $\mathbf C_t$ read them).
    pub xi: [S; 3],
    pub sv: [S; 2],
    pub sd: [S; 2],
    pub J: S,
    pub Jd: S,
    pub R: (S, S),
    pub frame_r: [S; 2],
    pub frame_phi: S,
}

impl<S: Scalar> Buf<S> {
    pub(crate) fn new(N: usize, n: usize, groups: usize) -> Self {
        let z = || vec![S::cst(0.0); n];
        Self {
            q: z(),
            qd: z(),
            qdd: z(),
            qjj: z(),
            rho: vec![[S::cst(0.0); 2]; N],
            y: z(),
            ybar: z(),
            zeta: z(),
            zetad: z(),
            Wq: z(),
            Sq: z(),
            Sz: z(),
            fq: z(),
            fe: z(),
            fd: z(),
            fg: z(),
            b: z(),
            p: z(),
            gq: vec![S::cst(0.0); n * groups],
            out: z(),
            parts: [z(), z(), z(), z()],
            Gi: [[S::cst(0.0); 3]; 3],
            xi: [S::cst(0.0); 3],
            sv: [S::cst(0.0); 2],
            sd: [S::cst(0.0); 2],
            J: S::cst(0.0),
            Jd: S::cst(0.0),
            R: (S::cst(0.0), S::cst(1.0)),
            frame_r: [S::cst(0.0); 2],
            frame_phi: S::cst(0.0),
        }
    }
}

/// The planar part of a [`crate::Workspace`].
#[derive(Clone, Debug)]
pub(crate) struct PlanarWorkspace {
    pub f: Buf<f64>,
    pub d: Buf<Dual<WIDTH>>,
    /// The buffers of the single [`WIDE`] pass, for $[`WIDTH`] < n \le$ [`WIDE`].
    pub wide: Option<Buf<Dual<WIDE>>>,
    /// Interface positions (x, y) and raw angles of the state.
    pub pos: Vec<[f64; 2]>,
    pub phi: Vec<f64>,
    /// Planar tangents, column-major $n\times n$: $\mathbf K_t$, $\mathbf C_t$, $\mathbf M$.
    pub mats: [Vec<f64>; 3],
    /// Buffers of the closed-form $\mathbf M$ and $\mathbf C_t$ (`PlanarBody::mass_damping`):
    /// $\mathbf Z_j$, the coupling rows $\mathbf A_{\xi\zeta}$ and a scratch ($3n$ each), $6n$ and
    /// $\max(n^2, 6n)$.
    pub Z: Vec<f64>,
    pub Bx: Vec<f64>,
    pub scratch: Vec<f64>,
    pub six: Vec<f64>,
    pub big: Vec<f64>,
    /// The last warm-start orientation read or frame orientation returned (quaternion
    /// coordinates) and its angle about z ([`Self::warm_angle`]).
    pub warm: ([f64; 4], f64),
}

impl PlanarWorkspace {
    pub fn new(pb: &PlanarBody) -> Self {
        let (N, n) = (pb.N, pb.n);
        let groups = pb.geometric.as_ref().map_or(0, |G| G.groups.len());
        Self {
            f: Buf::new(N, n, groups),
            d: Buf::new(N, n, groups),
            wide: (n > WIDTH && n <= WIDE).then(|| Buf::new(N, n, groups)),
            pos: vec![[0.0; 2]; N],
            phi: vec![0.0; N],
            mats: [vec![0.0; n * n], vec![0.0; n * n], vec![0.0; n * n]],
            Z: vec![0.0; 3 * n],
            Bx: vec![0.0; 3 * n],
            scratch: vec![0.0; 3 * n],
            six: vec![0.0; 6 * n],
            big: vec![0.0; (n * n).max(6 * n)],
            warm: ([f64::NAN; 4], f64::NAN),
        }
    }

    /// The angle about z of the warm-start orientation `R`: when `R` is (to the bit) the
    /// orientation of the frame this workspace last returned ([`Self::returned`]; a system
    /// passes each evaluation's frame back as the next warm start) that frame's angle, else
    /// [`angle_of`] `R` (kept for the next call). The two differ by round-off only.
    pub fn warm_angle(&mut self, R: &UnitQuaternion<f64>) -> f64 {
        let c = [R.coords[0], R.coords[1], R.coords[2], R.coords[3]];
        if c != self.warm.0 {
            self.warm = (c, angle_of(R));
        }
        self.warm.1
    }

    /// Records the frame orientation `R` = [`rotation_z`]`(phi)` an evaluation returned, for
    /// [`Self::warm_angle`] (`phi` wrapped to $(-\pi, \pi]$ as [`angle_of`]).
    pub fn returned(&mut self, R: &UnitQuaternion<f64>, phi: f64) {
        self.warm = ([R.coords[0], R.coords[1], R.coords[2], R.coords[3]], wrap(phi));
    }
}

/// $x$ wrapped to $(-\pi, \pi]$.
#[inline]
pub(crate) fn wrap(x: f64) -> f64 {
    if x > -PI && x <= PI {
        return x;
    }
    let t = (x + PI).rem_euclid(2.0 * PI) - PI;
    if t <= -PI {
        t + 2.0 * PI
    } else {
        t
    }
}

/// The angle about z of a rotation (atan2 of its first column).
#[inline]
pub(crate) fn angle_of(R: &UnitQuaternion<f64>) -> f64 {
    let (x, y, z, w) = (R.coords[0], R.coords[1], R.coords[2], R.coords[3]);
    let c0 = w * w + x * x - y * y - z * z;
    let c1 = 2.0 * (x * y + w * z);
    c1.atan2(c0)
}

/// The rotation by `phi` about z.
pub(crate) fn rotation_z(phi: f64) -> UnitQuaternion<f64> {
    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), phi)
}

/// $\mathbf G^{-1}$ of a $3\times3$ (rows) and its determinant.
#[inline(always)]
fn inv3<S: Scalar>(G: &[[S; 3]; 3]) -> ([[S; 3]; 3], S) {
    let c = |r0: usize, c0: usize, r1: usize, c1: usize| G[r0][c0] * G[r1][c1] - G[r0][c1] * G[r1][c0];
    let c00 = c(1, 1, 2, 2);
    let c01 = c(1, 2, 2, 0);
    let c02 = c(1, 0, 2, 1);
    let det = G[0][0] * c00 + G[0][1] * c01 + G[0][2] * c02;
    let id = det.recip();
    let inv = [
        [c00 * id, c(0, 2, 2, 1) * id, c(0, 1, 1, 2) * id],
        [c01 * id, c(0, 0, 2, 2) * id, c(0, 2, 1, 0) * id],
        [c02 * id, c(0, 1, 2, 0) * id, c(0, 0, 1, 1) * id],
    ];
    (inv, det)
}

/// $\bar{\mathbf R}\mathbf A\bar{\mathbf R}^T$ of a column-major $n\times n$ `A` in place: the
/// $2\times2$ blocks of rows and of columns of each interface, `R` = $(\sin, \cos)$ of the frame.
#[inline(always)]
fn rotate(A: &mut [f64], n: usize, N: usize, R: (f64, f64)) {
    let (s, c) = R;
    for j in 0..n {
        let col = &mut A[n * j..n * (j + 1)];
        for k in 0..N {
            let (x, y) = (col[3 * k], col[3 * k + 1]);
            col[3 * k] = c * x - s * y;
            col[3 * k + 1] = s * x + c * y;
        }
    }
    for k in 0..N {
        let (cx, cy) = A[n * 3 * k..n * (3 * k + 2)].split_at_mut(n);
        for (x, y) in cx.iter_mut().zip(cy.iter_mut()) {
            let (a, b) = (*x, *y);
            *x = c * a - s * b;
            *y = s * a + c * b;
        }
    }
}

/// $\mathbf A\mathbf v$ for a column-major $n\times n$ `A`, into `out`.
#[inline(always)]
fn matvec<S: Scalar>(A: &[f64], v: &[S], out: &mut [S]) {
    let n = v.len();
    if S::DUAL {
        // Row by row: each dual sum stays in registers (the columns would load and store the
        // output's derivative parts at every term).
        for (i, o) in out.iter_mut().enumerate() {
            let mut acc = S::cst(0.0);
            for (j, vj) in v.iter().enumerate() {
                acc = acc.mul_add_f(*vj, A[i + n * j]);
            }
            *o = acc;
        }
        return;
    }
    out.fill(S::cst(0.0));
    for (j, vj) in v.iter().enumerate() {
        let col = &A[n * j..n * (j + 1)];
        for (o, a) in out.iter_mut().zip(col) {
            *o = o.mul_add_f(*vj, *a);
        }
    }
}

/// Three matrix-vector products with one vector, `out[c] = A[c] v` ([`matvec`]); for dual numbers
/// in one pass over the rows, each term of `v` loaded once.
#[inline(always)]
fn matvec3<S: Scalar>(A: [&[f64]; 3], v: &[S], out: [&mut [S]; 3]) {
    let n = v.len();
    if S::DUAL {
        let [o0, o1, o2] = out;
        for i in 0..n {
            let mut acc = [S::cst(0.0); 3];
            for (j, vj) in v.iter().enumerate() {
                for c in 0..3 {
                    acc[c] = acc[c].mul_add_f(*vj, A[c][i + n * j]);
                }
            }
            o0[i] = acc[0];
            o1[i] = acc[1];
            o2[i] = acc[2];
        }
        return;
    }
    for (a, o) in A.into_iter().zip(out) {
        matvec(a, v, o);
    }
}

#[inline(always)]
fn dot<S: Scalar>(a: &[S], b: &[S]) -> S {
    let mut s = S::cst(0.0);
    for (x, y) in a.iter().zip(b) {
        s += *x * *y;
    }
    s
}

impl PlanarBody {
    /// $\boldsymbol\Phi_j\mathbf v$ (3 rows).
    #[inline(always)]
    fn phi_mul<S: Scalar>(&self, v: &[S]) -> [S; 3] {
        let mut g = [S::cst(0.0); 3];
        for (c, vc) in self.Phi.iter().zip(v) {
            for a in 0..3 {
                g[a] = g[a].mul_add_f(*vc, c[a]);
            }
        }
        g
    }

    /// $\mathbf q^{jj}$ and $\boldsymbol\rho_k$ for the frame in `b` (`frame_r`, `R`, `frame_phi`).
    #[inline(always)]
    fn local<S: Scalar>(&self, b: &mut Buf<S>) {
        let (s, c) = b.R;
        for k in 0..self.N {
            let dx = b.q[3 * k] - b.frame_r[0];
            let dy = b.q[3 * k + 1] - b.frame_r[1];
            let rx = c * dx + s * dy;
            let ry = c * dy - s * dx;
            b.rho[k] = [rx, ry];
            b.qjj[3 * k] = rx - S::cst(self.x[k][0]);
            b.qjj[3 * k + 1] = ry - S::cst(self.x[k][1]);
            b.qjj[3 * k + 2] = b.q[3 * k + 2] - b.frame_phi;
        }
        for i in 3 * self.N..self.n {
            b.qjj[i] = b.q[i];
        }
    }

    /// $\boldsymbol\Phi_j\boldsymbol\Psi$ for the deformed positions `rho` (rows).
    #[inline(always)]
    fn phi_psi<S: Scalar>(&self, rho: &[[S; 2]]) -> [[S; 3]; 3] {
        let mut col2 = [S::cst(0.0); 3];
        for (k, r) in rho.iter().enumerate() {
            let (px, py, pt) = (&self.Phi[3 * k], &self.Phi[3 * k + 1], &self.Phi[3 * k + 2]);
            for a in 0..3 {
                col2[a] += r[0] * py[a] - r[1] * px[a] + S::cst(pt[a]);
            }
        }
        std::array::from_fn(|a| [S::cst(self.sum_u[0][a]), S::cst(self.sum_u[1][a]), col2[a]])
    }

    /// $\boldsymbol\zeta = \mathbf v - \boldsymbol\Psi\boldsymbol\xi$ into `out`.
    #[inline(always)]
    fn minus_psi<S: Scalar>(&self, rho: &[[S; 2]], v: &[S], xi: &[S; 3], out: &mut [S]) {
        for (k, r) in rho.iter().enumerate() {
            out[3 * k] = v[3 * k] - (xi[0] - xi[2] * r[1]);
            out[3 * k + 1] = v[3 * k + 1] - (xi[1] + xi[2] * r[0]);
            out[3 * k + 2] = v[3 * k + 2] - xi[2];
        }
        out[3 * self.N..].copy_from_slice(&v[3 * self.N..]);
    }

    /// $\bar{\mathbf R}\mathbf P^T[\mathbf f_\xi; \mathbf f_\zeta]$ into `out`:
    /// $\mathbf f_\zeta + \boldsymbol\Phi_j^T\mathbf G^{-T}(\mathbf f_\xi - \boldsymbol\Psi^T\mathbf f_\zeta)$, rotated.
    #[inline(always)]
    fn project<S: Scalar>(&self, rho: &[[S; 2]], Gi: &[[S; 3]; 3], R: (S, S), fxi: [S; 3], fz: &[S], out: &mut [S]) {
        let mut h = fxi;
        for (k, r) in rho.iter().enumerate() {
            let (fx, fy, ft) = (fz[3 * k], fz[3 * k + 1], fz[3 * k + 2]);
            h[0] -= fx;
            h[1] -= fy;
            h[2] -= r[0] * fy - r[1] * fx + ft;
        }
        let l: [S; 3] = std::array::from_fn(|c| Gi[0][c] * h[0] + Gi[1][c] * h[1] + Gi[2][c] * h[2]);
        for (i, (o, ph)) in out.iter_mut().zip(&self.Phi).enumerate() {
            *o = fz[i] + l[0] * ph[0] + l[1] * ph[1] + l[2] * ph[2];
        }
        let (s, c) = R;
        for k in 0..self.N {
            let (x, y) = (out[3 * k], out[3 * k + 1]);
            out[3 * k] = c * x - s * y;
            out[3 * k + 1] = s * x + c * y;
        }
    }

    /// The generic residual: `b.q`, `b.qd`, `b.qdd` (planar absolute coordinates, velocities,
    /// accelerations) at the converged frame `frame` (with `Gi0` = its
    /// $(\boldsymbol\Phi_j\boldsymbol\Psi)^{-1}$ for the implicit derivative; `sc`: $(\sin, \cos)$ of
    /// the frame angle when known, [`Self::newton`]) into `b.out`, and with `parts` the four force
    /// parts into `b.parts`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn core<S: Scalar>(
        &self,
        b: &mut Buf<S>,
        frame: ([f64; 2], f64),
        sc: Option<(f64, f64)>,
        solve: FrameSolve,
        Gi0: &[[f64; 3]; 3],
        gravity: [f64; 2],
        parts: bool,
    ) {
        let N = self.N;
        let n = self.n;
        // The frame: explicit at an interface, else the converged one plus (dual numbers) its
        // implicit derivative.
        match solve {
            FrameSolve::AtInterface(k) => {
                b.frame_r = [b.q[3 * k], b.q[3 * k + 1]];
                b.frame_phi = b.q[3 * k + 2];
                b.R = b.frame_phi.sin_cos();
            }
            FrameSolve::Newton => {
                b.frame_r = [S::cst(frame.0[0]), S::cst(frame.0[1])];
                b.frame_phi = S::cst(frame.1);
                let (s0, c0) = sc.unwrap_or_else(|| frame.1.sin_cos());
                b.R = (S::cst(s0), S::cst(c0));
                if S::DUAL {
                    self.local(b);
                    let g = self.phi_mul(&b.qjj);
                    let d: [S; 3] = std::array::from_fn(|a| {
                        (g[0] * Gi0[a][0] + g[1] * Gi0[a][1] + g[2] * Gi0[a][2]).infinitesimal()
                    });
                    b.frame_r[0] += d[0] * c0 - d[1] * s0;
                    b.frame_r[1] += d[0] * s0 + d[1] * c0;
                    b.frame_phi += d[2];
                    b.R = b.frame_phi.sin_cos();
                }
            }
        }
        self.local(b);
        // The buffers as separate slices (no reloads of the vectors through `b` in the loops).
        let Buf {
            qd,
            qdd,
            qjj,
            rho,
            y,
            ybar,
            zeta,
            zetad,
            Wq,
            Sq,
            Sz,
            fq,
            fe,
            fd,
            fg,
            b: bv,
            p: pv,
            gq,
            out,
            parts: pparts,
            Gi: bGi,
            xi: bxi,
            sv: bsv,
            sd: bsd,
            J: bJ,
            Jd: bJd,
            R: bR,
            ..
        } = b;
        let (qd, qdd, qjj, rho) = (&qd[..n], &qdd[..n], &qjj[..n], &rho[..N]);
        let (y, ybar, zeta, zetad) = (&mut y[..n], &mut ybar[..n], &mut zeta[..n], &mut zetad[..n]);
        let (Wq, Sq, Sz, fq) = (&mut Wq[..n], &mut Sq[..n], &mut Sz[..n], &mut fq[..n]);
        let (fe, fd, fg, out) = (&mut fe[..n], &mut fd[..n], &mut fg[..n], &mut out[..n]);
        let (s, c) = *bR;
        // y and a in body axes (a into ybar).
        for k in 0..N {
            let (vx, vy) = (qd[3 * k], qd[3 * k + 1]);
            y[3 * k] = c * vx + s * vy;
            y[3 * k + 1] = c * vy - s * vx;
            y[3 * k + 2] = qd[3 * k + 2];
            let (ax, ay) = (qdd[3 * k], qdd[3 * k + 1]);
            ybar[3 * k] = c * ax + s * ay;
            ybar[3 * k + 1] = c * ay - s * ax;
            ybar[3 * k + 2] = qdd[3 * k + 2];
        }
        // The modal rows (a few: a loop, not a memcpy call).
        #[allow(clippy::manual_memcpy)]
        for i in 3 * N..n {
            y[i] = qd[i];
            ybar[i] = qdd[i];
        }
        let (Gi, _) = inv3(&self.phi_psi(rho));
        *bGi = Gi;
        let py = self.phi_mul(y);
        let xi: [S; 3] = std::array::from_fn(|a| Gi[a][0] * py[0] + Gi[a][1] * py[1] + Gi[a][2] * py[2]);
        self.minus_psi(rho, y, &xi, zeta);
        let om = xi[2];
        for k in 0..N {
            let (yx, yy) = (y[3 * k], y[3 * k + 1]);
            let (zx, zy) = (zeta[3 * k], zeta[3 * k + 1]);
            ybar[3 * k] += om * (yy + zy);
            ybar[3 * k + 1] -= om * (yx + zx);
        }
        let pa = self.phi_mul(ybar);
        let xid: [S; 3] = std::array::from_fn(|a| Gi[a][0] * pa[0] + Gi[a][1] * pa[1] + Gi[a][2] * pa[2]);
        self.minus_psi(rho, ybar, &xid, zetad);

        // FFR inertia (module docs).
        let q = qjj;
        let m = self.mass;
        let mut sv = [S::cst(m * self.d[0]), S::cst(m * self.d[1])];
        let mut sd = [S::cst(0.0); 2];
        let mut std_ = [S::cst(0.0); 2];
        for (i, st) in self.St.iter().enumerate() {
            for a in 0..2 {
                sv[a] = sv[a].mul_add_f(q[i], st[a]);
                sd[a] = sd[a].mul_add_f(zeta[i], st[a]);
                std_[a] = std_[a].mul_add_f(zetad[i], st[a]);
            }
        }
        matvec3([&self.W, &self.Sz, &self.K], q, [Wq, Sq, fe]);
        matvec(&self.Sz, zeta, Sz);
        let mut J = S::cst(self.J0);
        let mut Jd = S::cst(0.0);
        let mut cz = S::cst(0.0);
        for i in 0..n {
            let ai = S::cst(self.a[i]);
            J += (ai * 2.0 + Wq[i]) * q[i];
            Jd += (ai + Wq[i]) * zeta[i] * 2.0;
            // c = S_rz - S~_z q.
            cz += (S::cst(self.Srz[i]) - Sq[i]) * zetad[i];
        }
        *bxi = xi;
        *bsv = sv;
        *bsd = sd;
        *bJ = J;
        *bJd = Jd;
        let (V, Vd) = ([xi[0], xi[1]], [xid[0], xid[1]]);
        let omd = xid[2];
        let Es = [-sv[1], sv[0]];
        let Esd = [-sd[1], sd[0]];
        let pV = [V[0] * m + Es[0] * om + sd[0], V[1] * m + Es[1] * om + sd[1]];
        let EpV = [-pV[1], pV[0]];
        let FV: [S; 2] = std::array::from_fn(|a| Vd[a] * m + Es[a] * omd + Esd[a] * om + std_[a] + om * EpV[a]);
        let FO = Vd[0] * Es[0] + Vd[1] * Es[1] + J * omd + cz + Jd * om + om * (V[0] * sv[0] + V[1] * sv[1]);
        let Vt = [Vd[0] - om * V[1], Vd[1] + om * V[0]];
        matvec(&self.M, zetad, fq);
        let om2 = om * om;
        let two_om = om * 2.0;
        for i in 0..n {
            let st = &self.St[i];
            let ci = S::cst(self.Srz[i]) - Sq[i];
            fq[i] += Vt[0] * st[0] + Vt[1] * st[1] + ci * omd - two_om * Sz[i] - om2 * (S::cst(self.a[i]) + Wq[i]);
        }
        // Elastic force with geometric stiffening (K q formed above).
        if let Some(G) = &self.geometric {
            G.gradient(q, bv, pv, gq, fe);
        }
        // Damping.
        if self.damped {
            matvec(&self.D, zeta, fd);
        }
        // Gravity (x, y).
        let gL = [c * gravity[0] + s * gravity[1], c * gravity[1] - s * gravity[0]];
        let Fg = [gL[0] * m, gL[1] * m, Es[0] * gL[0] + Es[1] * gL[1]];
        for (f, st) in fg.iter_mut().zip(&self.St) {
            *f = gL[0] * st[0] + gL[1] * st[1];
        }
        let FI = [FV[0], FV[1], FO];
        let R = *bR;
        if parts {
            let zero = [S::cst(0.0); 3];
            let [pi, pe, pd, pg] = pparts;
            self.project(rho, &Gi, R, FI, fq, pi);
            self.project(rho, &Gi, R, zero, fe, pe);
            if self.damped {
                self.project(rho, &Gi, R, zero, fd, pd);
            } else {
                pd.fill(S::cst(0.0));
            }
            self.project(rho, &Gi, R, Fg, fg, pg);
            for i in 0..n {
                out[i] = pi[i] + pe[i] + pd[i] - pg[i];
            }
        } else {
            for i in 0..n {
                let mut f = fq[i] + fe[i] - fg[i];
                if self.damped {
                    f += fd[i];
                }
                fq[i] = f;
            }
            let fxi = [FI[0] - Fg[0], FI[1] - Fg[1], FI[2] - Fg[2]];
            self.project(rho, &Gi, R, fxi, fq, out);
        }
    }

    /// [`Self::core`] in `f64` with the force parts (the residual of an evaluation), compiled for
    /// the machine's vector instructions.
    pub(crate) fn forces(
        &self,
        b: &mut Buf<f64>,
        frame: ([f64; 2], f64),
        sc: Option<(f64, f64)>,
        solve: FrameSolve,
        gravity: [f64; 2],
    ) {
        struct Pass<'a> {
            pb: &'a PlanarBody,
            b: &'a mut Buf<f64>,
            frame: ([f64; 2], f64),
            sc: Option<(f64, f64)>,
            solve: FrameSolve,
            gravity: [f64; 2],
        }
        impl pulp::WithSimd for Pass<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                let Gi0 = [[0.0; 3]; 3];
                self.pb
                    .core(self.b, self.frame, self.sc, self.solve, &Gi0, self.gravity, true);
            }
        }
        pulp::Arch::new().dispatch(Pass {
            pb: self,
            b,
            frame,
            sc,
            solve,
            gravity,
        });
    }

    /// $\mathbf K_t$ (planar, `pw.mats[0]`): the derivative of the residual in the planar
    /// coordinates by dual numbers, [`WIDTH`] directions per pass (one pass of [`WIDE`] for
    /// $n \le$ [`WIDE`]), compiled for the machine's vector instructions.
    pub(crate) fn stiffness_pass(
        &self,
        pw: &mut PlanarWorkspace,
        frame: ([f64; 2], f64),
        sc: Option<(f64, f64)>,
        solve: FrameSolve,
        Gi0: &[[f64; 3]; 3],
        gravity: [f64; 2],
    ) {
        struct Pass<'a> {
            pb: &'a PlanarBody,
            pw: &'a mut PlanarWorkspace,
            frame: ([f64; 2], f64),
            sc: Option<(f64, f64)>,
            solve: FrameSolve,
            Gi0: &'a [[f64; 3]; 3],
            gravity: [f64; 2],
        }
        impl pulp::WithSimd for Pass<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                let (pb, frame, sc, solve, Gi0, gravity) =
                    (self.pb, self.frame, self.sc, self.solve, self.Gi0, self.gravity);
                let PlanarWorkspace { f, d, wide, mats, .. } = self.pw;
                let mat = &mut mats[0];
                match wide {
                    Some(w) => pb.dual_passes(f, w, mat, frame, sc, solve, Gi0, gravity),
                    None => pb.dual_passes(f, d, mat, frame, sc, solve, Gi0, gravity),
                }
            }
        }
        pulp::Arch::new().dispatch(Pass {
            pb: self,
            pw,
            frame,
            sc,
            solve,
            Gi0,
            gravity,
        });
    }

    /// The passes of [`Self::stiffness_pass`] in dual numbers of width `W` (buffers `d`) at the
    /// configuration of `f`, $\mathbf K_t$ into `mat`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn dual_passes<const W: usize>(
        &self,
        f: &Buf<f64>,
        d: &mut Buf<Dual<W>>,
        mat: &mut [f64],
        frame: ([f64; 2], f64),
        sc: Option<(f64, f64)>,
        solve: FrameSolve,
        Gi0: &[[f64; 3]; 3],
        gravity: [f64; 2],
    ) {
        let n = self.n;
        let mut start = 0;
        while start < n {
            let end = (start + W).min(n);
            for i in 0..n {
                d.q[i] = Dual::cst(f.q[i]);
                d.qd[i] = Dual::cst(f.qd[i]);
                d.qdd[i] = Dual::cst(f.qdd[i]);
            }
            for (s, i) in (start..end).enumerate() {
                d.q[i].d[s] = 1.0;
            }
            self.core(d, frame, sc, solve, Gi0, gravity, false);
            for (s, j) in (start..end).enumerate() {
                for i in 0..n {
                    mat[i + n * j] = d.out[i].d[s];
                }
            }
            start = end;
        }
    }

    /// $\mathbf M = \bar{\mathbf R}\mathbf P^T\mathbf M_{ffr}\mathbf P\bar{\mathbf R}^T$ into `pw.mats[2]`
    /// and, with `damping`, $\mathbf C_t = \bar{\mathbf R}[\mathbf P^T\,\partial\mathbf F/\partial\boldsymbol\nu\,\mathbf P +
    /// \mathbf P^T\mathbf M_{ffr}\mathbf P\,\partial\bar{\mathbf y}/\partial\mathbf y + \mathbf T_j^T\mathbf D\mathbf T_j]\bar{\mathbf R}^T$
    /// into `pw.mats[1]`, at the configuration and velocities of the last `core` pass in `pw.f`
    /// (module docs: $\mathbf F$ is linear in $\dot{\boldsymbol\nu}$ with the matrix $\mathbf M_{ffr}$,
    /// $\dot{\boldsymbol\nu} = \mathbf P\bar{\mathbf y}$, and the velocity terms of $\mathbf F$ are
    /// differentiated below). With $\mathbf P = \mathbf E_0 + \mathbf Q\mathbf Z_j$, $\mathbf E_0 = [\mathbf 0;
    /// \mathbf I]$, $\mathbf Q = [\mathbf I_3; -\boldsymbol\Psi]$, each $\mathbf P^T\mathbf A\mathbf P$ is the
    /// $\zeta\zeta$ block of $\mathbf A$ plus rank-3 terms through the 3 rows of $\mathbf Z_j$
    /// ([`Self::congruence`]).
    pub(crate) fn mass_damping(&self, pw: &mut PlanarWorkspace, damping: bool) {
        struct Pass<'a> {
            pb: &'a PlanarBody,
            pw: &'a mut PlanarWorkspace,
            damping: bool,
        }
        impl pulp::WithSimd for Pass<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                self.pb.mass_damping_body(self.pw, self.damping);
            }
        }
        pulp::Arch::new().dispatch(Pass { pb: self, pw, damping });
    }

    #[inline(always)]
    fn mass_damping_body(&self, pw: &mut PlanarWorkspace, damping: bool) {
        let n = self.n;
        let N = self.N;
        let b = &pw.f;
        let Gi = &b.Gi;
        // The vectors read in the loops as slices, taken once.
        let (St, Srz, sa, Szm) = (&self.St[..n], &self.Srz[..n], &self.a[..n], &self.Sz[..n * n]);
        let (Sq, Wq, bSz, by, bzeta) = (&b.Sq[..n], &b.Wq[..n], &b.Sz[..n], &b.y[..n], &b.zeta[..n]);
        // Z_j = Gi Phi_j, by rows (3 x n).
        let Z = &mut pw.Z;
        for (j, ph) in self.Phi.iter().enumerate() {
            for a in 0..3 {
                Z[a * n + j] = Gi[a][0] * ph[0] + Gi[a][1] * ph[1] + Gi[a][2] * ph[2];
            }
        }
        let Z = &pw.Z[..3 * n];
        let rho = &b.rho;
        let m = self.mass;
        let Es = [-b.sv[1], b.sv[0]];
        // M_ffr: the frame block A, the coupling rows Bx (S_t x, y and c), the M_CB block.
        let A = [[m, 0.0, Es[0]], [0.0, m, Es[1]], [Es[0], Es[1], b.J]];
        let Bx = &mut pw.Bx;
        for i in 0..n {
            Bx[i] = St[i][0];
            Bx[n + i] = St[i][1];
            Bx[2 * n + i] = Srz[i] - Sq[i];
        }
        let Bx = &pw.Bx[..3 * n];
        Self::congruence(n, rho, Z, &A, Bx, &self.M, &mut pw.scratch, &mut pw.mats[2]);
        if damping {
            // dF/dnu (module docs), nu = [V; Omega; zeta].
            let [V0, V1, om] = b.xi;
            let (sv, sd) = (b.sv, b.sd);
            let pV = [V0 * m + Es[0] * om + sd[0], V1 * m + Es[1] * om + sd[1]];
            let fvo = [-sd[1] - pV[1] - om * sv[0], sd[0] + pV[0] - om * sv[1]];
            let Fxx = [
                [0.0, -om * m, fvo[0]],
                [om * m, 0.0, fvo[1]],
                [om * sv[0], om * sv[1], b.Jd + V0 * sv[0] + V1 * sv[1]],
            ];
            // Fxz (3 x n by rows) and Fzx (n x 3 by columns) in the first 6n entries of `big`.
            let (Fxz, rest) = pw.big.split_at_mut(3 * n);
            let Fzx = &mut rest[..3 * n];
            for i in 0..n {
                let st = St[i];
                let aw = sa[i] + Wq[i];
                Fxz[i] = -2.0 * om * st[1];
                Fxz[n + i] = 2.0 * om * st[0];
                Fxz[2 * n + i] = 2.0 * om * aw;
                Fzx[i] = om * st[1];
                Fzx[n + i] = -om * st[0];
                Fzx[2 * n + i] = st[0] * -V1 + st[1] * V0 - 2.0 * bSz[i] - 2.0 * om * aw;
            }
            // P^T F P = Fzz + L Z + Z^T (U + Cf Z): L = Fzx - Fzz Psi, U = Fxz - Psi^T Fzz,
            // Cf = Fxx - Fxz Psi - Psi^T Fzx + Psi^T Fzz Psi, with Fzz = -2 Omega S~_z.
            let f = -2.0 * om;
            // Fzz Psi (n x 3, by rows) and Psi^T Fzz (3 x n, by columns) in `six`.
            let (FzzPsi, PsiFzz) = pw.six.split_at_mut(3 * n);
            for i in 0..n {
                let (mut g, mut h) = ([0.0; 3], [0.0; 3]);
                for (k, r) in rho.iter().enumerate() {
                    // Row i of S~_z at the interface columns, and column i at the interface rows.
                    let a = |l: usize| Szm[i + n * l];
                    let c = |l: usize| Szm[l + n * i];
                    let (ax, ay, at) = (a(3 * k), a(3 * k + 1), a(3 * k + 2));
                    let (cx, cy, ct) = (c(3 * k), c(3 * k + 1), c(3 * k + 2));
                    g[0] += ax;
                    g[1] += ay;
                    g[2] += -r[1] * ax + r[0] * ay + at;
                    h[0] += cx;
                    h[1] += cy;
                    h[2] += -r[1] * cx + r[0] * cy + ct;
                }
                for d in 0..3 {
                    FzzPsi[3 * i + d] = f * g[d];
                    PsiFzz[d * n + i] = f * h[d];
                }
            }
            let mut Cf = Fxx;
            for (k, r) in rho.iter().enumerate() {
                let psi = [[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]], [0.0, 0.0, 1.0]];
                for (d, l) in (3 * k..3 * k + 3).enumerate() {
                    for a in 0..3 {
                        for c in 0..3 {
                            Cf[a][c] += psi[d][a] * (FzzPsi[3 * l + c] - Fzx[c * n + l]) - Fxz[a * n + l] * psi[d][c];
                        }
                    }
                }
            }
            // L = Fzx - Fzz Psi (3 columns of n) into Bx, free after the mass.
            let L = &mut pw.Bx[..3 * n];
            for a in 0..3 {
                for i in 0..n {
                    L[a * n + i] = Fzx[a * n + i] - FzzPsi[3 * i + a];
                }
            }
            let (l0, rest) = pw.Bx[..3 * n].split_at(n);
            let (l1, l2) = rest.split_at(n);
            let (y0, rest) = Z.split_at(n);
            let (y1, y2) = rest.split_at(n);
            let [_, C, Mloc] = &mut pw.mats;
            for (j, (col, sz)) in C[..n * n].chunks_exact_mut(n).zip(Szm.chunks_exact(n)).enumerate() {
                let z = [y0[j], y1[j], y2[j]];
                let h: [f64; 3] = std::array::from_fn(|a| {
                    Fxz[a * n + j] - PsiFzz[a * n + j] + Cf[a][0] * z[0] + Cf[a][1] * z[1] + Cf[a][2] * z[2]
                });
                for (i, o) in col.iter_mut().enumerate() {
                    *o = f * sz[i]
                        + y0[i] * h[0]
                        + y1[i] * h[1]
                        + y2[i] * h[2]
                        + l0[i] * z[0]
                        + l1[i] * z[1]
                        + l2[i] * z[2];
                }
            }
            // + (P^T M_ffr P) dybar/dy, nonzero in the u_k rows only (module docs): row u_k,x is
            // w_y P_Omega + Omega (I + T)_{u_k,y}, row u_k,y is -w_x P_Omega - Omega (I + T)_{u_k,x},
            // w = y_u_k + zeta_u_k, P_Omega the Omega row of Z, T = I - Psi Z.
            for j in 0..n {
                let pO = Z[2 * n + j];
                let col = &mut C[n * j..n * (j + 1)];
                for (k, r) in rho.iter().enumerate() {
                    let (ix, iy) = (3 * k, 3 * k + 1);
                    let two = |i: usize| if i == j { 2.0 } else { 0.0 };
                    let ex = two(ix) - (Z[j] - pO * r[1]);
                    let ey = two(iy) - (Z[n + j] + pO * r[0]);
                    let w = [by[ix] + bzeta[ix], by[iy] + bzeta[iy]];
                    let yx = w[1] * pO + om * ey;
                    let yy = -w[0] * pO - om * ex;
                    let (cx, cy) = (&Mloc[n * ix..n * (ix + 1)], &Mloc[n * iy..n * (iy + 1)]);
                    for ((o, x), y) in col.iter_mut().zip(cx).zip(cy) {
                        *o += x * yx + y * yy;
                    }
                }
            }
            if self.damped {
                // + T^T D T: the congruence with A_xixi = 0, A_xizeta = 0.
                let zero_rows = &mut pw.Bx[..3 * n];
                zero_rows.fill(0.0);
                Self::congruence(
                    n,
                    rho,
                    Z,
                    &[[0.0; 3]; 3],
                    &pw.Bx[..3 * n],
                    &self.D,
                    &mut pw.six,
                    &mut pw.big,
                );
                for (c, d) in pw.mats[1].iter_mut().zip(&pw.big) {
                    *c += d;
                }
            }
            rotate(&mut pw.mats[1], n, N, b.R);
        }
        rotate(&mut pw.mats[2], n, N, b.R);
    }

    /// $\mathbf P^T\mathbf A\mathbf P$ of a symmetric $(3 + n)^2$ matrix with blocks $\mathbf A_{\xi\xi}$ (`A`),
    /// $\mathbf A_{\xi\zeta}$ (`Bx`, 3 rows of $n$) and $\mathbf A_{\zeta\zeta}$ (`Mzz`, column-major) into
    /// `out` ($n\times n$): $\mathbf A_{\zeta\zeta} + \mathbf B^T\mathbf Z + \mathbf Z^T(\mathbf B + \mathbf C\mathbf Z)$ with
    /// $\mathbf B = \mathbf A_{\xi\zeta} - \boldsymbol\Psi^T\mathbf A_{\zeta\zeta}$, $\mathbf C = \mathbf A_{\xi\xi} -
    /// \mathbf A_{\xi\zeta}\boldsymbol\Psi - \boldsymbol\Psi^T\mathbf A_{\xi\zeta}^T + \boldsymbol\Psi^T\mathbf A_{\zeta\zeta}\boldsymbol\Psi$
    /// ($\mathbf Z$: `Z`, 3 rows of $n$; `scratch` $\ge 3n$).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn congruence(
        n: usize,
        rho: &[[f64; 2]],
        Z: &[f64],
        A: &[[f64; 3]; 3],
        Bx: &[f64],
        Mzz: &[f64],
        scratch: &mut [f64],
        out: &mut [f64],
    ) {
        // B = Bx - Psi^T Mzz (rows), by the columns of the symmetric Mzz.
        let B = &mut scratch[..3 * n];
        for j in 0..n {
            let col = &Mzz[n * j..n * (j + 1)];
            let mut g = [0.0; 3];
            for (k, r) in rho.iter().enumerate() {
                let (x, y, t) = (col[3 * k], col[3 * k + 1], col[3 * k + 2]);
                g[0] += x;
                g[1] += y;
                g[2] += -r[1] * x + r[0] * y + t;
            }
            for a in 0..3 {
                B[a * n + j] = Bx[a * n + j] - g[a];
            }
        }
        // C = A - Bx Psi - (Bx Psi)^T + Psi^T Mzz Psi = A - Bx Psi - Psi^T B.
        let mut C = *A;
        for (k, r) in rho.iter().enumerate() {
            let psi = [[1.0, 0.0, -r[1]], [0.0, 1.0, r[0]], [0.0, 0.0, 1.0]];
            for (d, l) in (3 * k..3 * k + 3).enumerate() {
                for a in 0..3 {
                    for c in 0..3 {
                        C[a][c] -= Bx[a * n + l] * psi[d][c] + psi[d][a] * B[c * n + l];
                    }
                }
            }
        }
        // The rows of B and Z as slices of length n (no bounds checks in the loop).
        let (b0, rest) = B.split_at(n);
        let (b1, b2) = rest.split_at(n);
        let (y0, rest) = Z[..3 * n].split_at(n);
        let (y1, y2) = rest.split_at(n);
        for (j, (col, mz)) in out[..n * n].chunks_exact_mut(n).zip(Mzz.chunks_exact(n)).enumerate() {
            let (z0, z1, z2) = (y0[j], y1[j], y2[j]);
            let h: [f64; 3] = std::array::from_fn(|a| B[a * n + j] + C[a][0] * z0 + C[a][1] * z1 + C[a][2] * z2);
            for (i, o) in col.iter_mut().enumerate() {
                *o = mz[i] + b0[i] * z0 + b1[i] * z1 + b2[i] * z2 + y0[i] * h[0] + y1[i] * h[1] + y2[i] * h[2];
            }
        }
    }

    /// The planar $\boldsymbol\Phi_j\boldsymbol\Psi$ inverse at `rho` with its 1-norm reciprocal
    /// condition number.
    fn inverse_with_rcond(&self, rho: &[[f64; 2]]) -> Result<[[f64; 3]; 3], SuperelementError> {
        let G = self.phi_psi(rho);
        let (Gi, det) = inv3(&G);
        let norm1 = |A: &[[f64; 3]; 3]| {
            (0..3)
                .map(|c| (0..3).map(|r| A[r][c].abs()).sum::<f64>())
                .fold(0.0, f64::max)
        };
        if det == 0.0 || !det.is_finite() {
            return Err(SuperelementError::SingularFrame { rcond: 0.0 });
        }
        let rcond = 1.0 / (norm1(&G) * norm1(&Gi));
        if !(rcond >= RCOND_MIN) {
            return Err(SuperelementError::SingularFrame { rcond });
        }
        Ok(Gi)
    }

    /// The Newton solve of the planar (4.4) from `start` for positions `r`, angles `phi`,
    /// modal coordinates `eta` (`r_max`: the largest $|\mathbf r_k|$, body size `length`), with
    /// the tolerance logic and errors of the spatial solve; `b` holds the iterates. Returns the
    /// frame, the iterations and $(\sin, \cos)$ of the frame angle (formed by the last
    /// iteration's test; [`Self::core`] reads them).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn newton(
        &self,
        r: &[[f64; 2]],
        phi: &[f64],
        eta: &[f64],
        r_max: f64,
        start: ([f64; 2], f64),
        length: f64,
        settings: FrameSettings,
        b: &mut Buf<f64>,
    ) -> Result<(Frame2, usize, (f64, f64)), SuperelementError> {
        let pb = self;
        let N = pb.N;
        let L = length;
        let tol = settings.tolerance + 64.0 * f64::EPSILON * (1.0 + r_max / L);
        let (mut rj, mut pj) = start;
        let mut residual = f64::INFINITY;
        let (rho, qjj) = (&mut b.rho[..N], &mut b.qjj[..pb.n]);
        qjj[3 * N..].copy_from_slice(eta);
        for it in 0..=settings.max_iterations {
            let (s, c) = pj.sin_cos();
            for k in 0..N {
                let dx = r[k][0] - rj[0];
                let dy = r[k][1] - rj[1];
                let rx = c * dx + s * dy;
                let ry = c * dy - s * dx;
                rho[k] = [rx, ry];
                qjj[3 * k] = rx - pb.x[k][0];
                qjj[3 * k + 1] = ry - pb.x[k][1];
                qjj[3 * k + 2] = wrap(phi[k] - pj);
            }
            let g = pb.phi_mul(qjj);
            // |g_t| by the square root of the sum of squares (hypot where that overflows).
            let t2 = g[0] * g[0] + g[1] * g[1];
            let gt = if t2.is_finite() { t2.sqrt() } else { g[0].hypot(g[1]) };
            residual = (gt / L).max(g[2].abs());
            if !residual.is_finite() {
                break;
            }
            if residual <= tol {
                return Ok(((rj, pj), it, (s, c)));
            }
            if it == settings.max_iterations {
                break;
            }
            let Gi = pb.inverse_with_rcond(rho)?;
            let d: [f64; 3] = std::array::from_fn(|a| Gi[a][0] * g[0] + Gi[a][1] * g[1] + Gi[a][2] * g[2]);
            rj[0] += c * d[0] - s * d[1];
            rj[1] += s * d[0] + c * d[1];
            pj += d[2];
        }
        Err(SuperelementError::FrameNotConverged {
            iterations: settings.max_iterations,
            residual,
            tolerance: tol,
        })
    }

    /// Planar kinetic energy $\tfrac12\boldsymbol\nu^T\mathbf M_{ffr}\boldsymbol\nu$ at local
    /// coordinates `qjj` (planar) for body-axis velocities `y` (planar): forms $\boldsymbol\nu$
    /// from the configuration.
    pub(crate) fn kinetic(&self, qjj: &[f64], y: &[f64]) -> Result<f64, SuperelementError> {
        let pb = self;
        let n = pb.n;
        let rho: Vec<[f64; 2]> = (0..pb.N)
            .map(|k| [pb.x[k][0] + qjj[3 * k], pb.x[k][1] + qjj[3 * k + 1]])
            .collect();
        let Gi = pb.inverse_with_rcond(&rho)?;
        let py = pb.phi_mul(y);
        let xi: [f64; 3] = std::array::from_fn(|a| Gi[a][0] * py[0] + Gi[a][1] * py[1] + Gi[a][2] * py[2]);
        let mut zeta = vec![0.0; n];
        pb.minus_psi(&rho, y, &xi, &mut zeta);
        let m = pb.mass;
        let mut s = [m * pb.d[0], m * pb.d[1]];
        let mut stz = [0.0; 2];
        for (i, st) in pb.St.iter().enumerate() {
            for a in 0..2 {
                s[a] += st[a] * qjj[i];
                stz[a] += st[a] * zeta[i];
            }
        }
        let mut Wq = vec![0.0; n];
        let mut Sq = vec![0.0; n];
        matvec(&pb.W, qjj, &mut Wq);
        matvec(&pb.Sz, qjj, &mut Sq);
        let J = pb.J0 + (0..n).map(|i| (2.0 * pb.a[i] + Wq[i]) * qjj[i]).sum::<f64>();
        Ok(pb.kinetic_of(xi, s, stz, J, &Sq, &zeta))
    }

    /// [`Self::kinetic`] from what the last `f64` pass of [`Self::core`] left in `b` (its
    /// $\boldsymbol\xi$, $\mathbf s$, $\mathbf S_t^T\boldsymbol\zeta$, $J$, $\tilde{\mathbf S}_z\mathbf q$,
    /// $\boldsymbol\zeta$), for the velocities of that pass: one product with $\mathbf M$, no
    /// allocation (an energy sensor at every step). The caller checks that the velocities are
    /// the pass's.
    pub(crate) fn kinetic_in(&self, b: &Buf<f64>) -> f64 {
        let n = self.n;
        self.kinetic_of(b.xi, b.sv, b.sd, b.J, &b.Sq[..n], &b.zeta[..n])
    }

    /// $\tfrac12\boldsymbol\nu^T\mathbf M_{ffr}\boldsymbol\nu$ (7.7) from $\boldsymbol\xi = [\mathbf V;
    /// \Omega]$, $\mathbf s$, $\mathbf S_t^T\boldsymbol\zeta$ (`stz`), $J$, $\tilde{\mathbf S}_z\mathbf q$ (`Sq`)
    /// and $\boldsymbol\zeta$: the blocks of (7.7) without forming it, one product with $\mathbf M$.
    fn kinetic_of(&self, xi: [f64; 3], s: [f64; 2], stz: [f64; 2], J: f64, Sq: &[f64], zeta: &[f64]) -> f64 {
        let n = self.n;
        let (V, om) = ([xi[0], xi[1]], xi[2]);
        let Es = [-s[1], s[0]];
        let mut cz = 0.0;
        let mut zMz = 0.0;
        for (j, zj) in zeta.iter().enumerate() {
            cz += (self.Srz[j] - Sq[j]) * zj;
            let Mz: f64 = self.M[n * j..n * (j + 1)].iter().zip(zeta).map(|(m, z)| m * z).sum();
            zMz += zj * Mz;
        }
        0.5 * self.mass * (V[0] * V[0] + V[1] * V[1])
            + om * (V[0] * Es[0] + V[1] * Es[1])
            + V[0] * stz[0]
            + V[1] * stz[1]
            + 0.5 * J * om * om
            + om * cz
            + 0.5 * zMz
    }

    /// Planar strain energy at planar local coordinates `q`.
    pub(crate) fn strain_energy(&self, q: &[f64]) -> f64 {
        let pb = self;
        let n = pb.n;
        let mut f = vec![0.0; n];
        matvec(&pb.K, q, &mut f);
        let mut U = 0.5 * dot(q, &f);
        if let Some(G) = &pb.geometric {
            // U_3 + U_4 = q.b + b.p/2 (`GeometricStiffness`).
            let (mut b, mut p) = (vec![0.0; n], vec![0.0; n]);
            let (mut gq, mut fe) = (vec![0.0; n * G.groups.len()], vec![0.0; n]);
            G.gradient(q, &mut b, &mut p, &mut gq, &mut fe);
            U += dot(q, &b) + 0.5 * dot(&b, &p);
        }
        U
    }

    /// Frame velocity $\boldsymbol\xi = \mathbf Z_j\mathbf y$ and elastic velocity $\mathbf T_j\mathbf y$ at
    /// the planar local coordinates `q` for the body-axis velocities `y`.
    pub(crate) fn velocities(&self, q: &[f64], y: &[f64]) -> Result<([f64; 3], Vec<f64>), SuperelementError> {
        let pb = self;
        let rho: Vec<[f64; 2]> = (0..pb.N)
            .map(|k| [pb.x[k][0] + q[3 * k], pb.x[k][1] + q[3 * k + 1]])
            .collect();
        let Gi = pb.inverse_with_rcond(&rho)?;
        let py = pb.phi_mul(y);
        let xi: [f64; 3] = std::array::from_fn(|a| Gi[a][0] * py[0] + Gi[a][1] * py[1] + Gi[a][2] * py[2]);
        let mut zeta = vec![0.0; pb.n];
        pb.minus_psi(&rho, y, &xi, &mut zeta);
        Ok((xi, zeta))
    }
}

/// What [`PlanarInput::build`] reads of a spatial superelement.
pub(crate) struct PlanarInput<'a> {
    pub name: &'a str,
    pub body: &'a ReducedBody,
    pub n_interfaces: usize,
    pub n_modes: usize,
    pub n: usize,
    pub frame_choice: FrameChoice,
    pub mass_variant: MassVariant,
    pub origin: Vector3<f64>,
    pub x: &'a [Vector3<f64>],
    pub length: f64,
    pub K_CB: &'a Mat<f64>,
    pub M_CB: &'a Mat<f64>,
    pub D: &'a Mat<f64>,
    pub damped: bool,
    pub Phi_j: &'a Mat<f64>,
    pub inertia: &'a FfrInertia,
    pub geometric: Option<GeometricView<'a>>,
}

/// The spatial $\mathbf G_k$ (stacked column-major, `GeometricStiffness::stack`) and $\mathbf F$.
pub(crate) struct GeometricView<'a> {
    pub n: usize,
    pub stack: &'a [f64],
    pub F: &'a Mat<f64>,
}

impl GeometricView<'_> {
    fn matrix(&self, k: usize) -> faer::MatRef<'_, f64> {
        let n = self.n;
        faer::MatRef::from_column_major_slice(&self.stack[n * n * k..n * n * (k + 1)], n, n)
    }
}

impl PlanarInput<'_> {
    pub(crate) fn not_planar(&self, what: String) -> SuperelementError {
        SuperelementError::NotPlanar {
            body: self.name.to_string(),
            what,
        }
    }

    /// The planar data, after the checks of [`crate::Superelement::into_planar`].
    pub(crate) fn build(&self) -> Result<PlanarBody, SuperelementError> {
        let N = self.n_interfaces;
        let m = self.n_modes;
        let n3 = self.n;
        let names: Vec<String> = self.body.interfaces.iter().map(|i| i.name.clone()).collect();
        const DOF: [&str; 6] = ["x", "y", "z", "rx", "ry", "rz"];
        let entity = |g: usize| -> String {
            if g < 6 * N {
                format!("interface '{}' dof {}", names[g / 6], DOF[g % 6])
            } else {
                format!("mode {}", g - 6 * N)
            }
        };
        // Out-of-plane parity of a 3D coordinate: z, rx, ry of an interface.
        let odd = |g: usize| g < 6 * N && matches!(g % 6, 2..=4);
        if self.mass_variant == MassVariant::Lumped {
            return Err(self.not_planar("the Lumped inertia has no planar evaluation (use the Exact inertia)".into()));
        }
        if self.frame_choice == FrameChoice::AuxiliaryNode {
            return Err(self.not_planar(
                "the auxiliary-node frame has no planar evaluation (use the centre of mass or an interface node)"
                    .into(),
            ));
        }
        // The interfaces and the frame origin in one plane z = const.
        let z = self.origin.z;
        for (k, p) in self.body.interfaces.iter().enumerate() {
            let dz = p.position[2] - z;
            if !(dz.abs() <= COUPLING_TOL * self.length) {
                return Err(self.not_planar(format!(
                    "interface '{}' is at z = {} but the frame origin (the {}) at z = {z} ({dz:.3e} m apart): the interfaces and the frame origin must lie in one plane z = const",
                    names[k], p.position[2], self.frame_choice
                )));
            }
        }
        // Entries that couple the in-plane and out-of-plane sets (odd parity under z -> -z)
        // must vanish against the matrix's largest entry.
        let check = |what: &str,
                     rows: usize,
                     cols: usize,
                     get: &dyn Fn(usize, usize) -> f64,
                     row_odd: &dyn Fn(usize) -> bool,
                     col_odd: &dyn Fn(usize) -> bool,
                     row_name: &dyn Fn(usize) -> String,
                     col_name: &dyn Fn(usize) -> String|
         -> Result<(), SuperelementError> {
            let mut big: f64 = 0.0;
            let mut worst = (0.0, 0, 0);
            for j in 0..cols {
                for i in 0..rows {
                    let v = get(i, j).abs();
                    big = big.max(v);
                    if row_odd(i) != col_odd(j) && v > worst.0 {
                        worst = (v, i, j);
                    }
                }
            }
            if worst.0 > COUPLING_TOL * big {
                return Err(self.not_planar(format!(
                    "{what} couples {} with {} (entry {:.3e}, {:.3e} of its largest)",
                    row_name(worst.1),
                    col_name(worst.2),
                    get(worst.1, worst.2),
                    worst.0 / big
                )));
            }
            Ok(())
        };
        let coord = |g: usize| entity(g);
        check("K_CB", n3, n3, &|i, j| self.K_CB[(i, j)], &odd, &odd, &coord, &coord)?;
        check("M_CB", n3, n3, &|i, j| self.M_CB[(i, j)], &odd, &odd, &coord, &coord)?;
        let frame_row = |r: usize| format!("the frame condition row {}", DOF[r]);
        let odd_row = |r: usize| matches!(r, 2..=4);
        check(
            "Phi_j",
            6,
            n3,
            &|i, j| self.Phi_j[(i, j)],
            &odd_row,
            &odd,
            &frame_row,
            &coord,
        )?;
        let I = &self.inertia;
        let axis = |r: usize| format!("the {} component", ["x", "y", "z"][r]);
        // S_t: the z row is out of plane; S_r: the x, y rows.
        check(
            "the inertia invariant S_t",
            3,
            n3,
            &|i, j| I.S_t[(i, j)],
            &|r| r == 2,
            &odd,
            &axis,
            &coord,
        )?;
        check(
            "the inertia invariant S_r",
            3,
            n3,
            &|i, j| I.S_r[(i, j)],
            &|r| r != 2,
            &odd,
            &axis,
            &coord,
        )?;
        let pair_name = |r: usize| format!("the {}{} component", ["x", "y", "z"][r / 3], ["x", "y", "z"][r % 3]);
        check(
            "the inertia invariant S_x",
            9,
            n3,
            &|i, j| I.S_x[(i, j)],
            &|r| (r / 3 == 2) != (r % 3 == 2),
            &odd,
            &pair_name,
            &coord,
        )?;
        if let Some(G) = &self.geometric {
            let n = n3;
            // G as an n^2 x n matrix: row i + n j, column k.
            check(
                "the geometric stiffness G",
                n * n,
                n,
                &|r, k| G.stack[r + n * n * k],
                &|r| odd(r % n) != odd(r / n),
                &odd,
                &|r| format!("({}, {})", entity(r % n), entity(r / n)),
                &|k| format!("G of {}", entity(k)),
            )?;
        }
        let c0 = self.inertia.d;
        if !(c0.z.abs() <= COUPLING_TOL * self.length) {
            return Err(self.not_planar(format!(
                "the centre of mass is {:.3e} m off the plane of the interfaces",
                c0.z
            )));
        }
        // The planar index set and the restricted data.
        let mut index = Vec::with_capacity(3 * N + m);
        for k in 0..N {
            for c in IN_PLANE {
                index.push(6 * k + c);
            }
        }
        index.extend(6 * N..6 * N + m);
        let n = index.len();
        let restrict = |A: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            let mut v = vec![0.0; n * n];
            for (j, &gj) in index.iter().enumerate() {
                for (i, &gi) in index.iter().enumerate() {
                    v[i + n * j] = A(gi, gj);
                }
            }
            v
        };
        let Phi: Vec<[f64; 3]> = index
            .iter()
            .map(|&g| [self.Phi_j[(0, g)], self.Phi_j[(1, g)], self.Phi_j[(5, g)]])
            .collect();
        let mut sum_u = [[0.0; 3]; 2];
        for k in 0..N {
            for c in 0..2 {
                for a in 0..3 {
                    sum_u[c][a] += Phi[3 * k + c][a];
                }
            }
        }
        let geometric = match &self.geometric {
            None => None,
            Some(G) => {
                let mut groups = Vec::new();
                for (k, &gk) in index.iter().enumerate() {
                    let Gk = G.matrix(gk);
                    let mut entries = Vec::new();
                    for (j, &gj) in index.iter().enumerate() {
                        for (i, &gi) in index.iter().enumerate() {
                            let v = Gk[(gi, gj)];
                            if v != 0.0 {
                                entries.push((i as u32, j as u32, v));
                            }
                        }
                    }
                    if !entries.is_empty() {
                        groups.push((k, entries));
                    }
                }
                let F = self.pseudo_inverse(&index)?;
                // The planar pseudo-inverse against the restricted spatial one (equal when the
                // blocks decouple).
                let F3 = &G.F;
                let big = F.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let mut worst: f64 = 0.0;
                for (j, &gj) in index.iter().enumerate() {
                    for (i, &gi) in index.iter().enumerate() {
                        worst = worst.max((F[i + n * j] - F3[(gi, gj)]).abs());
                    }
                }
                if worst > 1e-6 * big {
                    return Err(self.not_planar(format!(
                        "the pseudo-inverse of the planar K_CB differs from the in-plane block of the spatial one by {:.3e} of its largest entry",
                        worst / big
                    )));
                }
                Some(PlanarGeometric { groups, F })
            }
        };
        let ffr = &self.inertia;
        let x: Vec<[f64; 2]> = self.x.iter().map(|v| [v.x, v.y]).collect();
        Ok(PlanarBody {
            N,
            n,
            x,
            Phi,
            sum_u,
            K: restrict(&|i, j| self.K_CB[(i, j)]),
            M: restrict(&|i, j| self.M_CB[(i, j)]),
            D: restrict(&|i, j| self.D[(i, j)]),
            damped: self.damped,
            mass: ffr.mass,
            d: [ffr.d.x, ffr.d.y],
            J0: ffr.J0[(2, 2)],
            St: index.iter().map(|&g| [ffr.S_t[(0, g)], ffr.S_t[(1, g)]]).collect(),
            Srz: index.iter().map(|&g| ffr.S_r[(2, g)]).collect(),
            a: index.iter().map(|&g| ffr.S_x[(0, g)] + ffr.S_x[(4, g)]).collect(),
            W: restrict(&|i, j| 0.5 * (ffr.S_bar_sym[0][(i, j)] + ffr.S_bar_sym[1][(i, j)])),
            Sz: restrict(&|i, j| ffr.S_tilde[2][(i, j)]),
            geometric,
            index,
        })
    }

    /// $\mathbf K_{CB}^+$ of the planar $\mathbf K_{CB}$ (the in-plane block), as the spatial
    /// `rigid_pseudo_inverse` with the three planar rigid modes.
    fn pseudo_inverse(&self, index: &[usize]) -> Result<Vec<f64>, SuperelementError> {
        use faer::linalg::solvers::DenseSolveCore;
        let n = index.len();
        let N = self.n_interfaces;
        let R = Mat::from_fn(n, 3, |i, c| {
            if i >= 3 * N {
                return 0.0;
            }
            let (k, d) = (i / 3, i % 3);
            let p = self.body.interfaces[k].position;
            match (d, c) {
                (0, 0) | (1, 1) | (2, 2) => 1.0,
                (0, 2) => -p[1],
                (1, 2) => p[0],
                _ => 0.0,
            }
        });
        let RtR = R.transpose() * &R;
        let P = &R * RtR.partial_piv_lu().inverse() * R.transpose();
        let K = Mat::from_fn(n, n, |i, j| self.K_CB[(index[i], index[j])]);
        let alpha = (0..n).map(|i| K[(i, i)].abs()).sum::<f64>() / n as f64;
        let A = Mat::from_fn(n, n, |i, j| K[(i, j)] + alpha * P[(i, j)]);
        let F = A.partial_piv_lu().inverse();
        if F.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
            return Err(
                self.not_planar("the planar K_CB has a null space beyond the three planar rigid motions".into())
            );
        }
        let mut out = vec![0.0; n * n];
        for j in 0..n {
            for i in 0..n {
                out[i + n * j] = 0.5 * (F[(i, j)] + F[(j, i)]) - P[(i, j)] / alpha;
            }
        }
        Ok(out)
    }
}
