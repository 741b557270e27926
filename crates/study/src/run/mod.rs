//! Executes a validated [`Study`] analysis by analysis, every result to an [`Observer`] as
//! soon as it is computed.
//!
//! | module | what it holds |
//! |---|---|
//! | [`runner`] | the [`Runner`]: the run loop, the summary, the mechanism built once, the start chain |
//! | [`part`] | the analyses of parts: static, modal, reduce |
//! | [`reduce`] | the cached reduction service: parts reduced through [`cache`], `flexmbs reduce` |
//! | [`cache`] | reduced bodies cached by a hash of what produced them |
//! | [`mechanism`] | the analyses of the mechanism: equilibrium, linearized, buckling |
//! | [`dynamic_output`] | a dynamic analysis' rows and meshes at the output times, its report and results |
//! | [`dynamic`] | the dynamic analysis: the time integration of a run |
//! | [`force_law`] | a force law of a run named in the study's terms: its ports on the built mechanism |
//! | [`selection`] | analyses picked by name, or all of them |
//! | [`simulation`] | a dynamic analysis stepped by the caller |
//! | [`sensors`] | sensor columns and the stream of samples |
//! | [`mesh`] | the deformed meshes of the mechanism, stresses and hot spots |
//! | [`inspect`] | what a reduced body holds and its physical checks, for a person (`flexmbs inspect`) |

pub mod cache;
pub mod dynamic;
pub mod dynamic_output;
pub mod force_law;
pub mod inspect;
pub mod mechanism;
pub mod mesh;
pub mod options;
pub mod outcome;
pub mod part;
pub mod reduce;
pub mod runner;
pub mod selection;
pub mod sensors;
pub mod simulation;

pub use force_law::{ForceLawSource, Forces};
pub use options::Options;
pub use runner::Runner;
pub use selection::{Selection, UnknownName};
pub use simulation::{SavedSimulation, Simulation};

use crate::error::BoxError;
use crate::input::validate::{AnalysisSpec, MbsAnalysis, Study};
use crate::output::folder::ResultsFolder;
use crate::output::observer::Observer;
use crate::output::summary::Summary;
use std::sync::Arc;

/// Runs every analysis of `study` into a results folder (`options.out`, or beside the study
/// file), with `observer` seeing every result too. Stops at the first analysis that fails,
/// after writing the summary with the failure.
pub fn run(study: &Study, options: &Options, observer: &mut dyn Observer) -> Result<Summary, BoxError> {
    run_forced(study, options, &None, observer)
}

/// [`run`] with the force law `forces` in every analysis of the mechanism.
fn run_forced(
    study: &Study,
    options: &Options,
    forces: &Forces,
    observer: &mut dyn Observer,
) -> Result<Summary, BoxError> {
    // Refused before the results folder is made.
    if study.analyses.is_empty() {
        return Err(nothing_to_run(study));
    }
    let names: Vec<String> = study.analyses.iter().map(|a| a.name.clone()).collect();
    let mut folder = ResultsFolder::open(&options.results_dir(study), &names, options.foreign)?;
    run_all(study, options, forces, &mut (&mut folder, observer))
}

/// Runs analysis `index` of `study` alone into its results folder (the other analyses'
/// files are left as they are), every result to `observer` too. When its `start` names
/// another analysis, that one (and the chain of `start`s behind it) runs first and writes
/// its results too ([`Runner::run_one`]).
pub fn run_only(
    study: &Study,
    options: &Options,
    index: usize,
    observer: &mut dyn Observer,
) -> Result<Summary, BoxError> {
    run_only_forced(study, options, index, &None, observer)
}

/// [`run_only`] with the force law `forces` in every analysis of the mechanism.
fn run_only_forced(
    study: &Study,
    options: &Options,
    index: usize,
    forces: &Forces,
    observer: &mut dyn Observer,
) -> Result<Summary, BoxError> {
    let names: Vec<String> = study.analyses.iter().map(|a| a.name.clone()).collect();
    let mut folder = ResultsFolder::open(&options.results_dir(study), &names, options.foreign)?;
    let obs: &mut dyn Observer = &mut (&mut folder, observer);
    let mut runner = Runner::new(study, options).with_forces(forces.clone());
    obs.summary(&runner.summary)?;
    runner.run_one(index, obs)?;
    runner.finish(obs)
}

/// Runs every analysis of `study`, every result to `obs` only (no results folder unless
/// `obs` writes one); the cache of reduced bodies is used as in [`run`].
pub fn run_with(study: &Study, options: &Options, obs: &mut dyn Observer) -> Result<Summary, BoxError> {
    run_all(study, options, &None, obs)
}

/// [`run_with`] with the force law `forces` in every analysis of the mechanism.
fn run_all(study: &Study, options: &Options, forces: &Forces, obs: &mut dyn Observer) -> Result<Summary, BoxError> {
    let n = study.analyses.len();
    if n == 0 {
        return Err(nothing_to_run(study));
    }
    let mut runner = Runner::new(study, options).with_forces(forces.clone());
    obs.summary(&runner.summary)?;
    for i in 0..n {
        runner.run_one(i, obs)?;
    }
    runner.finish(obs)
}

