//! Linearised analysis about a state (theory guide §9): $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$
//! of the assembled system ([`System::matrices`]) and the eigenvalues of
//! $\hat{\mathbf M}\delta\ddot{\mathbf q} + \hat{\mathbf C}\delta\dot{\mathbf q} + \hat{\mathbf K}\delta\mathbf q = \mathbf 0$.
//!
//! * Undamped frequencies: $\omega^2$ = the eigenvalues of $\hat{\mathbf M}^{-1}\hat{\mathbf K}$ (real
//!   parts; $\hat{\mathbf K}$ need not be symmetric: follower loads, gyroscopic states).
//! * Damped (state-space) eigenvalues $s$ of $\begin{bmatrix}\mathbf 0 & \mathbf I\\ -\hat{\mathbf M}^{-1}\hat{\mathbf K} &
//!   -\hat{\mathbf M}^{-1}\hat{\mathbf C}\end{bmatrix}$, whose imaginary parts are the damped frequencies.
//!
//! Both are computed on a scaled problem (unit mass per unknown; the symmetric eigenproblem
//! when undamped and symmetric; the state-space matrix in a scaled time and balanced otherwise:
//! `Scaled`, theory guide §9.3), so that the eigensolvers' round-off is that of the spectrum
//! and a stable state is reported stable whatever the model's size and units
//! ([`growth_bound`]).
//!
//! Dense: meant for models of up to a few hundred unknowns. About a static equilibrium the
//! result is the small-vibration spectrum, including the geometric stiffness of the preload
//! (a tensioned beam is stiffer). About a moving state in these inertial absolute coordinates
//! the linearised equations are time-varying in general (a spinning body's coordinates turn),
//! so the instantaneous spectrum is not the rotating-frame one: use it for states whose
//! coordinates are steady.
//!
//! [`mode_energies`]: every mode with its frequency, damping ratio, rigid-body flag and the
//! shares of its strain and kinetic energy carried by each body, spring, point mass and node,
//! labelled by the dominant ones ("rod (62 % kinetic), node B"; dense as well).
//!
//! [`buckling`]: linearised buckling loads about a static state (dense as well).

#![allow(non_snake_case)]

use crate::assembly::system::{ElementKind, Matrices, System, Workspace};
use crate::error::{At, SolveError};
use crate::model::Body;
use crate::solvers::static_solver::check_finite_matrix;
use crate::state::State;
use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use serde::{Deserialize, Serialize};

/// Eigenvalues of the linearised system.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSpectrum {
    /// Undamped circular frequencies \[rad/s\], ascending (only eigenvalues of
    /// $\hat{\mathbf M}^{-1}\hat{\mathbf K}$ with positive real part).
    pub omega: Vec<f64>,
    /// State-space eigenvalues $(\mathrm{Re}\,s, \mathrm{Im}\,s)$ with $\mathrm{Im}\,s \ge 0$, by
    /// ascending imaginary part.
    pub state_space: Vec<(f64, f64)>,
}

/// $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$ at `state` (loads at full value).
pub fn linearize(system: &System, state: &State) -> Result<Matrices, SolveError> {
    let mut s = state.clone();
    system.matrices(&mut s, 1.0)
}

/// The spectrum of the linearisation at `state` (module docs).
pub fn spectrum(system: &System, state: &State) -> Result<LinearSpectrum, SolveError> {
    let m = linearize(system, state)?;
    let sc = Scaled::new(system, &m, At::Time(state.time()))?;
    let ev = sc.undamped_eigenvalues()?;
    let mut omega: Vec<f64> = ev.iter().filter(|l| l.re > 0.0).map(|l| l.re.sqrt()).collect();
    omega.sort_by(f64::total_cmp);
    let state_space = sc.state_space_eigenvalues(&ev)?;
    Ok(LinearSpectrum { omega, state_space })
}

impl LinearSpectrum {
    /// The state-space eigenvalues with a positive real part beyond round-off,
    /// $\mathrm{Re}\,s > 10^{-6}\max(\max|s|, 1\ \mathrm{s^{-1}})$ ([`growth_bound`]): the linearised
    /// motion grows (an unstable equilibrium, flutter, negative damping).
    pub fn growing(&self) -> Vec<(f64, f64)> {
        let bound = growth_bound(&self.state_space);
        self.state_space.iter().copied().filter(|s| s.0 > bound).collect()
    }
}

/// Relative bound on $\mathrm{Re}\,s$ above which a state-space eigenvalue grows
/// ([`LinearSpectrum::growing`], [`ModeEnergy::unstable`]).
pub const GROWTH_TOLERANCE: f64 = 1e-6;

/// The real part above which a state-space eigenvalue of `state_space` grows:
/// [`GROWTH_TOLERANCE`] $\cdot\max(\max|s|, 1\ \mathrm{s^{-1}})$. The eigenvalues are computed on
/// the scaled problem (theory guide §9.3), so their round-off is $\varepsilon$ of the spectrum's scale
/// $\max|s|$, except at a double zero eigenvalue (a rigid-body mode), which splits by
/// $\sqrt\varepsilon\max|s| \approx 1.5\cdot10^{-8}\max|s|$; the bound lies above both and far below
/// a real growth rate. The floor of 1/s keeps a spectrum of zeros (a free mechanism) from
/// calling round-off growth.
pub fn growth_bound(state_space: &[(f64, f64)]) -> f64 {
    GROWTH_TOLERANCE * state_space.iter().map(|s| s.0.hypot(s.1)).fold(1.0, f64::max)
}

