//! Streaming time integration: generalized-α steps with a callback after each, so a caller
//! writes results as they are computed (and an interrupted run keeps them) without writing the
//! step loop again. The steps are fixed (a failed one retried with halved steps,
//! [`crate::step_retrying`]) or adaptive ([`crate::step_adaptive_to`]), both landing on the
//! end time.

use super::integrator::{fixed_steps, last_step_size, step_adaptive_to, AdaptiveSettings, Integrator, StepReport};
use super::retry::{step_retrying, Retry, RetryFailure};
use crate::error::SolveError;

/// How [`Integrator::run_to`] steps.
#[derive(Clone, Debug, PartialEq)]
pub enum Stepping {
    /// Steps of the integrator's step size $h$, as many as [`Integrator::steps_to`] the end
    /// time, the last one shortened to land on it ([`crate::fixed_steps`]); a step whose Newton iteration fails is retried with halved steps down to
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
    /// No step taken yet, `planned` fixed steps to go (`None`: adaptive steps).
    pub fn new(planned: Option<usize>) -> Self {
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

/// A run of [`Integrator::run_to`] stopped by its callback: the callback's error and the
/// totals of the steps taken (the last of them included).
#[derive(Clone, Debug, PartialEq)]
pub struct Interrupted<E> {
    pub error: E,
    pub totals: StepTotals,
}

/// What one step of [`Integrator::step_under`] took: the report of each step (one, or those of
/// the halved steps of a retried fixed step), the retry, and the adaptive attempts rejected.
#[derive(Clone, Debug, PartialEq)]
pub struct Taken {
    pub reports: Vec<StepReport>,
    pub retry: Option<Retry>,
    pub rejected: usize,
}

impl StepTotals {
    /// Counts a step `taken` of size `h`: its Newton work, its retry and its size.
    pub fn count(&mut self, taken: Taken, h: f64) {
        self.retries.extend(taken.retry);
        self.rejected += taken.rejected;
        taken.reports.iter().for_each(|rep| self.add(rep));
        self.steps += 1;
        self.smallest_step = self.smallest_step.min(h);
        self.largest_step = self.largest_step.max(h);
    }
}

impl Integrator<'_> {
    /// One step as `stepping` says, of the step size set ([`Integrator::set_step_size`]): a
    /// fixed step whose Newton iteration fails is retried with halved steps
    /// ([`crate::step_retrying`]); an adaptive step is under local error control and lands on
    /// `end_time` ([`crate::step_adaptive_to`]; past `end_time`, the step size set is taken
    /// as a fixed step). On failure the state stays at the last converged step.
    pub fn step_under(&mut self, stepping: &Stepping, end_time: f64) -> Result<Taken, Box<RetryFailure>> {
        match stepping {
            Stepping::Fixed { min_step } => step_retrying(self, *min_step).map(|r| Taken {
                reports: r.reports,
                retry: r.retry,
                rejected: 0,
            }),
            Stepping::Adaptive(ad) if self.state().time() < end_time => match step_adaptive_to(self, end_time, ad) {
                Ok(s) => Ok(Taken {
                    reports: vec![s.report],
                    retry: None,
                    rejected: s.rejected,
                }),
                Err(error) => Err(Box::new(RetryFailure { error, retry: None })),
            },
            Stepping::Adaptive(ad) => self.step_under(&Stepping::Fixed { min_step: ad.min_step }, end_time),
        }
    }
}

impl Integrator<'_> {
    /// The number of fixed steps from the current time to `end_time` ([`crate::fixed_steps`]):
    /// steps of $h$, the last one shortened to end exactly at `end_time`.
    pub fn steps_to(&self, end_time: f64) -> usize {
        fixed_steps(self.state().time(), end_time, self.step_size()).0
    }

    /// Steps from the current time to `end_time` as `stepping` says, calling
    /// `each(done, self)` after every step. A solver failure stops the run and is returned with
    /// the totals of the converged steps (the state stays at the last of them); an error of
    /// the callback stops it and is returned as `Err` with the totals of the steps taken.
    pub fn run_to<E>(
        &mut self,
        end_time: f64,
        stepping: &Stepping,
        mut each: impl FnMut(&StepDone, &Self) -> Result<(), E>,
    ) -> Result<(StepTotals, Option<SolveError>), Box<Interrupted<E>>> {
        let start = self.state().time();
        let h = self.step_size();
        // Fixed steps: the last one is shortened to land on the end time (fixed_steps).
        let planned = match stepping {
            Stepping::Fixed { .. } => Some(fixed_steps(start, end_time, h).0),
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
            let shortened = planned == Some(totals.steps + 1);
            if shortened {
                self.set_step_size(last_step_size(t_before, end_time, h));
            }
            let taken = self.step_under(stepping, end_time);
            if shortened {
                // The step size stays h for a run continued from here.
                self.set_step_size(h);
            }
            let t = self.state().time();
            match taken {
                Ok(taken) => totals.count(taken, t - t_before),
                Err(f) => {
                    totals.retries.extend(f.retry);
                    return Ok((totals, Some(f.error)));
                }
            }
            let last = match planned {
                Some(n) => totals.steps == n,
                None => at_end(t),
            };
            let done = StepDone {
                k: totals.steps,
                last,
                planned,
                time: t,
                start,
            };
            if let Err(error) = each(&done, self) {
                return Err(Box::new(Interrupted { error, totals }));
            }
        }
    }
}
