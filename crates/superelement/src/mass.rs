//! Inertia of the body: the standard floating-frame (FFR) mass matrix from the inertia
//! invariants, its generalised inertia force with the quadratic velocity terms, and their
//! partial derivatives (the `Exact` variant); the `Lumped` variant needs only
//! $\mathbf M_{CB}$ (see [`crate::forces`]).
//!
//! # FFR coordinates and kinetic energy
//!
//! A material point with undeformed position $\mathbf x$ (from the frame origin $P_j$, body
//! axes) is at $\mathbf p = \mathbf r_j + \mathbf R_j(\mathbf x + \mathbf w)$, $\mathbf w =
//! \mathbf S(\mathbf x)\mathbf q^{jj}$ (the translational CB field). With the body-axis
//! quasi-velocities $\boldsymbol\nu = [\mathbf V;\ \boldsymbol\Omega;\ \dot{\mathbf q}^{jj}]$,
//! $\mathbf V = \mathbf R_j^T\dot{\mathbf r}_j$, $\tilde{\boldsymbol\Omega} = \mathbf R_j^T\dot{\mathbf R}_j$:
//! $\mathbf R_j^T\dot{\mathbf p} = \mathbf V - (\mathbf x + \mathbf w)^\sim\boldsymbol\Omega + \mathbf S\dot{\mathbf q}^{jj}$
//! and $T = \tfrac12\boldsymbol\nu^T\mathbf M_{ffr}(\mathbf q^{jj})\boldsymbol\nu$ with
//!
//! $$\mathbf M_{ffr} = \begin{bmatrix} m\mathbf I & -\tilde{\mathbf s} & \mathbf S_t\\
//! \tilde{\mathbf s} & \mathbf J(\mathbf q) & \mathbf S_r + \mathbf S_w(\mathbf q)\\
//! \mathbf S_t^T & (\mathbf S_r + \mathbf S_w)^T & \mathbf M_{CB}\end{bmatrix},$$
//!
//! $\mathbf s = m\mathbf d + \mathbf S_t\mathbf q$ (first moment, $\mathbf d$ the centre of mass
//! from $P_j$), $\mathbf J = \mathbf J_0 + 2\,\mathrm{tr}(\mathbf X)\mathbf I - \mathbf X - \mathbf X^T +
//! \mathrm{tr}(\mathbf W)\mathbf I - \mathbf W$ with $X_{ab} = \int\rho x_a w_b = (\mathbf S_x)_{ab}\mathbf q$,
//! $W_{ab} = \int\rho w_a w_b = \mathbf q^T\bar{\mathbf S}_{ab}\mathbf q$, and row $i$ of
//! $\mathbf S_w(\mathbf q) = \int\rho\tilde{\mathbf w}\mathbf S$ equal to $\mathbf q^T\tilde{\mathbf S}_i$,
//! $\tilde{\mathbf S}_i = \epsilon_{iab}\bar{\mathbf S}_{ab}$ (skew). The invariants are those of
//! `reduction::InertiaData`, moved from the centre of mass to $P_j$. The rotary inertia of beam
//! sections enters $\mathbf J_0$, $\mathbf S_r$ and $\mathbf M_{CB}$ but not the
//! deformation-dependent terms (as in `InertiaData`): $T$ is still one kinetic energy, so the
//! forces below conserve energy exactly.
//!
//! # Generalised inertia force
//!
//! Euler-Poincaré on the frame ($\mathbf V, \boldsymbol\Omega$ are a body twist) and Lagrange on
//! $\mathbf q^{jj}$, with $\mathbf p = \mathbf M_{ffr}\boldsymbol\nu$:
//! $\mathbf F = \mathbf M_{ffr}\dot{\boldsymbol\nu} + \dot{\mathbf M}_{ffr}\boldsymbol\nu +
//! [\boldsymbol\Omega\times\mathbf p_V;\ \boldsymbol\Omega\times\mathbf p_\Omega + \mathbf V\times\mathbf p_V;\ \mathbf 0] -
//! [\mathbf 0;\ \mathbf 0;\ \partial T/\partial\mathbf q]$, which works out as
//!
//! * $\mathbf F_V = m\dot{\mathbf V} + \dot{\boldsymbol\Omega}\times\mathbf s + \mathbf S_t\ddot{\mathbf q} +
//!   \boldsymbol\Omega\times\dot{\mathbf s} + \boldsymbol\Omega\times\mathbf p_V$,
//! * $\mathbf F_\Omega = \mathbf s\times\dot{\mathbf V} + \mathbf J\dot{\boldsymbol\Omega} + (\mathbf S_r + \mathbf S_w)\ddot{\mathbf q} +
//!   \dot{\mathbf s}\times\mathbf V + \dot{\mathbf J}\boldsymbol\Omega + \boldsymbol\Omega\times\mathbf p_\Omega + \mathbf V\times\mathbf p_V$,
//! * $\mathbf F_q = \mathbf S_t^T\dot{\mathbf V} + (\mathbf S_r + \mathbf S_w)^T\dot{\boldsymbol\Omega} + \mathbf M_{CB}\ddot{\mathbf q} +
//!   2\mathbf S_w(\dot{\mathbf q})^T\boldsymbol\Omega - \mathbf S_t^T(\mathbf V\times\boldsymbol\Omega) -
//!   \tfrac12\,\mathbf j_q(\boldsymbol\Omega)^T\boldsymbol\Omega$,
//!
//! with $\mathbf j_q(\mathbf w) = \partial(\mathbf J(\mathbf q)\mathbf w)/\partial\mathbf q$ and
//! $\mathbf S_w(\dot{\mathbf q})\dot{\mathbf q} = 0$ ($\tilde{\mathbf S}_i$ skew). This is the
//! AIC-FFR paper's $\mathbf M\ddot{\mathbf q} + \mathbf C\dot{\mathbf q}$ of (6.1) in body-axis
//! quasi-velocities. The power balance $\boldsymbol\nu^T\mathbf F = \dot T$ is checked by
//! `tests/unit/energy.rs`, the partials by `tests/unit/fd_tangent.rs::ffr_partials`.

#![allow(non_snake_case)]

use crate::so3::skew;
use crate::transform::{col, cols_mut, PackedTall};
use faer::{Mat, MatRef};
use nalgebra::{Matrix3, Vector3};
use reduction::InertiaData;
use serde::{Deserialize, Serialize};

/// Which inertia the superelement uses (theory guide §4; [AIC-FFR] §4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MassVariant {
    /// The standard FFR mass matrix from the inertia invariants transformed by $\mathbf A$
    /// (5.6), with the exact quadratic velocity forces (6.4): $\mathbf M = \mathbf A^T\mathbf M_{ffr}\mathbf A$,
    /// $\mathbf Q_v = \mathbf A^T(\mathbf M_{ffr}\dot{\mathbf A}\dot{\mathbf q} + \mathbf h)$.
    Exact,
    /// The AIC-FFR paper's simplification (6.5): $\mathbf M = \bar{\mathbf R}\mathbf M_{CB}\bar{\mathbf R}^T$,
    /// and $\mathbf Q_v$ from the same "lumped" kinetic energy (see
    /// `Superelement::lumped_inertia` in `forces.rs` for what that means).
    Lumped,
}

