//! The [`Runner`]: a study run analysis by analysis into an observer, with its summary.

use super::options::Options;
use super::outcome::{record_outcome, Outcome, Recorded};
use crate::build::BuiltMechanism;
use crate::error::BoxError;
use crate::input::part::Part;
use crate::input::validate::{AnalysisSpec, MbsAnalysis, Study};
use crate::output::observer::{AnalysisInfo, Observer};
use crate::output::summary::{AnalysisSummary, PartSummary, Status, Summary};
use serde_json::json;
use std::time::Instant;

fn part_summary(p: &Part) -> PartSummary {
    PartSummary {
        name: p.name.clone(),
        description: p.description.clone(),
        nodes: p.base.node_count(),
        elements: p.base.elements.len(),
        interfaces: p.interfaces.iter().map(|i| i.name.clone()).collect(),
    }
}

/// The analysis `a` (number `index` of the study) as the observer sees it.
pub fn analysis_info(study: &Study, index: usize) -> AnalysisInfo {
    let a = &study.analyses[index];
    AnalysisInfo {
        index,
        count: study.analyses.len(),
        name: a.name.clone(),
        kind: a.kind_name().into(),
        of: match a.part {
            Some(p) => format!("part '{}'", study.parts[p].name),
            None => "the mechanism".to_string(),
        },
    }
}

/// The summary of `study` before anything ran: every analysis pending.
pub fn pending_summary(study: &Study) -> Summary {
    Summary {
        flexmbs_version: env!("CARGO_PKG_VERSION").to_string(),
        study: study.source.path.display().to_string(),
        title: study.title.clone(),
        status: "running".into(),
        reason: None,
        parts: study.parts.iter().map(part_summary).collect(),
        analyses: study
            .analyses
            .iter()
            .map(|a| AnalysisSummary {
                name: a.name.clone(),
                kind: a.kind_name().into(),
                part: a
                    .part
                    .map_or_else(|| "(mechanism)".to_string(), |p| study.parts[p].name.clone()),
                status: Status::Pending,
                seconds: None,
                free_dofs: None,
                report: Vec::new(),
                results: serde_json::Value::Null,
                files: Vec::new(),
                error: None,
            })
            .collect(),
        total_seconds: 0.0,
    }
}

/// A study being run analysis by analysis; the mechanism is built once, at its first
/// analysis, and kept for the next.
pub struct Runner<'s> {
    study: &'s Study,
    options: Options,
    start: Instant,
    pub summary: Summary,
    mechanism: Option<BuiltMechanism>,
    /// The final state of each analysis of the mechanism that ended in one (for `start`).
    states: Vec<Option<mbs::State>>,
    /// The force law every analysis of the mechanism evaluates in its iterations.
    forces: super::force_law::Forces,
}

impl<'s> Runner<'s> {
    pub fn new(study: &'s Study, options: &Options) -> Self {
        Self {
            study,
            options: options.clone(),
            start: Instant::now(),
            summary: pending_summary(study),
            mechanism: None,
            states: vec![None; study.analyses.len()],
            forces: None,
        }
    }

    /// This runner with the force law `forces` in every analysis of the mechanism
    /// ([`crate::ForceLawSource`]).
    pub fn with_forces(mut self, forces: super::force_law::Forces) -> Self {
        self.forces = forces;
        self
    }

    /// The force law of the run.
    pub fn forces(&self) -> &super::force_law::Forces {
        &self.forces
    }

    /// The final state of analysis `i`, once it has run (equilibrium and dynamic analyses).
    pub fn state(&self, i: usize) -> Option<&mbs::State> {
        self.states[i].as_ref()
    }

    /// The mechanism, built (its bodies reduced through the cache) at the first call.
    pub fn mechanism(&mut self, obs: &mut dyn Observer) -> Result<&BuiltMechanism, BoxError> {
        if self.mechanism.is_none() {
            let cache = self.options.cache_dir(self.study);
            self.mechanism = Some(super::reduce::build_mechanism(self.study, &cache, obs)?);
        }
        self.mechanism
            .as_ref()
            .ok_or_else(|| "the mechanism could not be built".into())
    }

    /// The state analysis `i` starts from: the final state of the analysis its `start`
    /// names, once that analysis and the chain of `start`s behind it have run, without output.
    pub fn start_state(&mut self, i: usize) -> Result<Option<mbs::State>, BoxError> {
        let mut chain = Vec::new();
        let mut at = self.study.analyses[i].start;
        while let Some(k) = at {
            chain.push(k);
            at = self.study.analyses[k].start;
        }
        for &k in chain.iter().rev() {
            self.run_one(k, &mut ())?;
        }
        Ok(self.study.analyses[i].start.and_then(|k| self.state(k)).cloned())
    }

