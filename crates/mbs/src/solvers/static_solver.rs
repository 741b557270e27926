//! Static equilibrium $\mathbf F(\mathbf q, \mathbf 0, \mathbf 0; \lambda) = \mathbf 0$ by Newton-Raphson on
//! the Lie group ($\mathbf q \leftarrow \mathbf q\oplus\Delta\mathbf q$, $\hat{\mathbf K}\Delta\mathbf q = -\mathbf F$) with adaptive
//! load stepping in the load factor $\lambda \in [0, 1]$, which scales every load and gravity.
//!
//! Each load step keeps its residual history $\|\mathbf F\|/f_{scale}$ per iteration, the
//! evidence that $\hat{\mathbf K}$ is the exact tangent (quadratic convergence near the solution).
//! A step that fails (no convergence in `max_iterations`, divergence, a singular tangent or a
//! floating frame that does not converge) is retried with half the increment. Each step starts
//! from the last converged state: a secant predictor was tried and cost more iterations on the
//! elastica (the first residual of a step is dominated by the axial strain that any linear
//! extrapolation of large rotations creates in stiff slender bodies).
//!
//! Load stepping cannot pass a limit point (it stops there with [`SolveError::NotConverged`],
//! or jumps to another branch): use [`crate::solve_arc_length`] ([`crate::StaticMethod::ArcLength`]).

#![allow(non_snake_case)]

use crate::assembly::system::sensors::SensorRecord;
use crate::assembly::system::System;
use crate::error::{At, Incomplete, SolveError};
use crate::state::State;

/// Settings of [`solve_static`].
#[derive(Clone, Debug, PartialEq)]
pub struct StaticSettings {
    /// Converged when $\|\mathbf F\| \le$ `tolerance` $\cdot f_{scale}$, $f_{scale}$ the sum of the
    /// norms of the generalised inertia, internal and external forces. $10^{-10}$ is six orders
    /// above the round-off of $\mathbf F$ in double precision for well-conditioned models and
    /// reached in one more quadratic iteration than $10^{-6}$.
    /// The test is $\|\mathbf F\| \le$ `tolerance` $\cdot f_{scale}$ + the round-off floor of the
    /// residual ([`System::residual_floor`]).
    pub tolerance: f64,
    pub max_iterations: usize,
    /// Largest Newton correction, in [`System::increment_norm`] (model size for lengths,
    /// radians for angles); longer ones are shortened. 1: a correction of more than a radian
    /// is outside the region where the linearisation of a rotation means anything (on the
    /// elastica it cut the iterations of the hardest load steps by a fifth; smaller limits
    /// gained nothing overall).
    pub max_correction: f64,
    /// First load increment $\Delta\lambda$.
    pub initial_increment: f64,
    /// Smallest increment before giving up.
    pub min_increment: f64,
    /// Largest increment.
    pub max_increment: f64,
    /// Time at which drivers and load functions are evaluated.
    pub time: f64,
}

impl StaticSettings {
    /// Default [`StaticSettings::tolerance`] (its docs say why).
    pub const DEFAULT_TOLERANCE: f64 = 1e-10;
    /// Default [`StaticSettings::max_iterations`].
    pub const DEFAULT_MAX_ITERATIONS: usize = 25;

    /// The whole load in `steps` equal increments (grown when Newton converges fast).
    pub fn new(steps: usize) -> Self {
        let d = 1.0 / steps.max(1) as f64;
        Self {
            tolerance: Self::DEFAULT_TOLERANCE,
            max_iterations: Self::DEFAULT_MAX_ITERATIONS,
            max_correction: 1.0,
            initial_increment: d,
            min_increment: 1e-6,
            max_increment: 1.0,
            time: 0.0,
        }
    }
}

/// One converged load step.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadStep {
    pub lambda: f64,
    /// Relative residual $\|\mathbf F\|/f_{scale}$ before each correction and at convergence.
    pub residuals: Vec<f64>,
    /// Size of each Newton correction, [`System::increment_norm`]. On slender bodies these show
    /// the quadratic convergence more clearly than the residuals, which jump while a large
    /// rotation correction strains the stiff axial direction.
    pub increments: Vec<f64>,
}