/// The six unique index pairs $(a, b)$, $a \le b$, of a symmetric $3\times3$ pattern.
pub const PAIRS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// Index into [`PAIRS`] of $(a, b)$ in either order.
#[inline]
pub fn pair(a: usize, b: usize) -> usize {
    match (a.min(b), a.max(b)) {
        (0, 0) => 0,
        (1, 1) => 1,
        (2, 2) => 2,
        (0, 1) => 3,
        (0, 2) => 4,
        _ => 5,
    }
}

/// The inertia invariants in the frame's coordinates (origin $P_j$), ready for
/// $\mathbf M_{ffr}$ (module docs).
#[derive(Clone, Debug)]
pub struct FfrInertia {
    pub mass: f64,
    /// Centre of mass from $P_j$, body axes.
    pub d: Vector3<f64>,
    /// Inertia tensor about $P_j$ (rotary inertia of beam sections included).
    pub J0: Matrix3<f64>,
    /// $\int\rho\mathbf S$, $3\times n$.
    pub S_t: Mat<f64>,
    /// $\int\rho\tilde{\mathbf x}\mathbf S$ about $P_j$ (rotary inertia included), $3\times n$.
    pub S_r: Mat<f64>,
    /// Row $3a + b$: $\int\rho\, x_a\mathbf S_b$, $\mathbf x$ from $P_j$; $9\times n$.
    pub S_x: Mat<f64>,
    /// $\bar{\mathbf S}_{ab} + \bar{\mathbf S}_{ba}$ for the pairs of [`PAIRS`] ($n\times n$, symmetric).
    pub S_bar_sym: Vec<Mat<f64>>,
    /// $\tilde{\mathbf S}_i = \bar{\mathbf S}_{jk} - \bar{\mathbf S}_{kj}$, $(i,j,k)$ cyclic ($n\times n$, skew).
    pub S_tilde: Vec<Mat<f64>>,
    /// $\mathbf M_{CB}$.
    pub M_CB: Mat<f64>,
    /// $[\tilde{\mathbf S}_0; \tilde{\mathbf S}_1; \tilde{\mathbf S}_2; \bar{\mathbf S}^{sym}_0; \dots;
    /// \bar{\mathbf S}^{sym}_5]$ stacked ($9n\times n$): one product with $[\mathbf q, \dot{\mathbf q},
    /// \ddot{\mathbf q}]$ gives all contractions (the $\bar{\mathbf S}^{sym}\ddot{\mathbf q}$ it adds are
    /// unused but cheaper than a second call).
    stack: Mat<f64>,
    /// $[\mathrm{vec}\,\tilde{\mathbf S}_0, \dots, \mathrm{vec}\,\tilde{\mathbf S}_2, \mathrm{vec}\,\bar{\mathbf S}^{sym}_0,
    /// \dots, \mathrm{vec}\,\bar{\mathbf S}^{sym}_5]$ ($n^2\times9$): the $\dot{\mathbf q}\dot{\mathbf q}$ block
    /// of $\partial\mathbf F/\partial\boldsymbol\nu$ and the $\mathbf q\mathbf q$ block of
    /// $\partial\mathbf F/\partial\mathbf q$ are combinations of these nine matrices: one product.
    vec_stack: Mat<f64>,
    /// `stack` and `vec_stack` packed for small bodies ($n \le$ [`PACKED_MAX_N`]).
    packed: Option<PackedInvariants>,
    /// $[\mathbf S_t; \mathbf S_r; \mathbf S_x]$ column by column, 15 rows padded to [`SMALL`]:
    /// the force's products with $\mathbf q$, $\dot{\mathbf q}$, $\ddot{\mathbf q}$ by one pass over
    /// the columns each ([`Self::small_products`]; their sums in fused multiply-adds, the same on
    /// every machine).
    small: Vec<[f64; SMALL]>,
    /// The same 15 rows row by row ($15n$): the transposed product $\mathbf S_t^T\mathbf a +
    /// \mathbf S_r^T\dot{\boldsymbol\Omega} + \sum_r k_r(\mathbf S_x)_r$ of the force as 15
    /// contiguous row updates.
    small_rows: Vec<f64>,
}

/// Entries per column of [`FfrInertia`]`::small`: $\mathbf S_t$ (rows 0-2), $\mathbf S_r$ (3-5),
/// $\mathbf S_x$ (6-14), a zero.
const SMALL: usize = 16;

/// Largest $n$ whose inertia contractions go through [`PackedTall`]; above, faer's product
/// (its fixed cost small against the $9n^2$ multiply-adds) is kept.
const PACKED_MAX_N: usize = 24;

/// The stacked invariants of [`FfrInertia`] packed for [`PackedTall::mul`].
#[derive(Clone, Debug)]
struct PackedInvariants {
    /// Rows $0..3n$ of `stack` ($\tilde{\mathbf S}_i$: with $\mathbf q$, $\dot{\mathbf q}$, $\ddot{\mathbf q}$).
    tilde: PackedTall,
    /// Rows $3n..9n$ of `stack` ($\bar{\mathbf S}^{sym}_p$: with $\mathbf q$, $\dot{\mathbf q}$ only).
    sym: PackedTall,
    /// `vec_stack`.
    vec: PackedTall,
}

/// $\int\rho\,\mathbf f$ rows of a `DenseMatrix` as a faer matrix.
fn dense(m: &reduction::DenseMatrix) -> Mat<f64> {
    m.to_faer()
}

