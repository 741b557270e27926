//! The `dynamic` analysis: the generalized-α time integration of the mechanism, stepped as a
//! [`Simulation`], its sensors written a batch of rows at a time and its meshes at the output
//! times ([`DynamicOutput`]).

use super::dynamic_output::{add_start_section, DynamicOutput, Halt};
use super::outcome::Outcome;
use super::simulation::{dynamic_start, Simulation};
use crate::build::BuiltMechanism;
use crate::error::BoxError;
use crate::input::validate::mechanism::MbsAnalysis;
use crate::input::validate::Study;
use crate::output::observer::{Observer, Progress};
use mbs::System;
use std::sync::Arc;
use std::time::Instant;

/// Runs the `dynamic` analysis `analysis` on the system `sys` of `b` from `start` (module
/// docs), into `out`.
pub fn dynamic(
    study: &Study,
    sys: &Arc<System>,
    b: &BuiltMechanism,
    analysis: &MbsAnalysis,
    start: Option<&mbs::State>,
    obs: &mut dyn Observer,
    out: &mut Outcome,
) -> Result<(), BoxError> {
    let MbsAnalysis::Dynamic { t_end, .. } = analysis else {
        return Err("internal error: not a dynamic analysis".into());
    };
    let t0 = Instant::now();
    let first = dynamic_start(sys, start, study.mechanism.start);
    let t_start = first.time();
    if *t_end <= t_start {
        return Err(format!(
            "t_end = {t_end} s is not after the start at t = {t_start} s (the state of the analysis named in `start`)"
        )
        .into());
    }
    let mut integ = Simulation::with_start(study, Arc::clone(sys), b, analysis, first)?;
    let mut output = DynamicOutput::start(study, b, integ.integrator(), obs, t0)?;
    let run = integ.run_to(|done, integ| -> Result<(), Halt> {
        output.after_step(done, integ, b, obs)?;
        obs.progress(&progress(done, *t_end));
        Ok(())
    });
    let (totals, failure) = output.end_rows(study, b, integ.integrator(), run, obs)?;
    out.failure = failure;
    obs.progress(&Progress::Finished);
    output.finish(analysis, b, integ.integrator(), &totals, obs, out)?;
    if start.is_none() {
        add_start_section(study, sys, out);
    }
    Ok(())
}

/// The progress after step `done` of a run to `t_end`: steps of the planned, or the share of
/// the time span (adaptive steps).
fn progress(done: &mbs::StepDone, t_end: f64) -> Progress {
    let (k, total) = match done.planned {
        Some(n) => (done.k as u64, n as u64),
        None => ((1000.0 * (done.time - done.start) / (t_end - done.start)) as u64, 1000),
    };
    Progress::Steps {
        what: "time integration".into(),
        done: k,
        total,
    }
}