fn singular(at: At, what: &str) -> SolveError {
    SolveError::Singular {
        at,
        step: 0,
        what: what.into(),
    }
}

/// The linearisation on a common scale (theory guide §9.1): in the coordinates
/// $\delta\mathbf q = \mathbf D\,\delta\tilde{\mathbf q}$, $\mathbf D = \mathrm{diag}(\hat M_{ii})^{-1/2}$, every unknown
/// (length, angle or modal coordinate, in any units) has unit mass,
/// $\tilde{\mathbf M} = \mathbf D\hat{\mathbf M}\mathbf D$, $\tilde{\mathbf C} = \mathbf D\hat{\mathbf C}\mathbf D$,
/// $\tilde{\mathbf K} = \mathbf D\hat{\mathbf K}\mathbf D$: a congruence, so the eigenvalues are those of
/// the model, but the dense eigensolvers, whose round-off is $\varepsilon$ times the norm of the
/// matrix they are given, now see a matrix whose norm is that of the spectrum.
struct Scaled {
    /// The diagonal of $\mathbf D$.
    d: Vec<f64>,
    M: Mat<f64>,
    C: Mat<f64>,
    K: Mat<f64>,
    /// $\mathbf L$ of $\tilde{\mathbf M} = \mathbf L\mathbf L^T$ when $\tilde{\mathbf M}$ is symmetric positive definite.
    L: Option<Mat<f64>>,
    /// $\tilde{\mathbf C} = \mathbf 0$ and $\tilde{\mathbf K}$ symmetric, with $\mathbf L$: the undamped symmetric
    /// case, solved as the symmetric eigenproblem $\mathbf L^{-1}\tilde{\mathbf K}\mathbf L^{-T}$, whose
    /// eigenvalues $\omega^2$ are real and give $s = \pm i\omega$ exactly.
    symmetric: bool,
    /// Frequency scale $\omega_{ref} = \max_i|\tilde K_{ii}|^{1/2}$ (else $\max_i|\tilde C_{ii}|$, else
    /// 1/s): the state-space matrix is formed in the time $\omega_{ref}t$.
    omega_ref: f64,
    at: At,
}

/// Largest $|A_{ij}|$.
fn max_abs(A: &Mat<f64>) -> f64 {
    A.col_iter()
        .flat_map(|c| c.iter().copied())
        .fold(0.0, |m, x| m.max(x.abs()))
}

/// Largest $|A_{ij} - A_{ji}|$.
fn max_asymmetry(A: &Mat<f64>) -> f64 {
    let n = A.nrows();
    (0..n)
        .flat_map(|j| (0..j).map(move |i| (i, j)))
        .fold(0.0, |m, (i, j)| m.max((A[(i, j)] - A[(j, i)]).abs()))
}

