//! Static equilibrium $\mathbf F(\mathbf q, \mathbf 0, \mathbf 0; \lambda) = \mathbf 0$ by Newton-Raphson on
//! the Lie group ($\mathbf q \leftarrow \mathbf q\oplus\Delta\mathbf q$, $\hat{\mathbf K}\Delta\mathbf q = -\mathbf F$) with adaptive
//! load stepping in the load factor $\lambda \in [0, 1]$, which scales every load and gravity.
//!
//! Each load step keeps its residual history $\|\mathbf F\|/f_{scale}$ per iteration, the
//! evidence that $\hat{\mathbf K}$ is the exact tangent (quadratic convergence near the solution).
//! A step that fails (no convergence in `max_iterations`, divergence, a singular tangent or a
//! floating frame that does not converge) is retried with half the increment. Each step starts
//! from the secant predictor $\mathbf q_n\oplus\frac{\Delta\lambda_{n+1}}{\Delta\lambda_n}(\mathbf q_n\ominus\mathbf q_{n-1})$.
//!
//! Arc-length continuation (Riks/Crisfield) is not implemented: limit points stop the
//! analysis with [`SolveError::NotConverged`].

#![allow(non_snake_case)]

use crate::error::{Incomplete, SolveError};
use crate::sensors::SensorRecord;
use crate::system::{State, System};

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
    /// The whole load in `steps` equal increments (grown when Newton converges fast).
    pub fn new(steps: usize) -> Self {
        let d = 1.0 / steps.max(1) as f64;
        Self {
            tolerance: 1e-10,
            max_iterations: 25,
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
    /// Relative residual before each correction and at convergence.
    pub residuals: Vec<f64>,
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

/// Newton at a fixed load factor from `state`; returns the residual history and whether it
/// converged.
pub(crate) fn newton_static(
    system: &System,
    state: &mut State,
    lambda: f64,
    settings: &StaticSettings,
    ws: &mut crate::system::Workspace,
) -> Result<(Vec<f64>, bool), SolveError> {
    let mut history = Vec::new();
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
        history.push(rel);
        if !rel.is_finite() {
            return Ok((history, false));
        }
        if norm <= settings.tolerance * ws.scale + ws.floor {
            return Ok((history, true));
        }
        if it == settings.max_iterations || (it > 3 && rel > 1e3 * history[0]) {
            return Ok((history, false));
        }
        ws.S.copy_from_slice(&ws.K);
        for i in 0..n {
            dq[i] = -ws.F[i];
        }
        system.solve(&ws.S, &mut dq).map_err(|what| SolveError::Singular {
            t: lambda,
            step: 0,
            what: format!("tangent stiffness ({what})"),
        })?;
        let base = state.clone();
        system.retract_in_place(state, &base, &dq);
    }
    Ok((history, false))
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
    let mut sol = StaticSolution {
        state: state.clone(),
        steps: Vec::new(),
        sensors: system.sensor_record(),
        rejected: Vec::new(),
    };
    let fail = |error: SolveError, sol: StaticSolution| Box::new(Incomplete { error, partial: sol });
    if !(settings.initial_increment > 0.0 && settings.min_increment > 0.0 && settings.tolerance > 0.0) {
        return Err(fail(
            SolveError::InvalidSettings {
                what: "increments and tolerance must be positive".into(),
            },
            sol,
        ));
    }
    let mut lambda = 0.0;
    let mut dl = settings.initial_increment.min(settings.max_increment);
    let mut step = 0;
    // The last converged step (state, load factor) for the secant predictor.
    let mut previous: Option<(State, f64)> = None;
    while lambda < 1.0 {
        let target = (lambda + dl).min(1.0);
        let saved = state.clone();
        // Secant predictor: continue the last step's motion in proportion to the new increment.
        if let Some((prev, l_prev)) = &previous {
            let ratio = (target - lambda) / (lambda - l_prev);
            let dq: Vec<f64> = system.difference(&saved, prev).iter().map(|d| d * ratio).collect();
            system.retract_in_place(&mut state, &saved, &dq);
        }
        let outcome = newton_static(system, &mut state, target, settings, &mut ws);
        match outcome {
            Ok((history, true)) => {
                step += 1;
                previous = Some((saved, lambda));
                lambda = target;
                let iterations = history.len() - 1;
                sol.steps.push(LoadStep {
                    lambda,
                    residuals: history,
                });
                if let Err(e) = system.record(&state, &ws, &mut sol.sensors) {
                    sol.state = state;
                    return Err(fail(e, sol));
                }
                // The record's time column holds the load factor.
                *sol.sensors.times.last_mut().expect("just recorded") = lambda;
                if iterations <= 4 {
                    dl = (dl * 1.5).min(settings.max_increment);
                }
            }
            other => {
                let (history, error) = match other {
                    Ok((h, _)) => {
                        let r = *h.last().unwrap_or(&f64::NAN);
                        let it = h.len().saturating_sub(1);
                        (
                            h,
                            SolveError::NotConverged {
                                t: target,
                                step: step + 1,
                                residual: r,
                                iterations: it,
                            },
                        )
                    }
                    Err(e) => (Vec::new(), e),
                };
                sol.rejected.push(LoadStep {
                    lambda: target,
                    residuals: history,
                });
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