impl FfrInertia {
    /// Moves the invariants of `data` (about the centre of mass) to the frame origin
    /// `origin` (FE coordinates): with $\mathbf x = \mathbf x_c + \mathbf d$,
    /// $\int\rho\tilde{\mathbf x}\mathbf S = \mathbf S_r + \tilde{\mathbf d}\mathbf S_t$,
    /// $\int\rho x_a\mathbf S_b = (\mathbf S_x)_{ab} + d_a(\mathbf S_t)_b$,
    /// $\mathbf J_0 = \mathbf I_c + m(|\mathbf d|^2\mathbf I - \mathbf d\mathbf d^T)$ (parallel axes).
    /// Checked by `tests/unit/energy.rs::rigid_kinetic_energy_is_exact` (frames off the centre of
    /// mass) and `tests/unit/linear_limit.rs::frequencies_match_fe_to_the_modes_kept` (the
    /// `Exact` mass equals $\mathbf M_{CB}$ at the undeformed state).
    pub fn new(data: &InertiaData, origin: &Vector3<f64>, M_CB: &Mat<f64>) -> Self {
        let m = data.mass;
        let c = Vector3::from(data.center_of_mass);
        let d = c - origin;
        let Ic = Matrix3::from_fn(|i, j| data.inertia_com[i][j]);
        let J0 = Ic + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * m;
        let S_t = dense(&data.S_t);
        let n = S_t.ncols();
        let Sr_c = dense(&data.S_r);
        let Dt = skew(&d);
        let S_r = Mat::from_fn(3, n, |i, j| {
            Sr_c[(i, j)] + (0..3).map(|k| Dt[(i, k)] * S_t[(k, j)]).sum::<f64>()
        });
        let Sx_c = dense(&data.S_x);
        let S_x = Mat::from_fn(9, n, |r, j| Sx_c[(r, j)] + d[r / 3] * S_t[(r % 3, j)]);
        let S_bar: Vec<Mat<f64>> = data.S_bar.iter().map(dense).collect();
        let S_bar_sym: Vec<Mat<f64>> = PAIRS
            .iter()
            .map(|&(a, b)| Mat::from_fn(n, n, |i, j| S_bar[3 * a + b][(i, j)] + S_bar[3 * b + a][(i, j)]))
            .collect();
        let S_tilde: Vec<Mat<f64>> = (0..3)
            .map(|i| {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                Mat::from_fn(n, n, |r, s| S_bar[3 * j + k][(r, s)] - S_bar[3 * k + j][(r, s)])
            })
            .collect();
        let nine = |k: usize| if k < 3 { &S_tilde[k] } else { &S_bar_sym[k - 3] };
        let stack = Mat::from_fn(9 * n, n, |r, c| nine(r / n)[(r % n, c)]);
        let vec_stack = Mat::from_fn(n * n, 9, |r, k| nine(k)[(r % n, r / n)]);
        let packed = (n <= PACKED_MAX_N).then(|| PackedInvariants {
            tilde: PackedTall::new(3 * n, n, |r, c| stack[(r, c)]),
            sym: PackedTall::new(6 * n, n, |r, c| stack[(3 * n + r, c)]),
            vec: PackedTall::new(n * n, 9, |r, c| vec_stack[(r, c)]),
        });
        let small = (0..n)
            .map(|j| {
                let mut c = [0.0; SMALL];
                for i in 0..3 {
                    c[i] = S_t[(i, j)];
                    c[3 + i] = S_r[(i, j)];
                }
                for r in 0..9 {
                    c[6 + r] = S_x[(r, j)];
                }
                c
            })
            .collect::<Vec<_>>();
        let small_rows = (0..SMALL - 1).flat_map(|r| small.iter().map(move |c| c[r])).collect();
        Self {
            mass: m,
            d,
            J0,
            S_t,
            S_r,
            S_x,
            S_bar_sym,
            S_tilde,
            M_CB: M_CB.clone(),
            stack,
            vec_stack,
            packed,
            small,
            small_rows,
        }
    }

    /// Number of CB coordinates $n$.
    pub fn n(&self) -> usize {
        self.S_t.ncols()
    }
}

/// $\mathbf A\mathbf x$ for a $3\times n$ matrix.
#[inline]
pub(crate) fn mul3(A: &Mat<f64>, x: &[f64]) -> Vector3<f64> {
    let mut r = [0.0; 3];
    for (j, xj) in x.iter().enumerate() {
        let a = &A.col_as_slice(j)[..3];
        r[0] += a[0] * xj;
        r[1] += a[1] * xj;
        r[2] += a[2] * xj;
    }
    Vector3::from(r)
}

/// $\mathbf A^T\mathbf w$ for a $3\times n$ matrix, added to `out` times `alpha`.
#[inline]
pub(crate) fn add_mul3t(out: &mut [f64], A: &Mat<f64>, w: &Vector3<f64>, alpha: f64) {
    for (j, o) in out.iter_mut().enumerate() {
        let a = &A.col_as_slice(j)[..3];
        *o += alpha * (a[0] * w[0] + a[1] * w[1] + a[2] * w[2]);
    }
}

/// $\mathbf A\mathbf x$ for an $n\times n$ matrix into `out`.
#[inline]
pub(crate) fn matvec(A: &Mat<f64>, x: &[f64], out: &mut [f64]) {
    out.iter_mut().for_each(|o| *o = 0.0);
    for (j, xj) in x.iter().enumerate() {
        if *xj == 0.0 {
            continue;
        }
        for (o, a) in out.iter_mut().zip(A.col_as_slice(j)) {
            *o += a * xj;
        }
    }
}

/// $\mathbf a\cdot\mathbf b$ over the shorter length: two partial sums of fused multiply-adds
/// over the pairs of entries (one two-wide vector), the odd last entry added after.
#[inline(always)]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let len = a.len().min(b.len());
    let (a, b) = (&a[..len], &b[..len]);
    let mut p = [0.0f64; 2];
    let (ca, cb) = (a.chunks_exact(2), b.chunks_exact(2));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        p[0] = x[0].mul_add(y[0], p[0]);
        p[1] = x[1].mul_add(y[1], p[1]);
    }
    let mut sum = p[0] + p[1];
    for (x, y) in ra.iter().zip(rb) {
        sum = x.mul_add(*y, sum);
    }
    sum
}

/// The FFR inertia force and, on request, its partial derivatives (module docs).
#[derive(Clone, Debug)]
pub struct FfrForce {
    /// $\mathbf F = \mathbf M_{ffr}\dot{\boldsymbol\nu} + \mathbf h$, $6 + n$.
    pub F: Vec<f64>,
    /// $\mathbf M_{ffr}(\mathbf q)$, $(6+n)^2$.
    pub M: Mat<f64>,
    /// $\partial\mathbf F/\partial\boldsymbol\nu$, $(6+n)^2$.
    pub F_nu: Mat<f64>,
    /// $\partial\mathbf F/\partial\mathbf q^{jj}$ at fixed $\boldsymbol\nu, \dot{\boldsymbol\nu}$, $(6+n)\times n$.
    pub F_q: Mat<f64>,
}

impl FfrForce {
    /// Buffers for $n$ CB coordinates.
    pub fn zeros(n: usize) -> Self {
        Self {
            F: vec![0.0; 6 + n],
            M: Mat::zeros(6 + n, 6 + n),
            F_nu: Mat::zeros(6 + n, 6 + n),
            F_q: Mat::zeros(6 + n, n),
        }
    }
}

/// Scratch of [`FfrInertia::force_into`]: contractions of the invariants with $\mathbf q$ and
/// its rates, kept between calls so that the hot loop does not allocate.
#[derive(Clone, Debug)]
pub struct FfrScratch {
    /// $\mathbf j_q$ buffers ($3\times n$).
    jq_Om: Mat<f64>,
    jq_Omd: Mat<f64>,
    jqd_Om: Mat<f64>,
    /// Right-hand sides $[\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q}]$ and the stacked product ($9n\times3$),
    /// read in place through `ContractionViews`.
    rhs: Mat<f64>,
    prod: Mat<f64>,
    /// Coefficients ($9\times2$) and the two $n\times n$ blocks from `vec_stack` ($n^2\times2$).
    coef: Mat<f64>,
    qq: Mat<f64>,
}