/// Runs the analyses `selection` picks: every one ([`run`]) or one ([`run_only`]), into the
/// results folder, every result to `observer` too.
pub fn run_selected(
    study: &Study,
    options: &Options,
    selection: Selection,
    observer: &mut dyn Observer,
) -> Result<Summary, BoxError> {
    run_selected_with(study, options, selection, &None, observer)
}

/// [`run_selected`] with the force law `forces` evaluated in every Newton iteration of every
/// analysis of the mechanism ([`ForceLawSource`]).
pub fn run_selected_with(
    study: &Study,
    options: &Options,
    selection: Selection,
    forces: &Forces,
    observer: &mut dyn Observer,
) -> Result<Summary, BoxError> {
    match selection {
        Selection::All => run_forced(study, options, forces, observer),
        Selection::One(i) => run_only_forced(study, options, i, forces, observer),
    }
}

/// The error for a study without analyses.
pub fn nothing_to_run(study: &Study) -> BoxError {
    format!(
        "{}: the study has no [[analyses]], so there is nothing to run; add one \
         (`type = \"static\"`, `\"modal\"`, `\"reduce\"`, `\"equilibrium\"`, `\"dynamic\"`, \
         `\"linearized\"` or `\"buckling\"`, docs/study-file.md)",
        study.source.path.display()
    )
    .into()
}

impl Simulation {
    /// Builds the mechanism of `study` (bodies reduced through the cache of `options`) and
    /// starts its dynamic analysis called `analysis` (from the final state of the analysis
    /// named in its `start`, which the runner runs first, without output).
    pub fn new(study: &Study, analysis: &str, options: &Options) -> Result<Self, BoxError> {
        Self::new_with(study, analysis, options, &None)
    }

    /// [`Simulation::new`] with the force law `forces` evaluated in every Newton iteration of
    /// its steps ([`ForceLawSource`]; and of the analyses its `start` runs first).
    pub fn new_with(study: &Study, analysis: &str, options: &Options, forces: &Forces) -> Result<Self, BoxError> {
        let mut p = Prepared::new(study, analysis, options, forces)?;
        Self::with_start(study, p.system, p.runner.mechanism(&mut ())?, p.spec, p.first)
    }

    /// [`Simulation::new`] writing the results folder of its analysis as it steps (the
    /// folder of `options`, as `flexmbs run --analysis NAME` writes it): sensor files and
    /// plots, meshes and the summary, step by step at the output times of the study. The
    /// results end with [`Simulation::finish_results`] (or when the simulation is dropped),
    /// and so does the summary, `complete` or `failed`; until then it says `running`.
    pub fn writing_results(study: &Study, analysis: &str, options: &Options) -> Result<Self, BoxError> {
        Self::writing_results_with(study, analysis, options, &None)
    }

    /// [`Simulation::writing_results`] with the force law `forces` ([`Simulation::new_with`]).
    pub fn writing_results_with(
        study: &Study,
        analysis: &str,
        options: &Options,
        forces: &Forces,
    ) -> Result<Self, BoxError> {
        let i = study.analysis(analysis)?;
        let names: Vec<String> = study.analyses.iter().map(|a| a.name.clone()).collect();
        let mut folder = ResultsFolder::open(&options.results_dir(study), &names, options.foreign)?;
        let began = std::time::Instant::now();
        let Prepared {
            spec,
            runner,
            system,
            first,
        } = Prepared::new(study, analysis, options, forces)?;
        let summary = runner.summary.clone();
        let built = runner.into_mechanism().ok_or("the mechanism could not be built")?;
        let mut sim = Self::with_start(study, system, &built, spec, first)?;
        let info = runner::analysis_info(study, i);
        folder.summary(&summary)?;
        folder.begin(&info)?;
        let output = dynamic_output::DynamicOutput::start(study, &built, sim.integrator(), &mut folder, began)?;
        let planned = sim.planned_steps();
        sim.keep_results(simulation::Recording {
            folder,
            output: Some(output),
            study: study.clone(),
            built,
            index: i,
            info,
            spec: spec.clone(),
            summary,
            totals: mbs::StepTotals::new(planned),
            began,
            halted: None,
        });
        Ok(sim)
    }
}

/// A dynamic analysis of the mechanism ready to step: its spec, the runner that built the
/// mechanism and ran the analyses its `start` names (without output), the system and the
/// first state.
struct Prepared<'s> {
    spec: &'s MbsAnalysis,
    runner: Runner<'s>,
    system: Arc<mbs::System>,
    first: mbs::State,
}

impl<'s> Prepared<'s> {
    fn new(study: &'s Study, analysis: &str, options: &Options, forces: &Forces) -> Result<Self, BoxError> {
        let i = study.analysis(analysis)?;
        let AnalysisSpec::Mbs(spec) = &study.analyses[i].spec else {
            return Err(format!("analysis '{analysis}' is not an analysis of the mechanism").into());
        };
        let mut runner = Runner::new(study, options).with_forces(forces.clone());
        let system = Arc::new(force_law::system(study, runner.mechanism(&mut ())?, forces)?);
        let start = runner.start_state(i)?;
        let first = simulation::dynamic_start(&system, start.as_ref(), study.mechanism.start);
        Ok(Self {
            spec,
            runner,
            system,
            first,
        })
    }
}