    /// Runs analysis `i`; a failure is recorded in the summary and returned with the
    /// analysis it belongs to. An analysis whose `start` names one that has not run yet runs
    /// that one first (and its own `start`, down the chain), with its results recorded as
    /// usual: running one analysis alone needs no earlier run.
    pub fn run_one(&mut self, i: usize, obs: &mut dyn Observer) -> Result<(), BoxError> {
        let study = self.study;
        let a = &study.analyses[i];
        // The analysis whose final state is the start, run now when it has not run.
        let mut prerequisite = None;
        if let Some(k) = a.start {
            if self.states[k].is_none() && self.summary.analyses[k].status == Status::Pending {
                self.run_one(k, obs)?;
                prerequisite = Some(k);
            }
        }
        let info = analysis_info(study, i);
        let t = Instant::now();
        if let Err(e) = obs.begin(&info) {
            // Its folder refused (a user's file, a symbolic link) or a stop asked for: the
            // summary says so, as for a failure of the analysis itself.
            return self.record(i, &info, t, Err(e), obs);
        }
        let (result, shortened) = match &a.spec {
            AnalysisSpec::Mbs(spec) => self.run_mechanism(i, spec, obs),
            _ => {
                let cache = self.options.cache_dir(study);
                (super::part::run_analysis(study, a, &cache, obs), None)
            }
        };
        let result = result.map(|o| annotate(study, o, prerequisite, shortened));
        self.record(i, &info, t, result, obs)
    }

    /// Runs analysis `i` of the mechanism, `spec` cut to `--t-end`, from the state its
    /// `start` names; keeps its final state. Returns with the outcome the study's `t_end` and
    /// the `--t-end` it was cut to, when the option shortened the run.
    fn run_mechanism(
        &mut self,
        i: usize,
        spec: &MbsAnalysis,
        obs: &mut dyn Observer,
    ) -> (Result<Outcome, BoxError>, Option<(f64, f64)>) {
        let study = self.study;
        let a = &study.analyses[i];
        let mut shortened = None;
        let mut spec = spec.clone();
        let mut refused = None;
        if let (MbsAnalysis::Dynamic { t_end, dt, .. }, Some(limit)) = (&mut spec, self.options.t_end) {
            if limit < *dt {
                refused = Some(format!(
                    "--t-end {limit} s is shorter than one time step of analysis '{}' (dt = {dt} s)",
                    a.name
                ));
            }
            if limit < *t_end {
                shortened = Some((*t_end, limit));
                *t_end = limit;
            }
        }
        let start: Result<Option<mbs::State>, BoxError> = match (refused, a.start) {
            (Some(refusal), _) => Err(refusal.into()),
            (None, start) => match start {
                Some(k) => self.states[k].clone().map(Some).ok_or_else(|| {
                    format!(
                        "analysis '{}' starts from '{}', which ended in no state",
                        a.name, study.analyses[k].name
                    )
                    .into()
                }),
                None => Ok(None),
            },
        };
        let forces = self.forces.clone();
        let mut result = match (start, self.mechanism(obs)) {
            (Ok(start), Ok(built)) => super::mechanism::run_analysis(study, &spec, built, start.as_ref(), &forces, obs),
            (Err(e), _) | (_, Err(e)) => Err(e),
        };
        self.states[i] = result.as_mut().ok().and_then(|o| o.final_state.take());
        (result, shortened)
    }

    /// Records the outcome `result` of analysis `i` (`info`, begun at `t`) in the summary
    /// and tells `obs`; a failure is returned with the analysis it belongs to.
    fn record(
        &mut self,
        i: usize,
        info: &AnalysisInfo,
        t: Instant,
        result: Result<Outcome, BoxError>,
        obs: &mut dyn Observer,
    ) -> Result<(), BoxError> {
        let study = self.study;
        self.summary.total_seconds = self.start.elapsed().as_secs_f64();
        let results_dir = match &self.options.out {
            Some(out) => out.display().to_string(),
            None => self.options.results_dir(study).display().to_string(),
        };
        let at = Recorded {
            study,
            index: i,
            info,
            seconds: t.elapsed().as_secs_f64(),
            results_dir,
        };
        record_outcome(&mut self.summary, &at, result, obs)
    }

    /// The mechanism built, handed out (`None` when no analysis of the mechanism ran).
    pub fn into_mechanism(self) -> Option<BuiltMechanism> {
        self.mechanism
    }

    /// Marks the run complete and hands the summary out.
    pub fn finish(mut self, obs: &mut dyn Observer) -> Result<Summary, BoxError> {
        self.summary.status = "complete".into();
        self.summary.total_seconds = self.start.elapsed().as_secs_f64();
        obs.summary(&self.summary)?;
        Ok(self.summary)
    }
}

/// The report of outcome `o` with what the run changed: the analysis that was run first for
/// its start (`prerequisite`), and the `t_end` of the study cut by `--t-end` (`shortened`).
fn annotate(study: &Study, mut o: Outcome, prerequisite: Option<usize>, shortened: Option<(f64, f64)>) -> Outcome {
    if let Some(k) = prerequisite {
        o.report.insert(
            0,
            format!(
                "started from the final state of '{}', which was run first for it",
                study.analyses[k].name
            ),
        );
    }
    if let Some((requested, limit)) = shortened {
        o.report.insert(
            0,
            format!("shortened by --t-end: run to t = {limit} s instead of the study's t_end = {requested} s"),
        );
        if let Some(r) = o.results.as_object_mut() {
            r.insert("t_end_study".into(), json!(requested));
            r.insert("t_end_option".into(), json!(limit));
        }
    }
    o
}
