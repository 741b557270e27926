//! The results of a `dynamic` analysis as it is stepped: sensor rows a batch at a time and
//! meshes at the output times, to an observer, and the report and results of the steps taken.
//! A run writes them ([`super::dynamic`]), and so does a simulation stepped by its caller that
//! keeps a results folder ([`super::Simulation::writing_results`]).

use super::mesh::MeshRecovery;
use super::outcome::Outcome;
use super::sensors::{report_last, SensorSampler};
use crate::build::BuiltMechanism;
use crate::error::{BoxError, SolverStopped};
use crate::input::validate::mechanism::MbsAnalysis;
use crate::input::validate::Study;
use crate::output::observer::Observer;
use mbs::{Integrator, System};
use serde_json::json;
use std::time::Instant;

/// Why the output stopped a run: a sensor that is not finite (`mbs::SolveError::NonFiniteSensor`,
/// a solver stop) or a file that cannot be written.
pub enum Halt {
    Sensor(mbs::SolveError, usize),
    Output(BoxError),
}

impl<E: Into<BoxError>> From<E> for Halt {
    fn from(e: E) -> Self {
        Halt::Output(e.into())
    }
}

/// A time integration stopped by its output: a stop asked for (Ctrl-C, SIGTERM) or a file
/// that cannot be written. Says where it stopped and up to where the rows went out.
#[derive(Debug, thiserror::Error)]
#[error("time integration stopped at t = {time:.6} s (step {step}); sensor rows up to t = {written:.6} s were sent to the results")]
pub struct OutputStopped {
    /// The time reached, and the time of the last sensor row handed to the output.
    pub time: f64,
    pub step: usize,
    pub written: f64,
    #[source]
    pub source: BoxError,
}

/// The sensor rows on their way to the observer.
struct Rows {
    /// Rows whose largest-von-Mises values are found a batch at a time (the rows reach the
    /// files in order, a batch at a time, at most `PendingRows::WAIT` late).
    pending: mbs::PendingRows,
    rec: mbs::SensorRecord,
    files: SensorSampler,
    /// The time of the last row written.
    last_written: f64,
}

impl Rows {
    /// Completes the waiting rows (all of them with `flush`) and writes every row the record
    /// gained; a sensor that is not finite: the rows before it are written, the run is not
    /// complete. Only the last row is kept, to keep the record small. `record`: the
    /// integrator whose current state is recorded first (else the waiting rows are completed
    /// alone).
    fn write(
        &mut self,
        sys: &System,
        record: Option<&mbs::Integrator>,
        obs: &mut dyn Observer,
        k: usize,
    ) -> Result<(), Halt> {
        let rec = &mut self.rec;
        let before = rec.rows.len();
        let recorded = match record {
            Some(integ) => integ.record_deferred(&mut self.pending, rec),
            None => sys.complete_rows(&mut self.pending, rec),
        };
        let good = if recorded.is_err() {
            rec.rows.len().saturating_sub(1).max(before)
        } else {
            rec.rows.len()
        };
        self.files.sample_rows(obs, rec, before..good)?;
        if good > before {
            self.last_written = rec.times[good - 1];
        }
        recorded.map_err(|e| {
            let step = match &e {
                mbs::SolveError::NonFiniteSensor { step, .. } => *step,
                _ => k,
            };
            Halt::Sensor(e, step)
        })?;
        if rec.rows.len() > 1 {
            rec.rows.drain(..rec.rows.len() - 1);
            rec.times.drain(..rec.times.len() - 1);
        }
        Ok(())
    }
}

/// The results of a `dynamic` analysis as it is stepped, to an observer: the sensor rows and
/// the meshes at the output times. A run writes them step by step ([`super::dynamic::dynamic`]), and so does
/// a simulation stepped by its caller that keeps a results folder ([`super::Simulation::writing_results`]).
pub struct DynamicOutput {
    rows: Rows,
    mw: MeshRecovery,
    every: usize,
    vtu_every: Option<usize>,
    t_start: f64,
    /// When the analysis began, for the time spent solving.
    t0: Instant,
}

impl DynamicOutput {
    /// Starts the output of `integ` at its current state to `obs`: the sensor files with their
    /// first row and the first meshes. `t0`: when the analysis began.
    pub fn start(
        study: &Study,
        b: &BuiltMechanism,
        integ: &Integrator,
        obs: &mut dyn Observer,
        t0: Instant,
    ) -> Result<Self, BoxError> {
        let output = &study.mechanism.output;
        let sys = integ.system();
        let t_start = integ.state().time();
        let mut rec = sys.sensor_record();
        integ.record(&mut rec)?;
        let mut files = SensorSampler::start(obs, &b.groups, &rec, "t [s]", output.plots)?;
        files.sample(obs, t_start, &rec)?;
        let mut mw = MeshRecovery::new(b, sys)?;
        if output.vtu_every.is_some() {
            mw.write(obs, t_start, sys, integ.state(), b)?;
        }
        let rows = Rows {
            pending: mbs::PendingRows::default(),
            rec,
            files,
            last_written: t_start,
        };
        Ok(Self {
            rows,
            mw,
            every: output.every,
            vtu_every: output.vtu_every,
            t_start,
            t0,
        })
    }

