//! Fixed time steps that retry a failed step with halved steps.
//!
//! [`solve_dynamic_retrying`] integrates like [`crate::solve_dynamic`] with the step $h$; when
//! the Newton iteration of a step fails (no convergence, a singular iteration matrix, a body
//! whose floating frame cannot be solved), the state stays at $t_n$ and the interval
//! $[t_n, t_n + h]$ is covered by steps of $h/2$, each failing one halved again, down to
//! `min_step`. The run then goes on with $h$. Sensors are recorded on the grid of $h$ as
//! without retries. Every retried interval is reported ([`Retry`]): where, how small the steps
//! had to become and what failed first. A step that fails at `min_step` stops the run with
//! its error and everything computed before it.
//!
//! The generalized-α recursion holds for any sequence of step sizes (the algorithmic
//! acceleration is carried over), so the retried interval is integrated by the same scheme;
//! its local error is that of the smaller steps.
//!
//! A step that starts or ends in a joint limit's stop and is too long to resolve it is taken
//! back and retried the same way ([`crate::SolveError::LimitNotResolved`], the stops of
//! [`crate::assembly::joint_forces`]); a stop that no step down to `min_step` resolves is
//! refused before the first step ([`crate::SolveError::UnresolvableLimit`]).

use super::integrator::{fixed_steps, last_step_size, DynamicSettings, Integrator, StepReport};
use super::trajectory::{finished, start_trajectory, stopped, Trajectory};
use crate::assembly::system::sensors::PendingRows;
use crate::assembly::system::System;
use crate::error::{Incomplete, SolveError};
use crate::state::State;

/// One interval of the fixed step that needed smaller steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Retry {
    /// Start $t_n$ of the interval.
    pub time: f64,
    /// The step $h$ that failed.
    pub step: f64,
    /// The smallest step that was tried in it.
    pub smallest_step: f64,
    /// Steps taken to cover the interval.
    pub substeps: usize,
    /// Why the step of size $h$ failed.
    pub cause: SolveError,
}

/// What [`step_retrying`] took: the report of each step (one, or those of the halved steps)
/// and the retry, when one was needed.
#[derive(Clone, Debug, PartialEq)]
pub struct RetriedStep {
    pub reports: Vec<StepReport>,
    pub retry: Option<Retry>,
}

/// A step that failed even at the smallest step: the error and the retry that was attempted.
#[derive(Clone, Debug, PartialEq)]
pub struct RetryFailure {
    pub error: SolveError,
    pub retry: Option<Retry>,
}

/// A trajectory with the intervals that were retried.
#[derive(Clone, Debug)]
pub struct RetriedTrajectory {
    pub trajectory: Trajectory,
    pub retries: Vec<Retry>,
}

fn retriable(e: &SolveError) -> bool {
    matches!(
        e,
        SolveError::NotConverged { .. }
            | SolveError::Singular { .. }
            | SolveError::Body { .. }
            | SolveError::LimitNotResolved { .. }
    )
}

/// A step of the retry (`Integrator::step_resolving_stops`): taken back when it does not
/// resolve a joint limit's stop, unless it can no longer be halved above `min_step`.
fn retry_step(integ: &mut Integrator, min_step: f64) -> Result<StepReport, SolveError> {
    integ.step_resolving_stops(2.0 * min_step * (1.0 - 2e-12))
}

