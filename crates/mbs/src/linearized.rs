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