    /// Writes what step `done` of `integ` gives at the output times: its sensor row every
    /// `[output] every` steps and at the last, its meshes every `vtu_every` steps.
    pub fn after_step(
        &mut self,
        done: &mbs::StepDone,
        integ: &mbs::Integrator,
        b: &BuiltMechanism,
        obs: &mut dyn Observer,
    ) -> Result<(), Halt> {
        let (k, t, sys) = (done.k, done.time, integ.system());
        let vtu_now = self.vtu_every.is_some_and(|v| k % v == 0 || done.last);
        if crate::interrupt::requested() && !self.rows.pending.is_empty() {
            // A stop asked for: the waiting rows are written first.
            self.rows.write(sys, None, obs, k)?;
        }
        if k % self.every == 0 || done.last {
            self.rows.write(sys, Some(integ), obs, k)?;
            if !vtu_now {
                self.mw.track(t, sys, integ.state(), b)?;
            }
        }
        if vtu_now {
            self.mw.write(obs, t, sys, integ.state(), b)?;
        }
        Ok(())
    }

    /// Ends the stepping `run` of `integ` (the totals of its steps and the solver failure, or
    /// the output's own stop): writes the rows still waiting and turns a failure into the
    /// stop the summary reports, with what was written.
    pub fn end_rows(
        &mut self,
        study: &Study,
        b: &BuiltMechanism,
        integ: &Integrator,
        run: Result<(mbs::StepTotals, Option<mbs::SolveError>), Box<mbs::Interrupted<Halt>>>,
        obs: &mut dyn Observer,
    ) -> Result<(mbs::StepTotals, Option<SolverStopped>), BoxError> {
        // The rows still waiting: a run that ended or failed writes them; a stop asked for
        // wrote them (after_step); a file that cannot be written stops here.
        let run = match run {
            Ok((totals, failure)) => match self.rows.write(integ.system(), None, obs, totals.steps) {
                Ok(()) => Ok((totals, failure)),
                // The solver's own failure stays the run's.
                Err(_) if failure.is_some() => Ok((totals, failure)),
                Err(error) => Err(Box::new(mbs::Interrupted { error, totals })),
            },
            Err(stop) => {
                let unwritable = matches!(&stop.error, Halt::Output(e) if !e.is::<crate::interrupt::Interrupted>());
                if !unwritable {
                    let _ = self.rows.write(integ.system(), None, obs, stop.totals.steps);
                }
                Err(stop)
            }
        };
        Ok(match run {
            Ok((totals, None)) => (totals, None),
            Ok((totals, Some(e))) => {
                let message = format!(
                    "time integration stopped; results up to t = {:.6} s (step {}) are written",
                    integ.state().time(),
                    totals.steps
                );
                let failure = b.stopped(study, message, Some(totals.steps + 1), e);
                (totals, Some(failure))
            }
            Err(stop) => match stop.error {
                Halt::Output(e) => {
                    return Err(Box::new(OutputStopped {
                        time: integ.state().time(),
                        step: stop.totals.steps,
                        written: self.rows.last_written,
                        source: e,
                    }))
                }
                Halt::Sensor(e, k) => {
                    let message = format!(
                        "time integration stopped; results up to t = {:.6} s are written",
                        self.rows.last_written
                    );
                    let failure = b.stopped(study, message, Some(k), e);
                    (stop.totals, Some(failure))
                }
            },
        })
    }

    /// The report, the results and the final state of `integ` after `totals`, into `out`; the
    /// sensor files are closed.
    pub fn finish(
        self,
        analysis: &MbsAnalysis,
        b: &BuiltMechanism,
        integ: &Integrator,
        totals: &mbs::StepTotals,
        obs: &mut dyn Observer,
        out: &mut Outcome,
    ) -> Result<(), BoxError> {
        let Self {
            rows,
            mut mw,
            t_start,
            t0,
            ..
        } = self;
        let sys = integ.system();
        report(analysis, integ, totals, t_start, out);
        report_last(&mut out.report, b, &rows.files);
        let (hot_spots, hot_lines) = mw.hot_spot_summary(sys, b, "t");
        out.report.extend(hot_lines);
        out.results = results(analysis, b.size(sys), hot_spots, integ, totals, t_start, t0);
        obs.sensors_end()?;
        if out.failure.is_none() {
            out.final_state = Some(integ.state().clone());
        }
        Ok(())
    }
}