impl FfrScratch {
    pub fn new(n: usize) -> Self {
        Self {
            jq_Om: Mat::zeros(3, n),
            jq_Omd: Mat::zeros(3, n),
            jqd_Om: Mat::zeros(3, n),
            rhs: Mat::zeros(n, 3),
            prod: Mat::zeros(9 * n, 3),
            coef: Mat::zeros(9, 2),
            qq: Mat::zeros(n * n, 2),
        }
    }
}

/// The contractions in the stacked product of [`FfrScratch`], in place (no copies):
/// $\bar{\mathbf S}^{sym}_p\mathbf q$, $\bar{\mathbf S}^{sym}_p\dot{\mathbf q}$ ($n\times6$) and
/// $\tilde{\mathbf S}_i\mathbf q$, $\tilde{\mathbf S}_i\dot{\mathbf q}$, $\tilde{\mathbf S}_i\ddot{\mathbf q}$
/// ($n\times3$; $\bar{\mathbf S}^{sym}_p\dot{\mathbf q}$ and $\tilde{\mathbf S}_i\ddot{\mathbf q}$ only after
/// the contractions for the partials, `FfrInertia::contractions`).
struct ContractionViews<'a> {
    sig: MatRef<'a, f64>,
    sigd: MatRef<'a, f64>,
    tq: MatRef<'a, f64>,
    tqd: MatRef<'a, f64>,
    tqdd: MatRef<'a, f64>,
}

impl<'a> ContractionViews<'a> {
    /// Column `c` of the product `prod` with $[\mathbf q, \dot{\mathbf q}, \ddot{\mathbf q}]$ holds the
    /// nine stacked blocks of $n$ entries, so the contractions are column-major views of it.
    fn of(prod: &'a Mat<f64>, n: usize) -> Self {
        let view = |c: usize, k0: usize, cols: usize| {
            MatRef::from_column_major_slice(&prod.col_as_slice(c)[k0 * n..(k0 + cols) * n], n, cols)
        };
        Self {
            sig: view(0, 3, 6),
            sigd: view(1, 3, 6),
            tq: view(0, 0, 3),
            tqd: view(1, 0, 3),
            tqdd: view(2, 0, 3),
        }
    }
}

/// Small contractions of [`FfrScratch`]'s columns.
struct Contractions {
    s: Vector3<f64>,
    sd: Vector3<f64>,
    J: Matrix3<f64>,
    Jd: Matrix3<f64>,
    /// $\mathbf S_r\dot{\mathbf q}$, $\mathbf S_t\ddot{\mathbf q}$, $\mathbf S_r\ddot{\mathbf q}$.
    sr_qd: Vector3<f64>,
    st_qdd: Vector3<f64>,
    sr_qdd: Vector3<f64>,
}

/// The arguments of one [`FfrInertia::force_impl`], handed to `pulp`'s runtime dispatch, which
/// calls [`FfrInertia::force_body`] with the machine's vector instructions.
struct ForceArgs<'a, 'b> {
    inertia: &'a FfrInertia,
    q: &'a [f64],
    nu: &'a [f64],
    nu_dot: &'a [f64],
    /// Form $\mathbf M_{ffr}$.
    mass: bool,
    /// Form the partials $\partial\mathbf F/\partial\boldsymbol\nu$, $\partial\mathbf F/\partial\mathbf q$.
    partials: bool,
    out: &'b mut FfrForce,
    w: &'b mut FfrScratch,
}

impl pulp::WithSimd for ForceArgs<'_, '_> {
    type Output = ();
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, simd: S) {
        let inertia = self.inertia;
        inertia.force_body(simd, self)
    }
}

impl FfrInertia {
    /// The contractions $\bar{\mathbf S}^{sym}_p\mathbf q$, $\tilde{\mathbf S}_i\mathbf q$, $\tilde{\mathbf S}_i\dot{\mathbf q}$
    /// and, with `partials` (only the partials need them), $\bar{\mathbf S}^{sym}_p\dot{\mathbf q}$ and
    /// $\tilde{\mathbf S}_i\ddot{\mathbf q}$: $12n^2$ multiply-adds for the force alone, $21n^2$ with the partials.
    #[inline(always)]
    fn contractions<S: pulp::Simd>(
        &self,
        simd: S,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        partials: bool,
        w: &mut FfrScratch,
    ) -> Contractions {
        let n = self.n();
        let m = self.mass;
        if let Some(p) = &self.packed {
            // The S~_i rows with q, qd and (for the partials) qdd, the S_bar_sym rows with q and
            // (for the partials) qd.
            let [c0, c1, c2] = cols_mut::<3>(w.prod.as_mut());
            let ((t0, s0), (t1, s1)) = (c0.split_at_mut(3 * n), c1.split_at_mut(3 * n));
            if partials {
                p.tilde.mul([q, qd, qdd], [t0, t1, &mut c2[..3 * n]]);
                p.sym.mul([q, qd], [s0, s1]);
            } else {
                p.tilde.mul([q, qd], [t0, t1]);
                p.sym.mul([q], [s0]);
            }
        } else {
            w.rhs.col_as_slice_mut(0).copy_from_slice(q);
            w.rhs.col_as_slice_mut(1).copy_from_slice(qd);
            w.rhs.col_as_slice_mut(2).copy_from_slice(qdd);
            faer::linalg::matmul::matmul(
                w.prod.as_mut().subcols_mut(0, 2 + partials as usize),
                faer::Accum::Replace,
                self.stack.as_ref(),
                w.rhs.as_ref().subcols(0, 2 + partials as usize),
                1.0,
                faer::Par::Seq,
            );
        }
        // X_ab = (S_x)_ab q (row 3a + b of S_x), Xd = (S_x)_ab qd, S_t q, S_t qd and the S_r,
        // S_t products of F in one pass over the columns; J1 = 2 tr(X) I - X - X^T.
        let (q, qd) = (&q[..n], &qd[..n]);
        let [pq, pqd, pqdd] = self.small_products(simd, [q, qd, &qdd[..n]]);
        let v3 = |p: &[f64; SMALL], r: usize| Vector3::new(p[r], p[r + 1], p[r + 2]);
        let s = self.d * m + v3(&pq, 0);
        let sd = v3(&pqd, 0);
        let X = Matrix3::from_fn(|a, b| pq[6 + 3 * a + b]);
        let Xd = Matrix3::from_fn(|a, b| pqd[6 + 3 * a + b]);
        // W_ab = q^T S_bar_ab q = q.sig_ab / 2 and W3_ab = qd.sig_ab on the six pairs.
        let sig = ContractionViews::of(&w.prod, n).sig;
        let (mut wp, mut w3p) = ([0.0; 6], [0.0; 6]);
        for p in 0..6 {
            let c = &col(sig, p)[..n];
            wp[p] = 0.5 * dot(q, c);
            w3p[p] = dot(qd, c);
        }
        let W = Matrix3::from_fn(|a, b| wp[pair(a, b)]);
        let W3 = Matrix3::from_fn(|a, b| w3p[pair(a, b)]);
        let I = Matrix3::identity();
        let J = self.deformed_J(&X, &W);
        let Jd = I * (2.0 * Xd.trace()) - Xd - Xd.transpose() + I * W3.trace() - W3;
        Contractions {
            s,
            sd,
            J,
            Jd,
            sr_qd: v3(&pqd, 3),
            st_qdd: v3(&pqdd, 0),
            sr_qdd: v3(&pqdd, 3),
        }
    }

