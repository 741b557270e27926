//! Streaming time integration: fixed generalized-α steps with a callback after each, so a
//! caller writes results as they are computed (and an interrupted run keeps them) without
//! writing the step loop again.

use crate::dynamic_solver::{Integrator, StepReport};
use crate::error::SolveError;

/// Newton work of the steps taken by [`Integrator::run_steps`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepTotals {
    /// Steps completed.
    pub steps: usize,
    /// Newton corrections of all steps.
    pub iterations: usize,
    /// Iteration matrices factorised (tangents evaluated).
    pub jacobians: usize,
    /// Most corrections in one step.
    pub max_iterations: usize,
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

    /// Takes `n_steps` steps, calling `each(k, self, report)` after step `k` (1-based). A
    /// solver failure stops the run and is returned with the totals of the converged steps
    /// (the state stays at the last of them); an error of the callback stops it and is
    /// returned as `Err`.
    pub fn run_steps<E>(
        &mut self,
        n_steps: usize,
        mut each: impl FnMut(usize, &Self, &StepReport) -> Result<(), E>,
    ) -> Result<(StepTotals, Option<SolveError>), E> {
        let mut totals = StepTotals::default();
        for k in 1..=n_steps {
            let report = match self.step() {
                Ok(r) => r,
                Err(e) => return Ok((totals, Some(e))),
            };
            let it = report.residuals.len().saturating_sub(1);
            totals.steps += 1;
            totals.iterations += it;
            totals.jacobians += report.jacobians;
            totals.max_iterations = totals.max_iterations.max(it);
            each(k, self, &report)?;
        }
        Ok((totals, None))
    }
}