impl Scaled {
    /// The scaled matrices of `m` (its entries finite: else [`SolveError::NonFinite`] naming
    /// the coordinate).
    fn new(system: &System, m: &Matrices, at: At) -> Result<Self, SolveError> {
        for (what, A) in [
            ("mass matrix", &m.M),
            ("damping matrix", &m.C),
            ("tangent stiffness", &m.K),
        ] {
            check_finite_matrix(system, what, A, at)?;
        }
        let n = m.M.nrows();
        // Unit mass per unknown; an unknown without mass (held by a spring only) is scaled by
        // its stiffness instead.
        let d: Vec<f64> = (0..n)
            .map(|i| {
                let (mi, ki) = (m.M[(i, i)], m.K[(i, i)].abs());
                if mi > 0.0 {
                    1.0 / mi.sqrt()
                } else if ki > 0.0 {
                    1.0 / ki.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        let scale = |A: &Mat<f64>| Mat::from_fn(n, n, |i, j| d[i] * A[(i, j)] * d[j]);
        let (M, C, K) = (scale(&m.M), scale(&m.C), scale(&m.K));
        let diag = |A: &Mat<f64>| (0..n).map(|i| A[(i, i)].abs()).fold(0.0, f64::max);
        let omega_ref = [diag(&K).sqrt(), diag(&C), 1.0]
            .into_iter()
            .find(|&w| w > 0.0 && w.is_finite())
            .unwrap_or(1.0);
        // Symmetric to round-off: the eigenproblem of the symmetric parts is then within
        // 1e-10 relative of the model's, far below the growth bound.
        let L = (max_asymmetry(&M) <= 1e-10 * max_abs(&M))
            .then(|| {
                let Ms = Mat::from_fn(n, n, |i, j| 0.5 * (M[(i, j)] + M[(j, i)]));
                Ms.llt(faer::Side::Lower).ok().map(|llt| llt.L().to_owned())
            })
            .flatten();
        let symmetric =
            L.is_some() && max_abs(&C) == 0.0 && max_asymmetry(&K) <= 1e-10 * max_abs(&K).max(f64::MIN_POSITIVE);
        Ok(Self {
            d,
            M,
            C,
            K,
            L,
            symmetric,
            omega_ref,
            at,
        })
    }

    /// $\mathbf L^{-1}\mathbf A\mathbf L^{-T}$ for the symmetric part of `A` (symmetrised).
    fn congruent(&self, L: &Mat<f64>, A: &Mat<f64>) -> Mat<f64> {
        use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
        let n = A.nrows();
        let mut X = Mat::from_fn(n, n, |i, j| 0.5 * (A[(i, j)] + A[(j, i)]));
        solve_lower_triangular_in_place(L.as_ref(), X.as_mut(), faer::Par::Seq);
        let mut B = X.transpose().to_owned();
        solve_lower_triangular_in_place(L.as_ref(), B.as_mut(), faer::Par::Seq);
        Mat::from_fn(n, n, |i, j| 0.5 * (B[(i, j)] + B[(j, i)]))
    }

    /// $\tilde{\mathbf M}^{-1}\mathbf A$ (one LU of $\tilde{\mathbf M}$ per call).
    fn mass_solve(&self, A: &Mat<f64>) -> Result<Mat<f64>, SolveError> {
        let mut X = A.clone();
        self.M.partial_piv_lu().solve_in_place(X.as_mut());
        if X.col_iter().any(|c| c.iter().any(|x| !x.is_finite())) {
            return Err(singular(self.at, "mass matrix of the linearisation"));
        }
        Ok(X)
    }

    /// The eigenvalues $\omega^2$ of $\hat{\mathbf M}^{-1}\hat{\mathbf K}$ (real for the symmetric case).
    fn undamped_eigenvalues(&self) -> Result<Vec<c64>, SolveError> {
        let fail = || singular(self.at, "eigenvalues of M^-1 K did not converge");
        match (&self.L, self.symmetric) {
            (Some(L), true) => Ok(self
                .congruent(L, &self.K)
                .self_adjoint_eigenvalues(faer::Side::Lower)
                .map_err(|_| fail())?
                .into_iter()
                .map(|x| c64::new(x, 0.0))
                .collect()),
            _ => self.mass_solve(&self.K)?.eigenvalues().map_err(|_| fail()),
        }
    }

    /// The eigenvalues $\omega^2$ of $\hat{\mathbf M}^{-1}\hat{\mathbf K}$ and their eigenvectors in the
    /// model's coordinates (columns).
    fn undamped_modes(&self) -> Result<(Vec<c64>, Mat<c64>), SolveError> {
        let fail = || singular(self.at, "eigenvectors of M^-1 K did not converge");
        let n = self.d.len();
        let (values, U) = match (&self.L, self.symmetric) {
            (Some(L), true) => {
                use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
                let eig = self
                    .congruent(L, &self.K)
                    .self_adjoint_eigen(faer::Side::Lower)
                    .map_err(|_| fail())?;
                // phi~ = L^-T y.
                let mut Y = eig.U().to_owned();
                solve_upper_triangular_in_place(L.transpose(), Y.as_mut(), faer::Par::Seq);
                let S = eig.S().column_vector();
                let values = (0..n).map(|i| c64::new(S[i], 0.0)).collect();
                (values, Mat::from_fn(n, n, |i, j| c64::new(Y[(i, j)], 0.0)))
            }
            _ => {
                let eig = self.mass_solve(&self.K)?.eigen().map_err(|_| fail())?;
                let S = eig.S().column_vector();
                ((0..n).map(|i| S[i]).collect(), eig.U().to_owned())
            }
        };
        Ok((values, Mat::from_fn(n, n, |i, j| U[(i, j)] * self.d[i])))
    }

    /// State-space eigenvalues $s$ with $\mathrm{Im}\,s \ge 0$, by ascending imaginary part (module
    /// docs). Undamped symmetric case: $s = i\omega$ from the eigenvalues `omega_squared`
    /// ($\pm\sqrt{-\omega^2}$ for a negative one). Otherwise those of
    /// $\mathbf A = \begin{bmatrix}\mathbf 0 & \mathbf I\\ -\tilde{\mathbf M}^{-1}\tilde{\mathbf K}/\omega_{ref}^2 &
    /// -\tilde{\mathbf M}^{-1}\tilde{\mathbf C}/\omega_{ref}\end{bmatrix}$ in the time $\omega_{ref}t$ (both
    /// rows of blocks of one size), balanced ([`balance`]), times $\omega_{ref}$.
    fn state_space_eigenvalues(&self, omega_squared: &[c64]) -> Result<Vec<(f64, f64)>, SolveError> {
        let mut s: Vec<(f64, f64)> = if self.symmetric {
            omega_squared
                .iter()
                .flat_map(|l| {
                    let r = l.re.abs().sqrt();
                    if l.re >= 0.0 {
                        vec![(0.0, r)]
                    } else {
                        vec![(r, 0.0), (-r, 0.0)]
                    }
                })
                .collect()
        } else {
            let n = self.d.len();
            let w = self.omega_ref;
            let (MK, MC) = (self.mass_solve(&self.K)?, self.mass_solve(&self.C)?);
            let mut A = Mat::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
                (true, true) => 0.0,
                (true, false) => f64::from(i == j - n),
                (false, true) => -MK[(i - n, j)] / (w * w),
                (false, false) => -MC[(i - n, j - n)] / w,
            });
            balance(&mut A);
            let ev = A
                .eigenvalues()
                .map_err(|_| singular(self.at, "state-space eigenvalues did not converge"))?;
            ev.iter()
                .filter(|l| l.im >= 0.0)
                .map(|l| (w * l.re, w * l.im))
                .collect()
        };
        s.sort_by(|a, b| a.1.total_cmp(&b.1));
        Ok(s)
    }
}

/// Balances `A` in place by a diagonal similarity of powers of 2 (Osborne 1960, Parlett &
/// Reinsch 1969, LAPACK's `gebal` without permutations): each row and column pair is scaled
/// until their off-diagonal norms agree within a factor 2. Powers of 2 are exact, so the
/// eigenvalues are unchanged, while the norm, to which the eigensolver's round-off is
/// proportional, drops to about that of the spectrum.
fn balance(A: &mut Mat<f64>) {
    const RADIX: f64 = 2.0;
    let n = A.nrows();
    for _sweep in 0..100 {
        let mut done = true;
        for i in 0..n {
            let c: f64 = (0..n).filter(|&j| j != i).map(|j| A[(j, i)].abs()).sum();
            let r: f64 = (0..n).filter(|&j| j != i).map(|j| A[(i, j)].abs()).sum();
            if c == 0.0 || r == 0.0 {
                continue;
            }
            // f: the power of 2 with c f^2 within a factor 2 of r; the pair's norm becomes
            // c f + r / f.
            let (mut cf2, mut f) = (c, 1.0);
            while cf2 < r / RADIX {
                cf2 *= RADIX * RADIX;
                f *= RADIX;
            }
            while cf2 > r * RADIX {
                cf2 /= RADIX * RADIX;
                f /= RADIX;
            }
            if (cf2 + r) / f < 0.95 * (c + r) {
                done = false;
                for j in 0..n {
                    A[(i, j)] /= f;
                    A[(j, i)] *= f;
                }
            }
        }
        if done {
            break;
        }
    }
}

/// Linearised buckling about a static state: the critical load factors and their modes.
#[derive(Clone, Debug)]
pub struct Buckling {
    /// Critical load factors $\lambda_{cr} = \mu\lambda_s$, positive first by ascending value,
    /// then the negative ones (load reversed) by ascending magnitude.
    pub load_factors: Vec<f64>,
    /// The mode $\boldsymbol\phi$ of each load factor (column $i$), largest entry 1.
    pub modes: Mat<f64>,
}

/// Linearised buckling loads about the static state `loaded` at load factor `lambda`
/// (Abaqus' *BUCKLE, Bathe §6.8.2): the tangent is extrapolated linearly in the load,
/// $\hat{\mathbf K}(\lambda) = \hat{\mathbf K}_0 + \frac{\lambda}{\lambda_s}\Delta\hat{\mathbf K}$,
/// $\Delta\hat{\mathbf K} = \hat{\mathbf K}(\mathbf q_s;\lambda_s) - \hat{\mathbf K}_0$, with $\hat{\mathbf K}_0$
/// the tangent of the unloaded state `unloaded` at $\lambda = 0$, and
/// $(\hat{\mathbf K}_0 + \mu\Delta\hat{\mathbf K})\boldsymbol\phi = \mathbf 0$ gives $\lambda_{cr} = \mu\lambda_s$.
/// Solved as the eigenvalues $\nu = -1/\mu$ of $\hat{\mathbf K}_0^{-1}\Delta\hat{\mathbf K}$ (dense; real
/// ones only: $|\mathrm{Im}\,\nu| \le 10^{-8}\max|\nu|$). $\Delta\hat{\mathbf K}$ is the geometric
/// stiffness of the prestress plus the change of the elastic stiffness with the pre-buckling
/// deformation; for a column it is the former, and $\lambda_{cr}$ converges to Euler's load.
pub fn buckling(system: &System, unloaded: &State, loaded: &State, lambda: f64) -> Result<Buckling, SolveError> {
    let singular = |what: &str| SolveError::Singular {
        at: At::LoadFactor(lambda),
        step: 0,
        what: what.into(),
    };
    if !(lambda != 0.0 && lambda.is_finite()) {
        return Err(SolveError::InvalidSettings {
            what: format!("buckling needs the load factor of the loaded state, non-zero and finite (got {lambda})"),
        });
    }
    let K0 = system.matrices(&mut unloaded.clone(), 0.0)?.K;
    check_finite_matrix(
        system,
        "tangent stiffness of the unloaded state",
        &K0,
        At::LoadFactor(0.0),
    )?;
    let Ks = system.matrices(&mut loaded.clone(), lambda)?.K;
    check_finite_matrix(
        system,
        "tangent stiffness of the loaded state",
        &Ks,
        At::LoadFactor(lambda),
    )?;
    let n = system.n_dof();
    let mut A = Mat::from_fn(n, n, |i, j| Ks[(i, j)] - K0[(i, j)]);
    let lu = K0.partial_piv_lu();
    lu.solve_in_place(A.as_mut());
    if A.col_iter().any(|c| c.iter().any(|x| !x.is_finite())) {
        return Err(singular("tangent stiffness of the unloaded state (buckling)"));
    }
    let eig = A
        .eigen()
        .map_err(|_| singular("eigenvalues of K0^-1 dK did not converge (buckling)"))?;
    let s = eig.S().column_vector();
    let U = eig.U();
    let nu_max = (0..n).map(|i| s[i].norm()).fold(0.0, f64::max);
    let mut found: Vec<(f64, usize)> = (0..n)
        .filter(|&i| s[i].im.abs() <= 1e-8 * nu_max && s[i].re.abs() > 1e-12 * nu_max)
        .map(|i| (-lambda / s[i].re, i))
        .collect();
    found.sort_by(|a, b| match (a.0 > 0.0, b.0 > 0.0) {
        (true, false) => std::cmp::Ordering::Less,
        (false, true) => std::cmp::Ordering::Greater,
        _ => a.0.abs().total_cmp(&b.0.abs()),
    });
    let modes = Mat::from_fn(n, found.len(), |r, c| U[(r, found[c].1)].re);
    let mut modes = modes;
    for c in 0..found.len() {
        let big = (0..n)
            .map(|r| modes[(r, c)])
            .fold(0.0, |m: f64, x| if x.abs() > m.abs() { x } else { m });
        if big != 0.0 {
            for r in 0..n {
                modes[(r, c)] /= big;
            }
        }
    }
    Ok(Buckling {
        load_factors: found.iter().map(|f| f.0).collect(),
        modes,
    })
}

/// What carries a share of a mode's energy (an element of the assembly, a joint spring, or the
/// joints' geometric stiffness).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum EnergyCarrier {
    /// A flexible or rigid body, by name.
    Body(String),
    /// A point mass on a node (`name`: its name, empty when it has none).
    PointMass { index: usize, name: String, node: String },
    /// A point-to-point spring-damper, by name.
    Spring(String),
    /// A follower load's stiffness (a dead load has none).
    Load { index: usize, node: String },
    /// A spring on a joint coordinate.
    JointSpring { joint: String, coordinate: usize },
    /// A user-defined force's stiffness and damping ([`crate::UserForce`]), by name.
    UserForce(String),
    /// The joints' geometric term $\mathbf G_r$ of $\hat{\mathbf K}$ (zero in an unloaded state).
    JointGeometry,
}

