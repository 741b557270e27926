//! Linearised analysis about a state (brief §6): $\hat{\mathbf M}$, $\hat{\mathbf C}$, $\hat{\mathbf K}$
//! of the assembled system ([`System::matrices`]) and the eigenvalues of
//! $\hat{\mathbf M}\delta\ddot{\mathbf q} + \hat{\mathbf C}\delta\dot{\mathbf q} + \hat{\mathbf K}\delta\mathbf q = \mathbf 0$.
//!
//! * Undamped frequencies: $\omega^2$ = the eigenvalues of $\hat{\mathbf M}^{-1}\hat{\mathbf K}$ (real
//!   parts; $\hat{\mathbf K}$ need not be symmetric: follower loads, gyroscopic states).
//! * Damped (state-space) eigenvalues $s$ of $\begin{bmatrix}\mathbf 0 & \mathbf I\\ -\hat{\mathbf M}^{-1}\hat{\mathbf K} &
//!   -\hat{\mathbf M}^{-1}\hat{\mathbf C}\end{bmatrix}$, whose imaginary parts are the damped frequencies.
//!
//! Dense: meant for models of up to a few hundred unknowns. About a static equilibrium the
//! result is the small-vibration spectrum, including the geometric stiffness of the preload
//! (a tensioned beam is stiffer). About a moving state in these inertial absolute coordinates
//! the linearised equations are time-varying in general (a spinning body's coordinates turn),
//! so the instantaneous spectrum is not the rotating-frame one: use it for states whose
//! coordinates are steady.
//!
//! [`buckling`]: linearised buckling loads about a static state (dense as well).

#![allow(non_snake_case)]

use crate::error::SolveError;
use crate::system::{Matrices, State, System};
use faer::linalg::solvers::Solve;
use faer::Mat;

/// Eigenvalues of the linearised system.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearSpectrum {
    /// Undamped circular frequencies [rad/s], ascending (only eigenvalues of
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
    let n = system.n_dof();
    let singular = |what: &str| SolveError::Singular {
        t: state.time(),
        step: 0,
        what: what.into(),
    };
    let lu = m.M.partial_piv_lu();
    let mut MK = m.K.clone();
    lu.solve_in_place(MK.as_mut());
    let mut MC = m.C.clone();
    lu.solve_in_place(MC.as_mut());
    if MK
        .col_iter()
        .chain(MC.col_iter())
        .any(|c| c.iter().any(|x| !x.is_finite()))
    {
        return Err(singular("mass matrix of the linearisation"));
    }
    let ev = MK
        .eigenvalues()
        .map_err(|_| singular("eigenvalues of M^-1 K did not converge"))?;
    let mut omega: Vec<f64> = ev.iter().filter(|l| l.re > 0.0).map(|l| l.re.sqrt()).collect();
    omega.sort_by(f64::total_cmp);
    let A = Mat::from_fn(2 * n, 2 * n, |i, j| match (i < n, j < n) {
        (true, true) => 0.0,
        (true, false) => f64::from(i == j - n),
        (false, true) => -MK[(i - n, j)],
        (false, false) => -MC[(i - n, j - n)],
    });
    let ev = A
        .eigenvalues()
        .map_err(|_| singular("state-space eigenvalues did not converge"))?;
    let mut state_space: Vec<(f64, f64)> = ev.iter().filter(|l| l.im >= 0.0).map(|l| (l.re, l.im)).collect();
    state_space.sort_by(|a, b| a.1.total_cmp(&b.1));
    Ok(LinearSpectrum { omega, state_space })
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
        t: lambda,
        step: 0,
        what: what.into(),
    };
    if !(lambda != 0.0 && lambda.is_finite()) {
        return Err(SolveError::InvalidSettings {
            what: format!("buckling needs the load factor of the loaded state, non-zero and finite (got {lambda})"),
        });
    }
    let K0 = system.matrices(&mut unloaded.clone(), 0.0)?.K;
    let Ks = system.matrices(&mut loaded.clone(), lambda)?.K;
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