/// One step of the integrator's step size $h$; when its Newton iteration fails, the interval
/// $[t_n, t_n + h]$ is covered by halved steps down to `min_step` (module docs). The
/// integrator's step size is $h$ again afterwards; on failure its state is the last converged
/// one.
pub fn step_retrying(integ: &mut Integrator, min_step: f64) -> Result<RetriedStep, Box<RetryFailure>> {
    if let Err(error) = integ.check_stops(min_step) {
        return Err(Box::new(RetryFailure { error, retry: None }));
    }
    let h = integ.step_size();
    let cause = match retry_step(integ, min_step) {
        Ok(report) => {
            return Ok(RetriedStep {
                reports: vec![report],
                retry: None,
            })
        }
        Err(e) if retriable(&e) && 0.5 * h >= min_step * (1.0 - 1e-12) => e,
        Err(error) => return Err(Box::new(RetryFailure { error, retry: None })),
    };
    let end = integ.state().time() + h;
    let mut retry = Retry {
        time: integ.state().time(),
        step: h,
        smallest_step: h,
        substeps: 0,
        cause,
    };
    let mut reports = Vec::new();
    let mut sub = 0.5 * h;
    let result = loop {
        let left = end - integ.state().time();
        if left <= 1e-12 * h {
            break Ok(());
        }
        retry.smallest_step = retry.smallest_step.min(sub);
        integ.set_step_size(sub.min(left));
        match retry_step(integ, min_step) {
            Ok(rep) => {
                reports.push(rep);
                retry.substeps += 1;
            }
            Err(e) if retriable(&e) && 0.5 * sub >= min_step * (1.0 - 1e-12) => sub *= 0.5,
            Err(e) => break Err(e),
        }
    };
    integ.set_step_size(h);
    match result {
        Ok(()) => Ok(RetriedStep {
            reports,
            retry: Some(retry),
        }),
        Err(error) => Err(Box::new(RetryFailure {
            error,
            retry: Some(retry),
        })),
    }
}

/// Integrates from `start` to `settings.end_time` with the fixed step `settings.step`,
/// retrying failed steps with halved steps down to `min_step` (module docs).
pub fn solve_dynamic_retrying(
    system: &System,
    start: State,
    settings: &DynamicSettings,
    min_step: f64,
) -> Result<RetriedTrajectory, Box<Incomplete<RetriedTrajectory>>> {
    let h = settings.step;
    let fail = |error: SolveError, trajectory: Trajectory, retries: Vec<Retry>| {
        Box::new(Incomplete {
            error,
            partial: RetriedTrajectory { trajectory, retries },
        })
    };
    if !(min_step > 0.0 && min_step <= h) {
        let error = SolveError::InvalidSettings {
            what: format!("the smallest retried step must be positive and at most the step {h} (got {min_step})"),
        };
        let trajectory = Trajectory {
            sensors: system.sensor_record(),
            iterations: Vec::new(),
            jacobians: Vec::new(),
            final_state: start,
        };
        return Err(fail(error, trajectory, Vec::new()));
    }
    let (mut integ, mut traj) = match start_trajectory(system, start, settings) {
        Ok(x) => x,
        Err(inc) => return Err(fail(inc.error, inc.partial, Vec::new())),
    };
    let (n_steps, _) = fixed_steps(integ.state().time(), settings.end_time, h);
    let every = settings.output_every.max(1);
    let mut retries = Vec::new();
    let mut pending = PendingRows::default();
    for k in 1..=n_steps {
        if k == n_steps {
            // Land on the end time: the last step may be shorter.
            integ.set_step_size(last_step_size(integ.state().time(), settings.end_time, h));
        }
        match step_retrying(&mut integ, min_step) {
            Ok(done) => {
                for rep in &done.reports {
                    traj.iterations.push(rep.residuals.len() - 1);
                    traj.jacobians.push(rep.jacobians);
                }
                retries.extend(done.retry);
            }
            Err(failure) => {
                retries.extend(failure.retry);
                let stopped = *stopped(&integ, failure.error, &mut pending, traj);
                return Err(fail(stopped.error, stopped.partial, retries));
            }
        }
        if k % every == 0 || k == n_steps {
            if let Err(e) = integ.record_deferred(&mut pending, &mut traj.sensors) {
                let stopped = *stopped(&integ, e, &mut pending, traj);
                return Err(fail(stopped.error, stopped.partial, retries));
            }
        }
    }
    match finished(&integ, &mut pending, traj) {
        Ok(trajectory) => Ok(RetriedTrajectory { trajectory, retries }),
        Err(stopped) => {
            let stopped = *stopped;
            Err(fail(stopped.error, stopped.partial, retries))
        }
    }
}