/// The start of the mechanism at t = 0 (what the drivers and `[[initial]]` set and how the
/// rest was solved) at the top of the report of `out` and in its results, for an analysis
/// that starts from t = 0 rather than from another analysis.
pub fn add_start_section(study: &Study, sys: &System, out: &mut Outcome) {
    let at_rest = study.mechanism.start == crate::input::validate::mechanism::StartChoice::AtRest;
    let (lines, json) = crate::output::summary::start_section(sys.start_report(), at_rest);
    out.report.splice(0..0, lines);
    out.results["start"] = json;
}

/// The report lines of the steps taken.
fn report(analysis: &MbsAnalysis, integ: &Integrator, totals: &mbs::StepTotals, t_start: f64, out: &mut Outcome) {
    let MbsAnalysis::Dynamic {
        t_end,
        dt,
        newton,
        dt_min,
        adaptive,
        ..
    } = analysis
    else {
        return;
    };
    // Fixed steps: the last one is shortened to end exactly at t_end (mbs::fixed_steps, as
    // Integrator::run_to steps).
    let (_, last_step) = mbs::fixed_steps(t_start, *t_end, *dt);
    let &mbs::StepTotals {
        steps,
        planned,
        iterations,
        jacobians,
        max_iterations: max_iter,
        ref retries,
        rejected,
        smallest_step: h_min,
        largest_step: h_max,
    } = totals;
    let n_steps = planned.unwrap_or(0);
    let t_reached = integ.state().time();
    match adaptive {
        None => out.report.push(format!(
            "{steps} of {n_steps} steps of {dt} s{} from t = {t_start} to {t_reached:.6} s, {iterations} Newton iterations ({:.2} per step, at most {max_iter})",
            if last_step < *dt * (1.0 - 1e-9) {
                format!(" (the last shortened to {last_step:.6e} s to end at t_end)")
            } else {
                String::new()
            },
            iterations as f64 / steps.max(1) as f64
        )),
        Some(ad) => out.report.push(format!(
            "{steps} adaptive steps from t = {t_start} to {t_reached:.6} s (error tolerance {:.1e}; steps {h_min:.3e} to {h_max:.3e} s), {rejected} rejected and retried, {iterations} Newton iterations",
            ad.tolerance
        )),
    }
    if adaptive.is_none() {
        out.report.push(if retries.is_empty() {
            "no step needed retrying (fixed step)".to_string()
        } else {
            let smallest = retries.iter().map(|r| r.smallest_step).fold(f64::INFINITY, f64::min);
            let first = &retries[0];
            format!(
                "{} failed step(s) retried with halved steps (smallest {smallest:.3e} s, dt_min {dt_min:.3e} s); the first at t = {:.6} s: {}",
                retries.len(),
                first.time,
                first.cause
            )
        });
    }
    if *newton == mbs::NewtonStrategy::Modified {
        out.report.push(format!(
            "modified Newton: {jacobians} iteration matrices factorised ({:.2} per step)",
            jacobians as f64 / steps.max(1) as f64
        ));
    }
}

/// The results of the run for the summary.
fn results(
    analysis: &MbsAnalysis,
    model: serde_json::Value,
    hot_spots: serde_json::Value,
    integ: &Integrator,
    totals: &mbs::StepTotals,
    t_start: f64,
    t0: Instant,
) -> serde_json::Value {
    let (newton, adaptive) = match analysis {
        MbsAnalysis::Dynamic { newton, adaptive, .. } => (*newton, adaptive.is_some()),
        _ => (mbs::NewtonStrategy::Full, false),
    };
    let (retries, h_min) = (&totals.retries, totals.smallest_step);
    json!({
        "model": model,
        "hot_spots": hot_spots,
        "steps": totals.steps,
        "steps_planned": totals.planned,
        "t_start": t_start,
        "t_reached": integ.state().time(),
        "newton_iterations": totals.iterations,
        "max_iterations_per_step": totals.max_iterations,
        "newton": match newton {
            mbs::NewtonStrategy::Full => "full",
            mbs::NewtonStrategy::Modified => "modified",
        },
        "jacobians": totals.jacobians,
        "adaptive": adaptive,
        "smallest_step": if h_min.is_finite() { json!(h_min) } else { json!(null) },
        "largest_step": totals.largest_step,
        "rejected_steps": totals.rejected,
        "retried_steps": retries.len(),
        "retries": retries.iter().map(|r| json!({
            "time": r.time,
            "step": r.step,
            "smallest_step": r.smallest_step,
            "substeps": r.substeps,
            "cause": r.cause.to_string(),
        })).collect::<Vec<_>>(),
        "seconds_solving": t0.elapsed().as_secs_f64(),
    })
}