    /// $[\mathbf S_t; \mathbf S_r; \mathbf S_x]\mathbf x_c$ for the right-hand sides `x` ($n$ each),
    /// by the columns of `small`: rows 0-2, 3-5 and 6-14 of each result. In `simd`'s vectors
    /// (four-wide with AVX2); each entry is the same sum of fused multiply-adds in the order of
    /// the columns whatever the vector width (`pulp::Scalar` gives the same bits).
    #[inline(always)]
    fn small_products<S: pulp::Simd, const C: usize>(&self, simd: S, x: [&[f64]; C]) -> [[f64; SMALL]; C] {
        let mut acc = [[0.0f64; SMALL]; C];
        for (a, x) in acc.iter_mut().zip(x) {
            let (a, _) = S::as_mut_simd_f64s(a);
            for (col, xj) in self.small.iter().zip(x) {
                let (col, _) = S::as_simd_f64s(col);
                let b = simd.splat_f64s(*xj);
                for (a, c) in a.iter_mut().zip(col) {
                    *a = simd.mul_add_f64s(*c, b, *a);
                }
            }
        }
        acc
    }

    /// $\mathbf J(\mathbf q) = \mathbf J_0 + 2\,\mathrm{tr}(\mathbf X)\mathbf I - \mathbf X - \mathbf X^T +
    /// \mathrm{tr}(\mathbf W)\mathbf I - \mathbf W$ from $\mathbf X_{ab} = (\mathbf S_x)_{ab}\mathbf q$ and
    /// $\mathbf W_{ab} = \mathbf q^T\bar{\mathbf S}_{ab}\mathbf q$ (the force's contractions and the
    /// kinetic energy share it).
    fn deformed_J(&self, X: &Matrix3<f64>, W: &Matrix3<f64>) -> Matrix3<f64> {
        let I = Matrix3::identity();
        self.J0 + I * (2.0 * X.trace()) - X - X.transpose() + I * W.trace() - W
    }

    /// $\mathbf j_q(\mathbf w) = \partial(\mathbf J(\mathbf q)\mathbf w)/\partial\mathbf q$ ($3\times n$):
    /// row $i$ is $w_i(2\,\mathrm{tr}\mathbf S_x + \mathrm{tr}\boldsymbol\sigma) - \sum_b w_b
    /// ((\mathbf S_x)_{ib} + (\mathbf S_x)_{bi} + \boldsymbol\sigma_{ib})$, $\boldsymbol\sigma_{ab} =
    /// (\bar{\mathbf S}_{ab} + \bar{\mathbf S}_{ba})\mathbf q$. With `with_sx = false` only the
    /// $\boldsymbol\sigma$ part (that is $\partial(\dot{\mathbf J}\mathbf w)/\partial\mathbf q$ when
    /// `sig` holds $\bar{\mathbf S}^{sym}\dot{\mathbf q}$).
    fn jq(&self, w: &Vector3<f64>, sig: MatRef<'_, f64>, with_sx: bool, out: &mut Mat<f64>) {
        let n = self.n();
        let sg: [&[f64]; 6] = std::array::from_fn(|p| &col(sig, p)[..n]);
        let (w0, w1, w2) = (w[0], w[1], w[2]);
        for j in 0..n {
            // The symmetric a = sigma + S_x + S_x^T of column j (in the order of `PAIRS`) and
            // tr(sigma) + 2 tr(S_x), unrolled: row i is w_i tr - (a w)_i.
            let mut a = [sg[0][j], sg[1][j], sg[2][j], sg[3][j], sg[4][j], sg[5][j]];
            let mut tr = a[0] + a[1] + a[2];
            if with_sx {
                let sx = &self.S_x.col_as_slice(j)[..9];
                tr += 2.0 * (sx[0] + sx[4] + sx[8]);
                a[0] += 2.0 * sx[0];
                a[1] += 2.0 * sx[4];
                a[2] += 2.0 * sx[8];
                a[3] += sx[1] + sx[3];
                a[4] += sx[2] + sx[6];
                a[5] += sx[5] + sx[7];
            }
            let o = &mut out.col_as_slice_mut(j)[..3];
            o[0] = w0 * tr - (w0 * a[0] + w1 * a[3] + w2 * a[4]);
            o[1] = w1 * tr - (w0 * a[3] + w1 * a[1] + w2 * a[5]);
            o[2] = w2 * tr - (w0 * a[4] + w1 * a[5] + w2 * a[2]);
        }
    }