impl std::fmt::Display for EnergyCarrier {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Body(name) | Self::Spring(name) => write!(f, "{name}"),
            Self::PointMass { index, name, node } if name.is_empty() => write!(f, "point mass {index} on node {node}"),
            Self::PointMass { name, node, .. } => write!(f, "point mass '{name}' on node {node}"),
            Self::Load { index, node } => write!(f, "load {index} on node {node}"),
            Self::JointSpring { joint, coordinate } => write!(f, "joint spring {joint}[{coordinate}]"),
            Self::JointGeometry => write!(f, "joint geometry"),
            Self::UserForce(name) => write!(f, "user force {name}"),
        }
    }
}

/// A mode's energies in one carrier (body or element): $\boldsymbol\phi_e^T\hat{\mathbf K}_e\boldsymbol\phi_e$,
/// $\boldsymbol\phi_e^T\hat{\mathbf M}_e\boldsymbol\phi_e$ and their shares of the totals.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CarrierEnergy {
    pub carrier: EnergyCarrier,
    /// $\boldsymbol\phi^T\hat{\mathbf K}_e\boldsymbol\phi$ (twice the strain energy at unit amplitude).
    pub strain: f64,
    /// $\boldsymbol\phi^T\hat{\mathbf M}_e\boldsymbol\phi$ (twice the kinetic energy at unit velocity amplitude).
    pub kinetic: f64,
    pub strain_share: f64,
    pub kinetic_share: f64,
    /// Part of `strain`, `kinetic` on a flexible body's modal coordinates (its interior, no node).
    pub interior_strain: f64,
    pub interior_kinetic: f64,
}