/// Result of [`solve_static`].
#[derive(Clone, Debug)]
pub struct StaticSolution {
    pub state: State,
    pub steps: Vec<LoadStep>,
    /// Sensors at each converged load step (time column = load factor).
    pub sensors: SensorRecord,
    /// Failed attempts (load factor tried, residual history) before each cut-back.
    pub rejected: Vec<LoadStep>,
}

impl StaticSolution {
    /// An empty solution at `state` with the system's sensor names (no rows yet).
    pub(crate) fn start(system: &System, state: &State) -> Self {
        Self {
            state: state.clone(),
            steps: Vec::new(),
            sensors: system.sensor_record(),
            rejected: Vec::new(),
        }
    }
}

/// The first entry of `x` (one per unknown) that is not finite, as [`SolveError::NonFinite`]
/// naming its coordinate ([`System::dof_labels`]): `what` is the quantity ("residual").
pub(crate) fn check_finite(system: &System, what: &str, x: &[f64], at: At) -> Result<(), SolveError> {
    match x.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(non_finite(system, what, i, x[i], at)),
    }
}

/// The first column of the dense `A` (unknowns by unknowns) with an entry that is not
/// finite, as [`SolveError::NonFinite`] naming the coordinate of that column (the unknown
/// whose motion the matrix cannot take).
pub(crate) fn check_finite_matrix(system: &System, what: &str, A: &faer::Mat<f64>, at: At) -> Result<(), SolveError> {
    for j in 0..A.ncols() {
        if let Some(i) = (0..A.nrows()).find(|&i| !A[(i, j)].is_finite()) {
            return Err(non_finite(system, what, j, A[(i, j)], at));
        }
    }
    Ok(())
}

/// [`check_finite_matrix`] of the tangent stiffness $\hat{\mathbf K}$ in `ws` (formed densely only
/// when an entry is not finite).
pub(crate) fn check_finite_tangent(
    system: &System,
    ws: &crate::assembly::system::Workspace,
    at: At,
) -> Result<(), SolveError> {
    if ws.K.iter().all(|x| x.is_finite()) {
        return Ok(());
    }
    check_finite_matrix(system, "tangent stiffness", &system.dense(&ws.K, system.n_dof()), at)
}

fn non_finite(system: &System, what: &str, index: usize, value: f64, at: At) -> SolveError {
    SolveError::NonFinite {
        what: what.into(),
        coordinate: system
            .dof_labels()
            .get(index)
            .cloned()
            .unwrap_or_else(|| format!("unknown {index}")),
        index,
        value,
        at,
        step: 0,
    }
}

/// Newton at a fixed load factor from `state`; returns the iteration history and whether it
/// converged. A residual or correction that is not finite is [`SolveError::NonFinite`].
pub(crate) fn newton_static(
    system: &System,
    state: &mut State,
    lambda: f64,
    settings: &StaticSettings,
    ws: &mut crate::assembly::system::Workspace,
) -> Result<(LoadStep, bool), SolveError> {
    let mut step = LoadStep {
        lambda,
        residuals: Vec::new(),
        increments: Vec::new(),
    };
    let n = system.n_dof();
    let mut dq = vec![0.0; n];
    for it in 0..=settings.max_iterations {
        // Forces alone after a correction; tangents only when another correction is needed.
        system.evaluate_into(state, lambda, it == 0, ws)?;
        let mut norm = ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
        if it > 0 && norm > settings.tolerance * ws.scale + ws.floor && norm.is_finite() {
            system.evaluate_into(state, lambda, true, ws)?;
            norm = ws.F.iter().map(|x| x * x).sum::<f64>().sqrt();
        }
        let rel = if ws.scale > 0.0 { norm / ws.scale } else { norm };
        step.residuals.push(rel);
        check_finite(system, "residual", &ws.F, At::LoadFactor(lambda))?;
        if norm <= settings.tolerance * ws.scale + ws.floor {
            return Ok((step, true));
        }
        // No early divergence test on the residual: on slender bodies it jumps to the order of
        // the internal forces while a large rotation correction strains the axial direction,
        // and comes back; the correction limit keeps such iterations bounded.
        if it == settings.max_iterations {
            return Ok((step, false));
        }
        check_finite_tangent(system, ws, At::LoadFactor(lambda))?;
        ws.S.copy_from_slice(&ws.K);
        for i in 0..n {
            dq[i] = -ws.F[i];
        }
        system.solve(ws, &mut dq).map_err(|what| SolveError::Singular {
            at: At::LoadFactor(lambda),
            step: 0,
            what: format!("tangent stiffness ({what})"),
        })?;
        let size = system.increment_norm(&dq);
        step.increments.push(size);
        // Shorten a correction larger than `max_correction` along its direction.
        if size > settings.max_correction {
            let f = settings.max_correction / size;
            dq.iter_mut().for_each(|d| *d *= f);
        }
        let base = state.clone();
        system.retract_in_place(state, &base, &dq);
    }
    Ok((step, false))
}