    /// The kinetic energy $\tfrac12\boldsymbol\nu^T\mathbf M_{ffr}(\mathbf q)\boldsymbol\nu$,
    /// $\boldsymbol\nu = [\boldsymbol\xi_v;\ \boldsymbol\xi_\omega;\ \mathbf c]$, by the blocks of
    /// [`Self::mass_matrix`] without forming it: $m\,\mathbf v\cdot\mathbf v - 2\mathbf v\cdot(\mathbf s\times
    /// \boldsymbol\omega) + 2\mathbf v\cdot\mathbf S_t\mathbf c + \boldsymbol\omega\cdot\mathbf J\boldsymbol\omega +
    /// 2\boldsymbol\omega\cdot(\mathbf S_r - (\tilde{\mathbf S}\mathbf q)^T)\mathbf c + \mathbf c^T\mathbf M_{CB}\mathbf c$, halved,
    /// with the contractions of $\mathbf q$ alone (an energy sensor at every step: one small
    /// allocation, no scratch of the force). Checked equal to the quadratic form with
    /// [`Self::mass_matrix`] by `tests/unit/evaluation.rs` (through `kinetic_energy_in`).
    pub fn kinetic_energy(&self, q: &[f64], nu: &[f64]) -> f64 {
        let n = self.n();
        let m = self.mass;
        // The stacked product with q alone: S~_i q (3n) then S_bar_sym q (6n), as one column
        // of `contractions`' product.
        let mut prod = vec![0.0; 9 * n];
        if let Some(p) = &self.packed {
            let (t0, s0) = prod.split_at_mut(3 * n);
            p.tilde.mul([q], [t0]);
            p.sym.mul([q], [s0]);
        } else {
            faer::linalg::matmul::matmul(
                faer::MatMut::from_column_major_slice_mut(&mut prod, 9 * n, 1),
                faer::Accum::Replace,
                self.stack.as_ref(),
                faer::MatRef::from_column_major_slice(&q[..n], n, 1),
                1.0,
                faer::Par::Seq,
            );
        }
        let q = &q[..n];
        let [pq] = self.small_products(pulp::Scalar::new(), [q]);
        let s = self.d * m + Vector3::new(pq[0], pq[1], pq[2]);
        let X = Matrix3::from_fn(|a, b| pq[6 + 3 * a + b]);
        let wp: [f64; 6] = std::array::from_fn(|p| 0.5 * dot(q, &prod[(3 + p) * n..(4 + p) * n]));
        let W = Matrix3::from_fn(|a, b| wp[pair(a, b)]);
        let J = self.deformed_J(&X, &W);
        let v = Vector3::new(nu[0], nu[1], nu[2]);
        let om = Vector3::new(nu[3], nu[4], nu[5]);
        let c = &nu[6..6 + n];
        let mut T2 = m * v.dot(&v) - 2.0 * v.dot(&s.cross(&om)) + om.dot(&(J * om));
        for (j, cj) in c.iter().enumerate() {
            let st = self.S_t.col_as_slice(j);
            let sr = self.S_r.col_as_slice(j);
            // Column j of S_r - (S~ q)^T: (S~ q) is n x 3, column i at prod[i n..].
            let mut coupling = 0.0;
            for i in 0..3 {
                coupling += v[i] * st[i] + om[i] * (sr[i] - prod[i * n + j]);
            }
            let mcb: f64 = self.M_CB.col_as_slice(j)[..n].iter().zip(c).map(|(a, b)| a * b).sum();
            T2 += cj * (2.0 * coupling + mcb);
        }
        0.5 * T2
    }

    /// $\mathbf M_{ffr}(\mathbf q)$ (module docs).
    pub fn mass_matrix(&self, q: &[f64]) -> Mat<f64> {
        let n = self.n();
        let zeros = vec![0.0; n];
        let mut w = FfrScratch::new(n);
        let c = self.contractions(pulp::Scalar::new(), q, &zeros, &zeros, false, &mut w);
        let mut M = Mat::zeros(6 + n, 6 + n);
        self.fill_mass(&c, ContractionViews::of(&w.prod, n).tq, &mut M);
        M
    }

    fn fill_mass(&self, c: &Contractions, tq: MatRef<'_, f64>, M: &mut Mat<f64>) {
        let n = self.n();
        let m = self.mass;
        let st = skew(&c.s);
        for i in 0..3 {
            for j in 0..3 {
                M[(i, j)] = if i == j { m } else { 0.0 };
                M[(i, 3 + j)] = -st[(i, j)];
                M[(3 + i, j)] = st[(i, j)];
                M[(3 + i, 3 + j)] = c.J[(i, j)];
            }
        }
        for j in 0..n {
            for i in 0..3 {
                let srw = self.S_r[(i, j)] - tq[(j, i)];
                M[(i, 6 + j)] = self.S_t[(i, j)];
                M[(6 + j, i)] = self.S_t[(i, j)];
                M[(3 + i, 6 + j)] = srw;
                M[(6 + j, 3 + i)] = srw;
            }
            M.col_as_slice_mut(6 + j)[6..].copy_from_slice(self.M_CB.col_as_slice(j));
        }
    }

    /// Allocating form of [`Self::force_into`].
    pub fn force(&self, q: &[f64], nu: &[f64], nu_dot: &[f64]) -> FfrForce {
        let n = self.n();
        let mut out = FfrForce::zeros(n);
        let mut w = FfrScratch::new(n);
        self.force_into(q, nu, nu_dot, &mut out, &mut w);
        out
    }

    /// Allocating form of [`Self::force_with_partials_into`].
    pub fn force_with_partials(&self, q: &[f64], nu: &[f64], nu_dot: &[f64]) -> FfrForce {
        let n = self.n();
        let mut out = FfrForce::zeros(n);
        let mut w = FfrScratch::new(n);
        self.force_with_partials_into(q, nu, nu_dot, &mut out, &mut w);
        out
    }

    /// $\mathbf F(\mathbf q, \boldsymbol\nu, \dot{\boldsymbol\nu})$, $\mathbf M_{ffr}$ and the derivatives
    /// $\partial\mathbf F/\partial\boldsymbol\nu$, $\partial\mathbf F/\partial\mathbf q$ (module docs).
    ///
    /// # Derivation
    /// Straight differentiation of the three force blocks of the module docs; with
    /// $\mathbf p_V = m\mathbf V + \boldsymbol\Omega\times\mathbf s + \dot{\mathbf s}$,
    /// $\mathbf p_\Omega = \mathbf s\times\mathbf V + \mathbf J\boldsymbol\Omega + (\mathbf S_r + \mathbf S_w)\dot{\mathbf q}$,
    /// $c_{ab} = \delta_{ab}|\boldsymbol\Omega|^2 - \Omega_a\Omega_b$ and $\mathrm{Rows}(\mathbf t)$ the
    /// $3\times n$ matrix with rows $\mathbf t_i^T$ ($= \partial(\mathbf S_w(\mathbf q)\mathbf x)/\partial\mathbf q$
    /// for $\mathbf t_i = \tilde{\mathbf S}_i\mathbf x$):
    ///
    /// | block | $\partial/\partial\mathbf V$ | $\partial/\partial\boldsymbol\Omega$ | $\partial/\partial\dot{\mathbf q}$ | $\partial/\partial\mathbf q$ |
    /// |---|---|---|---|---|
    /// | $\mathbf F_V$ | $m\tilde{\boldsymbol\Omega}$ | $-\tilde{\dot{\mathbf s}} - \tilde{\mathbf p}_V - \tilde{\boldsymbol\Omega}\tilde{\mathbf s}$ | $2\tilde{\boldsymbol\Omega}\mathbf S_t$ | $(\tilde{\dot{\boldsymbol\Omega}} + \tilde{\boldsymbol\Omega}^2)\mathbf S_t$ |
    /// | $\mathbf F_\Omega$ | $\tilde{\dot{\mathbf s}} + \tilde{\boldsymbol\Omega}\tilde{\mathbf s} - \tilde{\mathbf p}_V + m\tilde{\mathbf V}$ | $\dot{\mathbf J} - \tilde{\mathbf p}_\Omega + \tilde{\boldsymbol\Omega}\mathbf J - \tilde{\mathbf V}\tilde{\mathbf s}$ | $\mathbf j_q(\boldsymbol\Omega) + \tilde{\boldsymbol\Omega}(\mathbf S_r + \mathbf S_w)$ | see below |
    /// | $\mathbf F_q$ | $\mathbf S_t^T\tilde{\boldsymbol\Omega}$ | $2\mathbf S_w(\dot{\mathbf q})^T - \mathbf S_t^T\tilde{\mathbf V} - \mathbf j_q(\boldsymbol\Omega)^T$ | $-2\sum_i\Omega_i\tilde{\mathbf S}_i$ | $-\sum_i\dot\Omega_i\tilde{\mathbf S}_i - \tfrac12\sum_{ab}c_{ab}\bar{\mathbf S}^{sym}_{ab}$ |
    ///
    /// $\partial\mathbf F_\Omega/\partial\mathbf q = -\tilde{\dot{\mathbf V}}\mathbf S_t + \mathbf j_q(\dot{\boldsymbol\Omega}) +
    /// \mathrm{Rows}(\tilde{\mathbf S}\ddot{\mathbf q}) + \dot{\mathbf j}_q(\boldsymbol\Omega) +
    /// \tilde{\boldsymbol\Omega}(-\tilde{\mathbf V}\mathbf S_t + \mathbf j_q(\boldsymbol\Omega) + \mathrm{Rows}(\tilde{\mathbf S}\dot{\mathbf q})) +
    /// \tilde{\mathbf V}\tilde{\boldsymbol\Omega}\mathbf S_t$, with $\dot{\mathbf j}_q(\mathbf w) =
    /// \partial(\dot{\mathbf J}\mathbf w)/\partial\mathbf q$. Checked by
    /// `tests/unit/fd_tangent.rs::ffr_partials`.
    pub fn force_with_partials_into(
        &self,
        q: &[f64],
        nu: &[f64],
        nu_dot: &[f64],
        out: &mut FfrForce,
        w: &mut FfrScratch,
    ) {
        self.force_impl(q, nu, nu_dot, true, true, out, w);
    }