/// A mode's energies through one node's ports: $\sum_e \mathbf w_c^T\mathbf y_{e,c}$ (see [`mode_energies`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NodeEnergy {
    pub node: String,
    pub strain: f64,
    pub kinetic: f64,
    pub strain_share: f64,
    pub kinetic_share: f64,
}

/// One linearised mode: frequency, damping and where its energy is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModeEnergy {
    /// Real part of the eigenvalue $\omega^2$ of $\hat{\mathbf M}^{-1}\hat{\mathbf K}$.
    pub omega_squared: f64,
    /// $\sqrt{\max(\omega^2, 0)}$ \[rad/s\] and in Hz.
    pub omega: f64,
    pub frequency_hz: f64,
    /// Rigid-body (zero) mode: $|\omega^2| \le 10^{-9}\max(\max_i|\omega_i^2|,\ 1\ \mathrm{s^{-2}})$.
    pub rigid_body: bool,
    /// The state-space eigenvalue $s$ matched to this mode (nearest $|s|$ to $\omega$), and
    /// $\zeta = -\mathrm{Re}\,s/|s|$; `None` for rigid-body modes.
    pub damped_eigenvalue: Option<(f64, f64)>,
    pub damping_ratio: Option<f64>,
    /// The mode grows: $\omega^2$ is negative beyond the rigid-body bound (a divergence: the
    /// equilibrium is unstable, $\omega$ and the frequency are then 0) or its state-space
    /// eigenvalue has $\mathrm{Re}\,s > 0$ ([`LinearSpectrum::growing`]). The label then starts
    /// with "UNSTABLE".
    pub unstable: bool,
    /// Growth rate of an unstable mode \[1/s\]: $\sqrt{-\omega^2}$ for a divergence, else
    /// $\mathrm{Re}\,s$.
    pub growth_rate: Option<f64>,
    /// $\boldsymbol\phi$: real, mass-normalised ($\boldsymbol\phi^T\hat{\mathbf M}\boldsymbol\phi = 1$) when
    /// $\boldsymbol\phi^T\hat{\mathbf M}\boldsymbol\phi > 0$, sign such that its largest entry is positive.
    pub shape: Vec<f64>,
    /// $\boldsymbol\phi^T\hat{\mathbf K}\boldsymbol\phi$, $\boldsymbol\phi^T\hat{\mathbf M}\boldsymbol\phi$.
    pub strain: f64,
    pub kinetic: f64,
    /// Per carrier (elements with a non-zero share, joint springs, joint geometry).
    pub carriers: Vec<CarrierEnergy>,
    /// Per model node (all nodes, model order).
    pub nodes: Vec<NodeEnergy>,
    /// "rod (62 % kinetic), node B": the carrier and the node with the largest share of either
    /// energy (kinetic first on ties; kinetic only for rigid-body modes and modes with
    /// $\boldsymbol\phi^T\hat{\mathbf K}\boldsymbol\phi \le 0$, whose strain shares are ratios to
    /// about zero).
    pub label: String,
}

