//! Streaming time integration: generalized-α steps with a callback after each, so a caller
//! writes results as they are computed (and an interrupted run keeps them) without writing the
//! step loop again. The steps are fixed (a failed one retried with halved steps,
//! [`crate::step_retrying`]) or adaptive ([`crate::step_adaptive_to`]), both landing on the
//! end time.

use crate::dynamic_solver::{AdaptiveSettings, Integrator, StepReport};
use crate::error::SolveError;
use crate::retry::{step_adaptive_to, step_retrying, Retry};

/// How [`Integrator::run_to`] steps.
#[derive(Clone, Debug, PartialEq)]
pub enum Stepping {
    /// Steps of the integrator's step size $h$, as many as [`Integrator::steps_to`] the end
    /// time; a step whose Newton iteration fails is retried with halved steps down to
    /// `min_step` (`min_step` $= h$: no retry).
    Fixed { min_step: f64 },
    /// Steps under the local error control of the settings, the last one landing on the end
    /// time.
    Adaptive(AdaptiveSettings),
}

/// What the callback of [`Integrator::run_to`] is told after a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepDone {
    /// The step just completed, 1-based (a fixed step retried with halved steps counts once).
    pub k: usize,
    /// Whether it reached the end time.
    pub last: bool,
    /// The steps planned (fixed steps), `None` for adaptive steps.
    pub planned: Option<usize>,
    /// Time $t_{n+1}$ reached \[s\].
    pub time: f64,
    /// Time at the start of the run \[s\] (for progress of adaptive runs).
    pub start: f64,
}

/// Newton work and step sizes of the steps taken by [`Integrator::run_to`].
#[derive(Clone, Debug, PartialEq)]
pub struct StepTotals {
    /// Steps completed.
    pub steps: usize,
    /// Steps planned (fixed steps), `None` for adaptive steps.
    pub planned: Option<usize>,
    /// Newton corrections of all steps (and substeps).
    pub iterations: usize,
    /// Iteration matrices factorised (tangents evaluated).
    pub jacobians: usize,
    /// Most corrections in one step.
    pub max_iterations: usize,
    /// Fixed steps that failed and were covered by halved steps.
    pub retries: Vec<Retry>,
    /// Adaptive attempts rejected (error too large or Newton failed).
    pub rejected: usize,
    /// Smallest and largest step taken \[s\] (`INFINITY` and 0 before any step).
    pub smallest_step: f64,
    pub largest_step: f64,
}

impl StepTotals {
    fn new(planned: Option<usize>) -> Self {
        Self {
            steps: 0,
            planned,
            iterations: 0,
            jacobians: 0,
            max_iterations: 0,
            retries: Vec::new(),
            rejected: 0,
            smallest_step: f64::INFINITY,
            largest_step: 0.0,
        }
    }

    fn add(&mut self, report: &StepReport) {
        let it = report.residuals.len().saturating_sub(1);
        self.iterations += it;
        self.jacobians += report.jacobians;
        self.max_iterations = self.max_iterations.max(it);
    }
}

impl Integrator<'_> {
    /// The number of fixed steps from the current time to `end_time`: the last step ends at or
    /// just past `end_time` (a remainder below $10^{-9}$ steps is round-off of `end_time / h`,
    /// not a step).
    pub fn steps_to(&self, end_time: f64) -> usize {
        ((end_time - self.state().time()) / self.step_size() - 1e-9)
            .ceil()
            .max(0.0) as usize
    }

    /// Steps from the current time to `end_time` as `stepping` says, calling
    /// `each(done, self)` after every step. A solver failure stops the run and is returned with
    /// the totals of the converged steps (the state stays at the last of them); an error of
    /// the callback stops it and is returned as `Err`.
    pub fn run_to<E>(
        &mut self,
        end_time: f64,
        stepping: &Stepping,
        mut each: impl FnMut(&StepDone, &Self) -> Result<(), E>,
    ) -> Result<(StepTotals, Option<SolveError>), E> {
        let start = self.state().time();
        let planned = match stepping {
            Stepping::Fixed { .. } => Some(self.steps_to(end_time)),
            Stepping::Adaptive(_) => None,
        };
        // An adaptive run ends when the time is on the end time to round-off.
        let at_end = |t: f64| end_time - t <= 1e-12 * end_time.abs().max(1.0);
        let mut totals = StepTotals::new(planned);
        loop {
            let done = match planned {
                Some(n) => totals.steps >= n,
                None => at_end(self.state().time()),
            };
            if done {
                return Ok((totals, None));
            }
            let t_before = self.state().time();
            let taken = match stepping {
                Stepping::Fixed { min_step } => match step_retrying(self, *min_step) {
                    Ok(r) => {
                        totals.retries.extend(r.retry);
                        r.reports.iter().for_each(|rep| totals.add(rep));
                        None
                    }
                    Err(f) => {
                        totals.retries.extend(f.retry);
                        Some(f.error)
                    }
                },
                Stepping::Adaptive(ad) => match step_adaptive_to(self, end_time, ad) {
                    Ok(s) => {
                        totals.rejected += s.rejected;
                        totals.add(&s.report);
                        None
                    }
                    Err(e) => Some(e),
                },
            };
            if let Some(e) = taken {
                return Ok((totals, Some(e)));
            }
            totals.steps += 1;
            let t = self.state().time();
            totals.smallest_step = totals.smallest_step.min(t - t_before);
            totals.largest_step = totals.largest_step.max(t - t_before);
            let last = match planned {
                Some(n) => totals.steps == n,
                None => at_end(t),
            };
            each(
                &StepDone {
                    k: totals.steps,
                    last,
                    planned,
                    time: t,
                    start,
                },
                self,
            )?;
        }
    }
}