    /// [`Self::force_with_partials_into`] without the derivatives: $\mathbf F$ and $\mathbf M_{ffr}$
    /// (`out.F_nu`, `out.F_q` keep their old values).
    pub fn force_into(&self, q: &[f64], nu: &[f64], nu_dot: &[f64], out: &mut FfrForce, w: &mut FfrScratch) {
        self.force_impl(q, nu, nu_dot, true, false, out, w);
    }

    /// $\mathbf F(\mathbf q, \boldsymbol\nu, \dot{\boldsymbol\nu})$ alone into `out.F` (`out.M` and the
    /// partials keep their old values): the residual of a forces-only evaluation, which never
    /// forms $\mathbf M_{ffr}$ ([`Self::force_into`] for the formulas). Equal to the force of
    /// [`Self::force_into`] to round-off (`tests/unit/evaluation.rs`).
    pub fn force_only_into(&self, q: &[f64], nu: &[f64], nu_dot: &[f64], out: &mut FfrForce, w: &mut FfrScratch) {
        self.force_impl(q, nu, nu_dot, false, false, out, w);
    }

    /// [`Self::force_into`] with $\mathbf M_{ffr}$ on request (`mass`). Compiled for the machine's
    /// vector instructions like the block kernels of [`crate::transform`] (`pulp`'s runtime
    /// dispatch; AVX2 and FMA where the machine has them), so that its column loops and fused
    /// multiply-adds run on vector hardware.
    #[allow(clippy::too_many_arguments)]
    fn force_impl(
        &self,
        q: &[f64],
        nu: &[f64],
        nu_dot: &[f64],
        mass: bool,
        partials: bool,
        out: &mut FfrForce,
        w: &mut FfrScratch,
    ) {
        pulp::Arch::new().dispatch(ForceArgs {
            inertia: self,
            q,
            nu,
            nu_dot,
            mass,
            partials,
            out,
            w,
        })
    }