/// Every mode of the linearisation at `state` with its energy distribution, by ascending
/// $\omega^2$ (dense, as [`spectrum`]).
///
/// For mode $\boldsymbol\phi$, element $e$ (on its unknowns, [`System::matrices`]' element blocks)
/// carries $\boldsymbol\phi_e^T\hat{\mathbf K}_e\boldsymbol\phi_e$ and $\boldsymbol\phi_e^T\hat{\mathbf M}_e\boldsymbol\phi_e$;
/// joint springs $k\phi_s^2$; the joints' geometric term is what remains of
/// $\boldsymbol\phi^T\hat{\mathbf K}\boldsymbol\phi$, so the carriers' shares sum to 1.
///
/// # Derivation
/// Not in the AIC-FFR papers. With the port vector $\mathbf w = [\mathbf J_a\boldsymbol\phi;\ \dots;\ \boldsymbol\phi_\eta]$
/// (node velocities of the mode, then the body's modal amplitudes) and
/// $\mathbf y^K = \mathbf K_t\mathbf w + \mathbf C_t\,(\partial\mathbf V/\partial\mathbf q)\boldsymbol\phi +
/// \mathbf M\,(\partial\mathbf A/\partial\mathbf q)\boldsymbol\phi$, $\mathbf y^M = \mathbf M\mathbf w$ (the element
/// block of [`System::matrices`] applied to $\boldsymbol\phi$, before $\mathbf J^T$), the element's
/// $\boldsymbol\phi_e^T\hat{\mathbf K}_e\boldsymbol\phi_e = \sum_a\mathbf w_a^T\mathbf y^K_a + \mathbf w_\eta^T\mathbf y^K_\eta$
/// exactly, and likewise for $\hat{\mathbf M}_e$. Node $a$ is given $\sum_e\mathbf w_a^T\mathbf y_{e,a}$; the
/// modal rows go to the body's interior. Nodes, interiors, joint springs and joint geometry sum
/// to the totals.
/// A port's share is a split of a quadratic form and can be negative when ports move against
/// each other. Checked by `tests/unit/linearized.rs`.
pub fn mode_energies(system: &System, state: &State) -> Result<Vec<ModeEnergy>, SolveError> {
    let t = state.time();
    let mut s = state.clone();
    let mut ws = system.workspace();
    system.evaluate_into(&mut s, 1.0, true, &mut ws)?;
    let n = system.n_dof();
    if n == 0 {
        return Ok(Vec::new());
    }
    let m = Matrices {
        F: ws.F.clone(),
        M: system.dense(&ws.M, n),
        C: system.dense(&ws.C, n),
        K: system.dense(&ws.K, n),
    };
    let sc = Scaled::new(system, &m, At::Time(t))?;
    let (S, U) = sc.undamped_modes()?;
    let state_space = sc.state_space_eigenvalues(&S)?;
    let quad = |A: &Mat<f64>, x: &[f64]| -> f64 {
        (0..n)
            .map(|j| x[j] * (0..n).map(|i| x[i] * A[(i, j)]).sum::<f64>())
            .sum()
    };
    // Real mode shapes: a real eigenvalue gives u / (its largest entry). A repeated real
    // eigenvalue may come back as a complex pair a ± ib with b at round-off: its real invariant
    // subspace is span{Re u, Im u}, two modes, M-orthonormalised. A truly complex eigenvalue
    // (follower loads) keeps the real part of the normalised u, once per conjugate pair.
    let mut found: Vec<(f64, Vec<f64>)> = Vec::with_capacity(n);
    for i in 0..n {
        let (l, u) = (S[i], U.col(i));
        if l.im < 0.0 {
            continue;
        }
        let big = u.iter().fold(u[0], |b, &x| if x.norm() > b.norm() { x } else { b });
        let unit: Vec<_> = u.iter().map(|&x| x / big).collect();
        if l.im > 0.0 && l.im <= 1e-6 * l.norm() {
            let re: Vec<f64> = unit.iter().map(|x| x.re).collect();
            let im: Vec<f64> = unit.iter().map(|x| x.im).collect();
            for v in m_orthonormal(&m.M, [re, im]) {
                found.push((l.re, v));
            }
        } else {
            found.push((l.re, unit.iter().map(|x| x.re).collect()));
        }
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    let lambda_max = found.iter().map(|f| f.0.abs()).fold(0.0, f64::max);
    let bound = growth_bound(&state_space);
    let mut used = vec![false; state_space.len()];
    let mut modes = Vec::with_capacity(found.len());
    for (omega_squared, mut phi) in found {
        let mass = quad(&m.M, &phi);
        if mass > 0.0 {
            phi.iter_mut().for_each(|x| *x /= mass.sqrt());
        }
        let big = phi.iter().fold(0.0, |b: f64, &x| if x.abs() > b.abs() { x } else { b });
        if big < 0.0 {
            phi.iter_mut().for_each(|x| *x = -*x);
        }
        let rigid_body = omega_squared.abs() <= 1e-9 * lambda_max.max(1.0);
        let omega = omega_squared.max(0.0).sqrt();
        let (damped_eigenvalue, damping_ratio) = if rigid_body {
            (None, None)
        } else {
            // |s| = sqrt(|omega^2|): a divergence (omega^2 < 0) is matched to its real s > 0.
            let target = omega_squared.abs().sqrt();
            let best = (0..state_space.len()).filter(|&k| !used[k]).min_by(|&a, &b| {
                let d = |k: usize| (state_space[k].0.hypot(state_space[k].1) - target).abs();
                d(a).total_cmp(&d(b))
            });
            match best {
                Some(k) => {
                    used[k] = true;
                    let (re, im) = state_space[k];
                    (Some((re, im)), Some(-re / re.hypot(im)))
                }
                None => (None, None),
            }
        };
        let mut mode = distribute(system, &ws, &phi);
        mode.strain = quad(&m.K, &phi);
        mode.kinetic = quad(&m.M, &phi);
        mode.rigid_body = rigid_body;
        finish_shares(&mut mode);
        mode.omega_squared = omega_squared;
        mode.omega = omega;
        mode.frequency_hz = omega / (2.0 * std::f64::consts::PI);
        mode.damped_eigenvalue = damped_eigenvalue;
        mode.damping_ratio = damping_ratio;
        let growing = damped_eigenvalue.map_or(0.0, |s| s.0);
        mode.growth_rate = if !rigid_body && omega_squared < 0.0 {
            Some((-omega_squared).sqrt().max(growing))
        } else if growing > bound {
            Some(growing)
        } else {
            None
        };
        mode.unstable = mode.growth_rate.is_some();
        if let Some(rate) = mode.growth_rate {
            mode.label = format!(
                "UNSTABLE ({} at {rate:.4e} 1/s), {}",
                if omega_squared < 0.0 { "diverges" } else { "grows" },
                mode.label
            );
        }
        mode.shape = phi;
        modes.push(mode);
    }
    Ok(modes)
}

/// The element, joint-spring and node energies of mode `phi` from an evaluated workspace
/// (frequency fields left for the caller).
fn distribute(system: &System, ws: &Workspace, phi: &[f64]) -> ModeEnergy {
    let model = system.model();
    let map = &system.topo.map;
    let n = phi.len();
    let node_name = |a: usize| model.nodes[a].name.clone();
    let mut nodes: Vec<NodeEnergy> = model
        .nodes
        .iter()
        .map(|nd| NodeEnergy {
            node: nd.name.clone(),
            strain: 0.0,
            kinetic: 0.0,
            strain_share: 0.0,
            kinetic_share: 0.0,
        })
        .collect();
    // Per node: w = J phi, dV/dq phi, dA/dq phi (6-vectors).
    let node_vectors: Vec<[[f64; 6]; 3]> = (0..model.nodes.len())
        .map(|a| {
            let d = &ws.derivs[a];
            let mut v = [[0.0; 6]; 3];
            for (u, &k) in d.unknown.iter().enumerate() {
                let id = map.chains[a].cols[k];
                if id >= n {
                    continue;
                }
                let col = ws.motions[a].col(k);
                for r in 0..6 {
                    v[0][r] += col[r] * phi[id];
                    v[1][r] += d.DV[u][r] * phi[id];
                    v[2][r] += d.DA[u][r] * phi[id];
                }
            }
            v
        })
        .collect();
    let mut carriers = Vec::new();
    for (ei, (e, b)) in system.elements.iter().zip(&ws.elems).enumerate() {
        let dofs = &system.pattern.elem_dofs[ei];
        let s = dofs.len();
        let local = |A: &[f64]| -> f64 {
            (0..s)
                .map(|c| phi[dofs[c]] * (0..s).map(|r| phi[dofs[r]] * A[c * s + r]).sum::<f64>())
                .sum()
        };
        let (strain, kinetic) = (local(&b.local[2]), local(&b.local[0]));
        if strain == 0.0 && kinetic == 0.0 {
            continue;
        }
        // Port vectors: w (and dV, dA) of each port, then the modal amplitudes.
        let N = e.nodes.len();
        let rows = 6 * N + e.modal.len();
        let port = |which: usize| -> Vec<f64> {
            let mut x = vec![0.0; rows];
            for (ia, &a) in e.nodes.iter().enumerate() {
                x[6 * ia..6 * ia + 6].copy_from_slice(&node_vectors[a][which]);
            }
            if which == 0 {
                for (i, &d) in e.modal.iter().enumerate() {
                    x[6 * N + i] = phi[d];
                }
            }
            x
        };
        let (w, dv, da) = (port(0), port(1), port(2));
        let o = &b.out;
        let times = |A: &Mat<f64>, x: &[f64], r: usize| (0..rows).map(|c| A[(r, c)] * x[c]).sum::<f64>();
        let mut interior = (0.0, 0.0);
        for r in 0..rows {
            let yK = times(&o.K, &w, r) + times(&o.C, &dv, r) + times(&o.M, &da, r);
            let yM = times(&o.M, &w, r);
            let (pk, pm) = (w[r] * yK, w[r] * yM);
            if r < 6 * N {
                let a = e.nodes[r / 6];
                nodes[a].strain += pk;
                nodes[a].kinetic += pm;
            } else {
                interior.0 += pk;
                interior.1 += pm;
            }
        }
        let carrier = match &e.kind {
            ElementKind::Flexible(i) => EnergyCarrier::Body(model.bodies[system.flexible[*i].body].name().to_string()),
            ElementKind::Rigid(i) => EnergyCarrier::Body(rigid_name(system, *i)),
            ElementKind::PointMass(node, _) => {
                let index = point_mass_index(system, ei);
                EnergyCarrier::PointMass {
                    index,
                    name: model.point_masses.get(index).map_or(String::new(), |p| p.name.clone()),
                    node: node_name(*node),
                }
            }
            ElementKind::Spring(i) => EnergyCarrier::Spring(model.springs[*i].name.clone()),
            ElementKind::Load(i) => EnergyCarrier::Load {
                index: *i,
                node: node_name(system.loads[*i].node),
            },
            ElementKind::User(i) => EnergyCarrier::UserForce(system.user_forces[*i].name().to_string()),
        };
        carriers.push(CarrierEnergy {
            carrier,
            strain,
            kinetic,
            strain_share: 0.0,
            kinetic_share: 0.0,
            interior_strain: interior.0,
            interior_kinetic: interior.1,
        });
    }
    for (js, &(sc, k, ..)) in model.joint_springs.iter().zip(&system.joint_springs) {
        if let crate::assembly::coordinates::Slot::Unknown(d) = map.scalars[sc].slot {
            carriers.push(CarrierEnergy {
                carrier: EnergyCarrier::JointSpring {
                    joint: model.joints[js.joint.index()].name.clone(),
                    coordinate: js.coordinate,
                },
                strain: k * phi[d] * phi[d],
                kinetic: 0.0,
                strain_share: 0.0,
                kinetic_share: 0.0,
                interior_strain: 0.0,
                interior_kinetic: 0.0,
            });
        }
    }
    ModeEnergy {
        omega_squared: 0.0,
        omega: 0.0,
        frequency_hz: 0.0,
        rigid_body: false,
        damped_eigenvalue: None,
        damping_ratio: None,
        unstable: false,
        growth_rate: None,
        shape: Vec::new(),
        strain: 0.0,
        kinetic: 0.0,
        carriers,
        nodes,
        label: String::new(),
    }
}

/// Adds the joint-geometry remainder, the shares and the label, once `strain` and `kinetic`
/// hold the totals.
fn finish_shares(mode: &mut ModeEnergy) {
    let counted: f64 = mode.carriers.iter().map(|c| c.strain).sum();
    let geometric = mode.strain - counted;
    if geometric.abs() > 1e-10 * mode.strain.abs().max(counted.abs()) {
        mode.carriers.push(CarrierEnergy {
            carrier: EnergyCarrier::JointGeometry,
            strain: geometric,
            kinetic: 0.0,
            strain_share: 0.0,
            kinetic_share: 0.0,
            interior_strain: 0.0,
            interior_kinetic: 0.0,
        });
    }
    let share = |x: f64, total: f64| if total != 0.0 { x / total } else { 0.0 };
    let (ks, km) = (mode.strain, mode.kinetic);
    for c in &mut mode.carriers {
        c.strain_share = share(c.strain, ks);
        c.kinetic_share = share(c.kinetic, km);
    }
    for nd in &mut mode.nodes {
        nd.strain_share = share(nd.strain, ks);
        nd.kinetic_share = share(nd.kinetic, km);
    }
    // Largest share of either energy; on ties kinetic first, then the earlier entry. Strain
    // shares of a rigid-body mode or of a mode with phi^T K phi <= 0 are ratios to (nearly)
    // zero: such modes are labelled by their kinetic energy only.
    let use_strain = !mode.rigid_body && mode.strain > 0.0;
    let dominant = |k: f64, s: f64| {
        if k >= s || !use_strain {
            (k, "kinetic")
        } else {
            (s, "strain")
        }
    };
    let first_max = |shares: &mut dyn Iterator<Item = (f64, f64)>| {
        let mut best: Option<(usize, f64, &'static str)> = None;
        for (i, (k, s)) in shares.enumerate() {
            let (x, what) = dominant(k, s);
            if best.is_none_or(|b| x > b.1 || (x == b.1 && what == "kinetic" && b.2 == "strain")) {
                best = Some((i, x, what));
            }
        }
        best
    };
    let best_carrier = first_max(&mut mode.carriers.iter().map(|c| (c.kinetic_share, c.strain_share)))
        .map(|(i, x, what)| (&mode.carriers[i], (x, what)));
    let best_node =
        first_max(&mut mode.nodes.iter().map(|n| (n.kinetic_share, n.strain_share))).map(|b| &mode.nodes[b.0]);
    mode.label = match (best_carrier, best_node) {
        (Some((c, (x, what))), Some(nd)) => format!("{} ({:.0} % {what}), node {}", c.carrier, 100.0 * x, nd.node),
        (Some((c, (x, what))), None) => format!("{} ({:.0} % {what})", c.carrier, 100.0 * x),
        (None, _) => "no energy".into(),
    };
}

fn rigid_name(system: &System, i: usize) -> String {
    // Rigid elements are built in body order, skipping flexible bodies.
    system
        .model()
        .bodies
        .iter()
        .filter(|b| matches!(b, Body::Rigid(_)))
        .nth(i)
        .map_or_else(|| format!("rigid body {i}"), |b| b.name().to_string())
}

fn point_mass_index(system: &System, ei: usize) -> usize {
    system.elements[..ei]
        .iter()
        .filter(|e| matches!(e.kind, ElementKind::PointMass(..)))
        .count()
}

/// Two vectors made $\hat{\mathbf M}$-orthonormal by Gram-Schmidt (a vector with no component
/// left, relative $10^{-8}$, is dropped).
fn m_orthonormal(M: &Mat<f64>, vectors: [Vec<f64>; 2]) -> Vec<Vec<f64>> {
    let n = M.nrows();
    let inner = |x: &[f64], y: &[f64]| -> f64 {
        (0..n)
            .map(|j| y[j] * (0..n).map(|i| x[i] * M[(i, j)]).sum::<f64>())
            .sum()
    };
    let mut out: Vec<Vec<f64>> = Vec::new();
    for mut v in vectors {
        let before = inner(&v, &v).abs().sqrt();
        for q in &out {
            let c = inner(q, &v);
            v.iter_mut().zip(q).for_each(|(x, y)| *x -= c * y);
        }
        let norm = inner(&v, &v);
        if norm > 0.0 && norm.sqrt() > 1e-8 * before {
            v.iter_mut().for_each(|x| *x /= norm.sqrt());
            out.push(v);
        }
    }
    out
}