/// Records the sensors of the converged `state` (evaluated into `ws`) at load factor `lambda`,
/// load step `step`, in `rec` (time column = load factor). A value that is not finite stops
/// the analysis with [`SolveError::NonFiniteSensor`], as in a dynamic run
/// ([`crate::SensorRecord::check_last_row`]); the row stays in `rec` as evidence.
pub(crate) fn record(
    system: &System,
    state: &State,
    ws: &crate::assembly::system::Workspace,
    lambda: f64,
    step: usize,
    rec: &mut SensorRecord,
) -> Result<(), SolveError> {
    let checked = system.record(state, ws, rec).and_then(|()| {
        *rec.times.last_mut().expect("just recorded") = lambda;
        rec.check_last_row(step)
    });
    checked.map_err(|e| e.in_load_step(lambda, step))
}

/// Static equilibrium under the full load ($\lambda = 1$) from `start` (module docs).
pub fn solve_static(
    system: &System,
    start: State,
    settings: &StaticSettings,
) -> Result<StaticSolution, Box<Incomplete<StaticSolution>>> {
    let mut state = start;
    state.time = settings.time;
    let mut ws = system.workspace();
    let mut sol = StaticSolution::start(system, &state);
    let fail = |error: SolveError, sol: StaticSolution| Box::new(Incomplete { error, partial: sol });
    if !(settings.initial_increment > 0.0 && settings.min_increment > 0.0 && settings.tolerance > 0.0) {
        let what = "increments and tolerance must be positive".into();
        return Err(fail(SolveError::InvalidSettings { what }, sol));
    }
    let mut lambda = 0.0;
    let mut dl = settings.initial_increment.min(settings.max_increment);
    let mut step = 0;
    while lambda < 1.0 {
        let target = (lambda + dl).min(1.0);
        let saved = state.clone();
        match newton_static(system, &mut state, target, settings, &mut ws) {
            Ok((load_step, true)) => {
                step += 1;
                lambda = target;
                let iterations = load_step.residuals.len() - 1;
                sol.steps.push(load_step);
                if let Err(e) = record(system, &state, &ws, lambda, step, &mut sol.sensors) {
                    sol.state = state;
                    return Err(fail(e, sol));
                }
                // Large rotation steps of slender bodies take 5-6 iterations (the residual
                // alternates while the axial strain of a correction settles), so grow up to 6.
                if iterations <= 6 {
                    dl = (dl * 1.5).min(settings.max_increment);
                }
            }
            other => {
                let (attempt, error) = match other {
                    Ok((h, _)) => {
                        let residual = *h.residuals.last().unwrap_or(&f64::NAN);
                        let iterations = h.residuals.len().saturating_sub(1);
                        (
                            h,
                            SolveError::NotConverged {
                                at: At::LoadFactor(target),
                                step: step + 1,
                                residual,
                                iterations,
                            },
                        )
                    }
                    // A body, a user force or the tangent failed at this load factor: the
                    // error says so (the parts below the solver only know the time at which
                    // the loads are evaluated).
                    Err(e) => (
                        LoadStep {
                            lambda: target,
                            residuals: Vec::new(),
                            increments: Vec::new(),
                        },
                        e.in_load_step(target, step + 1),
                    ),
                };
                sol.rejected.push(attempt);
                state = saved;
                dl *= 0.5;
                if dl < settings.min_increment {
                    sol.state = state;
                    return Err(fail(error, sol));
                }
            }
        }
    }
    sol.state = state;
    Ok(sol)
}