    #[inline(always)]
    fn force_body<S: pulp::Simd>(&self, simd: S, args: ForceArgs<'_, '_>) {
        let (q, nu, nu_dot, out, w) = (args.q, args.nu, args.nu_dot, args.out, args.w);
        let (mass, partials) = (args.mass, args.partials);
        let n = self.n();
        let m = self.mass;
        let v3 = |x: &[f64], o: usize| Vector3::new(x[o], x[o + 1], x[o + 2]);
        let (V, Om, qd) = (v3(nu, 0), v3(nu, 3), &nu[6..]);
        let (Vd, Omd, qdd) = (v3(nu_dot, 0), v3(nu_dot, 3), &nu_dot[6..]);
        let c = self.contractions(simd, q, qd, qdd, partials, w);
        let ContractionViews {
            sig,
            sigd,
            tq,
            tqd,
            tqdd,
        } = ContractionViews::of(&w.prod, n);
        let (s, sd) = (c.s, c.sd);
        if partials {
            self.jq(&Om, sig, true, &mut w.jq_Om);
        }
        // F_q = M_CB qdd + S_t^T (Vd - V x Om) + (S_r + S_w)^T Omd + 2 S_w(qd)^T Om
        //     - 1/2 j_q(Om)^T Om. With S_w(x)^T y = -sum_i y_i S~_i x, (S_w(q) x)_i = -(S~_i q).x
        // and j_q(Om)^T Om (`Self::jq`) = sum_ab 2 c_ab (S_x)_ab + sum_p k_p sig_p, c_ab =
        // delta_ab |Om|^2 - Om_a Om_b, k_p = c_ab twice for a != b: [S_t; S_r; S_x]^T [a; Omd; -c]
        // by its rows (`small_rows`), then the columns of the contractions S~_i q, S~_i qd,
        // sig_p combined, each a loop over j.
        let (qd, qdd) = (&qd[..n], &qdd[..n]);
        let F = &mut out.F;
        let Fq = &mut F[6..6 + n];
        matvec(&self.M_CB, qdd, Fq);
        let a = Vd - V.cross(&Om);
        let o2 = Om.norm_squared();
        let cab = |a: usize, b: usize| if a == b { o2 - Om[a] * Om[a] } else { -Om[a] * Om[b] };
        let mut wt = [0.0; SMALL - 1];
        for i in 0..3 {
            wt[i] = a[i];
            wt[3 + i] = Omd[i];
        }
        for r in 0..9 {
            wt[6 + r] = -cab(r / 3, r % 3);
        }
        for (row, w) in self.small_rows.chunks_exact(n).zip(wt) {
            for (f, x) in Fq.iter_mut().zip(row) {
                *f = x.mul_add(w, *f);
            }
        }
        let ks: [f64; 6] = std::array::from_fn(|p| {
            let (a, b) = PAIRS[p];
            -0.5 * cab(a, b) * if a == b { 1.0 } else { 2.0 }
        });
        let sg: [&[f64]; 6] = std::array::from_fn(|p| &col(sig, p)[..n]);
        let t: [&[f64]; 3] = std::array::from_fn(|i| &col(tq, i)[..n]);
        let td: [&[f64]; 3] = std::array::from_fn(|i| &col(tqd, i)[..n]);
        let (ct, cd) = (-Omd, Om * -2.0);
        for j in 0..n {
            let v = (ct[0] * t[0][j] + ct[1] * t[1][j] + ct[2] * t[2][j])
                + (cd[0] * td[0][j] + cd[1] * td[1][j] + cd[2] * td[2][j]);
            let o = (ks[0] * sg[0][j] + ks[1] * sg[1][j] + ks[2] * sg[2][j])
                + (ks[3] * sg[3][j] + ks[4] * sg[4][j] + ks[5] * sg[5][j]);
            Fq[j] += v + o;
        }
        let Sw_qd = -Vector3::new(dot(t[0], qd), dot(t[1], qd), dot(t[2], qd));
        let Sw_qdd = -Vector3::new(dot(t[0], qdd), dot(t[1], qdd), dot(t[2], qdd));
        let Srw_qd = c.sr_qd + Sw_qd;
        let Srw_qdd = c.sr_qdd + Sw_qdd;
        let p_V = V * m + Om.cross(&s) + sd;
        let p_Om = s.cross(&V) + c.J * Om + Srw_qd;
        let F_V = Vd * m + Omd.cross(&s) + c.st_qdd + Om.cross(&sd) + Om.cross(&p_V);
        let F_Om = s.cross(&Vd) + c.J * Omd + Srw_qdd + sd.cross(&V) + c.Jd * Om + Om.cross(&p_Om) + V.cross(&p_V);
        F[0..3].copy_from_slice(F_V.as_slice());
        F[3..6].copy_from_slice(F_Om.as_slice());
        // The residual's M (not for a forces-only evaluation); the partials only for tangents.
        if mass {
            self.fill_mass(&c, tq, &mut out.M);
        }
        if !partials {
            return;
        }

        let (Ot, Vt, st, sdt) = (skew(&Om), skew(&V), skew(&s), skew(&sd));
        let F_nu = &mut out.F_nu;
        let put3 = |A: &mut Mat<f64>, r0: usize, c0: usize, B: &Matrix3<f64>| {
            for i in 0..3 {
                for j in 0..3 {
                    A[(r0 + i, c0 + j)] = B[(i, j)];
                }
            }
        };
        put3(F_nu, 0, 0, &(Ot * m));
        put3(F_nu, 0, 3, &(-sdt - skew(&p_V) - Ot * st));
        put3(F_nu, 3, 0, &(sdt + Ot * st - skew(&p_V) + Vt * m));
        put3(F_nu, 3, 3, &(c.Jd - skew(&p_Om) + Ot * c.J - Vt * st));
        let jq_Om = &w.jq_Om;
        for j in 0..n {
            let St = Vector3::new(self.S_t[(0, j)], self.S_t[(1, j)], self.S_t[(2, j)]);
            let Srw = Vector3::new(
                self.S_r[(0, j)] - tq[(j, 0)],
                self.S_r[(1, j)] - tq[(j, 1)],
                self.S_r[(2, j)] - tq[(j, 2)],
            );
            // [V, qd] = 2 Om~ S_t ; [Om, qd] = j_q(Om) + Om~ Srw
            let a = Ot * St * 2.0;
            let b = Ot * Srw;
            // [qd, V] = S_t^T Om~ ; row j of it is (Om~^T S_t_j)^T = -(Om~ S_t_j)^T
            let cv = -(Ot * St);
            // [qd, Om] = 2 S_w(qd)^T - S_t^T V~ - j_q(Om)^T ; S_w(qd)^T row j = -tqd_.j
            let cw = Vt * St; // -(S_t^T V~) row j = -(V~^T S_t_j)^T = (V~ S_t_j)^T
            for i in 0..3 {
                F_nu[(i, 6 + j)] = a[i];
                F_nu[(3 + i, 6 + j)] = b[i] + jq_Om[(i, j)];
                F_nu[(6 + j, i)] = cv[i];
                F_nu[(6 + j, 3 + i)] = -2.0 * tqd[(j, i)] + cw[i] - jq_Om[(i, j)];
            }
        }

        // F_Om rows: j_q(Omd) + jdot_q(Om) + Om~ j_q(Om) and the S_t, Rows terms.
        self.jq(&Omd, sig, true, &mut w.jq_Omd);
        self.jq(&Om, sigd, false, &mut w.jqd_Om);
        let F_q = &mut out.F_q;
        let A_V = skew(&Omd) + Ot * Ot;
        let A_Om = -skew(&Vd) - Ot * Vt + Vt * Ot;
        for j in 0..n {
            let St = Vector3::new(self.S_t[(0, j)], self.S_t[(1, j)], self.S_t[(2, j)]);
            let fv = A_V * St;
            let jqO = Vector3::new(jq_Om[(0, j)], jq_Om[(1, j)], jq_Om[(2, j)]);
            let rows_qd = Vector3::new(tqd[(j, 0)], tqd[(j, 1)], tqd[(j, 2)]);
            let fo = A_Om * St + Ot * (jqO + rows_qd);
            for i in 0..3 {
                F_q[(i, j)] = fv[i];
                F_q[(3 + i, j)] = fo[i] + w.jq_Omd[(i, j)] + tqdd[(j, i)] + w.jqd_Om[(i, j)];
            }
        }
        // The qq blocks, one product with the nine stacked matrices: F_q rows
        // -sum_i Omd_i S~_i - 1/2 sum_ab c_ab S_bar_sym_ab, and [qd, qd] = -2 sum_i Om_i S~_i of F_nu.
        let on2 = Om.norm_squared();
        let cab = |a: usize, b: usize| if a == b { on2 - Om[a] * Om[a] } else { -Om[a] * Om[b] };
        for i in 0..3 {
            w.coef[(i, 0)] = -Omd[i];
            w.coef[(i, 1)] = -2.0 * Om[i];
        }
        for (p, &(a, b)) in PAIRS.iter().enumerate() {
            // Off-diagonal pairs appear twice in the double sum.
            w.coef[(3 + p, 0)] = -0.5 * cab(a, b) * if a == b { 1.0 } else { 2.0 };
            w.coef[(3 + p, 1)] = 0.0;
        }
        if let Some(p) = &self.packed {
            let [q0, q1] = cols_mut::<2>(w.qq.as_mut());
            p.vec.mul([w.coef.col_as_slice(0), w.coef.col_as_slice(1)], [q0, q1]);
        } else {
            faer::linalg::matmul::matmul(
                w.qq.as_mut(),
                faer::Accum::Replace,
                self.vec_stack.as_ref(),
                w.coef.as_ref(),
                1.0,
                faer::Par::Seq,
            );
        }
        for j in 0..n {
            F_q.col_as_slice_mut(j)[6..].copy_from_slice(&w.qq.col_as_slice(0)[j * n..(j + 1) * n]);
            out.F_nu.col_as_slice_mut(6 + j)[6..].copy_from_slice(&w.qq.col_as_slice(1)[j * n..(j + 1) * n]);
        }
    }
}
