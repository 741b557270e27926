//! What one analysis produced, part or mechanism alike.

use crate::build::{joint_count, BuiltMechanism};
use crate::error::{AnalysisFailed, BoxError, SolverStopped};
use crate::input::validate::Study;
use crate::output::observer::{AnalysisInfo, Observer};
use crate::output::summary::{Status, Summary};
use serde_json::json;

/// What one analysis produced, for the summary.
pub struct Outcome {
    pub free_dofs: usize,
    pub report: Vec<String>,
    pub results: serde_json::Value,
    /// A solver that stopped after writing part of its results.
    pub failure: Option<SolverStopped>,
    /// The final state (equilibrium, dynamic), for analyses that `start` from it.
    pub final_state: Option<mbs::State>,
}

impl Outcome {
    /// The outcome of an analysis of the mechanism `b` (system `sys`) before it runs: its size.
    pub(crate) fn of_mechanism(study: &Study, b: &BuiltMechanism, sys: &mbs::System) -> Self {
        let n = sys.n_dof();
        Outcome {
            free_dofs: n,
            report: vec![format!(
                "mechanism: {} nodes, {} flexible and {} rigid bodies, {}, {n} unknowns",
                b.model.nodes.len(),
                b.bodies.len(),
                b.rigid.len(),
                joint_count(study)
            )],
            results: json!({}),
            failure: None,
            final_state: None,
        }
    }
}

/// Analysis `index` of `study` (`info`), which took `seconds`, with results in
/// `results_dir`: what [`record_outcome`] records.
pub(crate) struct Recorded<'a> {
    pub study: &'a Study,
    pub index: usize,
    pub info: &'a AnalysisInfo,
    pub seconds: f64,
    pub results_dir: String,
}

/// Records the outcome `result` of analysis `at` in `summary` and tells `obs`; a failure is
/// returned with the analysis it belongs to.
pub(crate) fn record_outcome(
    summary: &mut Summary,
    at: &Recorded<'_>,
    result: Result<Outcome, BoxError>,
    obs: &mut dyn Observer,
) -> Result<(), BoxError> {
    let (study, info) = (at.study, at.info);
    let a = &study.analyses[at.index];
    let files = obs.take_files();
    let entry = &mut summary.analyses[at.index];
    entry.seconds = Some(at.seconds);
    entry.files = files;
    let where_ = || at.results_dir.clone();
    match result {
        Ok(o) => {
            entry.status = Status::Done;
            entry.free_dofs = Some(o.free_dofs);
            entry.report = o.report;
            entry.results = o.results;
            if let Some(failure) = o.failure {
                // The solver stopped: what it computed is written; the run fails here.
                entry.status = Status::Failed;
                entry.error = Some(crate::error::chain(&failure));
                summary.status = failed_status();
                summary.reason = Some(format!("analysis '{}': {}", a.name, crate::error::chain(&failure)));
                let entry = entry.clone();
                // The failure is the message; a summary that cannot be written (a full
                // disk) must not replace it.
                let _ = obs.end(info, &entry);
                let _ = obs.summary(summary);
                return Err(Box::new(AnalysisFailed {
                    analysis: a.name.clone(),
                    message: format!(
                        "{} analysis '{}' ({}) stopped; what it computed is in {}/{}",
                        a.kind_name(),
                        a.name,
                        study.location(&a.path),
                        where_(),
                        a.name
                    ),
                    source: Box::new(failure),
                }));
            }
            let entry = entry.clone();
            obs.end(info, &entry)?;
            obs.summary(summary)?;
            Ok(())
        }
        Err(e) => {
            entry.status = Status::Failed;
            entry.error = Some(crate::error::chain(&*e));
            summary.status = failed_status();
            summary.reason = Some(format!("analysis '{}': {}", a.name, crate::error::chain(&*e)));
            let entry = entry.clone();
            let _ = obs.end(info, &entry);
            let _ = obs.summary(summary);
            Err(Box::new(AnalysisFailed {
                analysis: a.name.clone(),
                message: format!(
                    "{} analysis '{}' ({}) failed; the results of the analyses before it are in {}",
                    a.kind_name(),
                    a.name,
                    study.location(&a.path),
                    where_()
                ),
                source: e,
            }))
        }
    }
}

/// The summary status of a run that stopped: `interrupted` after Ctrl-C or SIGTERM, else
/// `failed`.
fn failed_status() -> String {
    if crate::interrupt::requested() {
        "interrupted".into()
    } else {
        "failed".into()
    }
}
