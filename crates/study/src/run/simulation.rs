//! A dynamic analysis of the mechanism stepped by the caller: [`Simulation::step`] or
//! [`Simulation::advance_to`], and between steps every sensor, the state and the node
//! motions can be read, the value of named loads changed and actuator efforts held at values
//! set by the caller. The `dynamic` analyses of a study run (`run::dynamic`)
//! step the same type, so a script that steps a simulation to the end gets the numbers the
//! program writes. [`Simulation::new`] (in `run`) builds the mechanism and asks the
//! [`super::Runner`] for the state its `start` names.

use super::dynamic_output::{add_start_section, DynamicOutput, Halt};
use super::outcome::{record_outcome, Outcome, Recorded};
use super::sensors::{sensor_columns, sensor_indices};
use crate::build::{BuiltMechanism, LoadTarget, NamedLoad};
use crate::error::{BoxError, Location};
use crate::input::validate::mechanism::StartChoice;
use crate::input::validate::{MbsAnalysis, Study};
use crate::output::folder::ResultsFolder;
use crate::output::observer::{AnalysisInfo, Observer};
use crate::output::summary::Summary;
use crate::sensor_group::SensorGroup;
use mbs::{DynamicSettings, Integrator, LoadKind, NodeMotion, SensorRecord, State, System};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;
use std::time::Instant;

/// A generalized-α time integration of the study's mechanism (module docs).
pub struct Simulation {
    integrator: Integrator<'static>,
    groups: Vec<SensorGroup>,
    /// Per sensor group: its columns in a row of the `mbs` sensor record.
    columns: Vec<Vec<usize>>,
    /// Per sensor group: its `mbs` sensors (indices in `Model::sensors`, ascending), found once
    /// at set-up so that reading a sensor between steps (a controller's loop) looks nothing up.
    sensor_indices: Vec<Vec<usize>>,
    /// The group of each sensor name (the first, should two share one).
    group_of: HashMap<String, usize>,
    loads: Vec<NamedLoad>,
    /// The step size and end time of the analysis.
    dt: f64,
    t_end: f64,
    /// The analysis' step control: fixed steps retried with halved steps down to `dt_min`, or
    /// adaptive steps (`[analyses.adaptive]`), as in a run.
    stepping: mbs::Stepping,
    /// The fixed steps of `dt` to the end time, planned as a run plans them: taken since the
    /// plan was made and planned in all (the last one is shortened to land on `t_end`).
    plan: FixedPlan,
    /// Where the study describes each entity of the model, for [`Simulation::locate`].
    locations: BTreeMap<mbs::Entity, Location>,
    /// The results folder written as the simulation steps ([`Simulation::writing_results`]).
    recording: Option<Box<Recording>>,
}

/// The results folder of a simulation that writes one as it steps: the files of a run of its
/// analysis (sensor CSVs and plots, meshes, summary), written step by step by the run's own
/// [`DynamicOutput`].
pub(crate) struct Recording {
    pub folder: ResultsFolder,
    /// `None` once the results are finished.
    pub output: Option<DynamicOutput>,
    pub study: Study,
    pub built: BuiltMechanism,
    pub index: usize,
    pub info: AnalysisInfo,
    pub spec: MbsAnalysis,
    pub summary: Summary,
    pub totals: mbs::StepTotals,
    pub began: Instant,
    /// What stopped the output (a sensor that is not finite, a file that cannot be written):
    /// the results end there.
    pub halted: Option<Halt>,
}

impl Recording {
    /// Writes the rows still waiting, the report and results of the steps taken, and the
    /// summary (`complete`, or `failed` with what stopped the output); the results are final.
    fn finish(&mut self, integ: &mbs::Integrator) -> Result<Summary, BoxError> {
        let Some(mut output) = self.output.take() else {
            return Ok(self.summary.clone());
        };
        let run = match self.halted.take() {
            Some(error) => Err(Box::new(mbs::Interrupted {
                error,
                totals: self.totals.clone(),
            })),
            None => Ok((self.totals.clone(), None)),
        };
        let folder = &mut self.folder;
        let (study, built, spec, index) = (&self.study, &self.built, &self.spec, self.index);
        let result = || -> Result<Outcome, BoxError> {
            let (totals, failure) = output.end_rows(study, built, integ, run, folder)?;
            let mut out = Outcome::of_mechanism(study, built, integ.system());
            out.failure = failure;
            output.finish(spec, built, integ, &totals, folder, &mut out)?;
            if study.analyses[index].start.is_none() {
                add_start_section(study, integ.system(), &mut out);
            }
            Ok(out)
        };
        let result = result();
        let at = Recorded {
            study,
            index: self.index,
            info: &self.info,
            seconds: self.began.elapsed().as_secs_f64(),
            results_dir: self.folder.root().display().to_string(),
        };
        self.summary.total_seconds = self.began.elapsed().as_secs_f64();
        record_outcome(&mut self.summary, &at, result, &mut self.folder)?;
        self.summary.status = "complete".into();
        self.folder.summary(&self.summary)?;
        Ok(self.summary.clone())
    }
}

/// Fixed steps from a time to the end time ([`mbs::fixed_steps`]), counted as they are taken.
#[derive(Clone, Copy, Debug)]
struct FixedPlan {
    taken: usize,
    planned: usize,
}

impl FixedPlan {
    fn new(t: f64, t_end: f64, h: f64) -> Self {
        Self {
            taken: 0,
            planned: mbs::fixed_steps(t, t_end, h).0,
        }
    }
}

/// The step control of a `dynamic` analysis: fixed steps retried down to `dt_min`, or the
/// adaptive steps of its `[analyses.adaptive]`.
pub fn stepping(spec: &MbsAnalysis) -> Option<mbs::Stepping> {
    match spec {
        MbsAnalysis::Dynamic { dt_min, adaptive, .. } => Some(match adaptive {
            None => mbs::Stepping::Fixed { min_step: *dt_min },
            Some(ad) => mbs::Stepping::Adaptive(ad.clone()),
        }),
        _ => None,
    }
}

/// The integrator settings of a `dynamic` analysis.
pub fn dynamic_settings(spec: &MbsAnalysis, output_every: usize) -> Option<DynamicSettings> {
    let MbsAnalysis::Dynamic {
        t_end,
        dt,
        rho_inf,
        tolerance,
        max_iterations,
        newton,
        body_axis_translations,
        ..
    } = spec
    else {
        return None;
    };
    let mut settings = DynamicSettings::new(*dt, *t_end, *rho_inf);
    settings.tolerance = *tolerance;
    settings.max_iterations = *max_iterations;
    settings.newton = *newton;
    settings.body_axis_translations = *body_axis_translations;
    settings.output_every = output_every;
    Some(settings)
}

impl Simulation {
    /// Starts the `dynamic` analysis `spec` of `study` on the built mechanism `b` at the
    /// initial state (initial accelerations solved).
    pub fn start(study: &Study, b: &BuiltMechanism, spec: &MbsAnalysis) -> Result<Self, BoxError> {
        Self::with_system(study, Arc::new(b.system(study)?), b, spec)
    }

    /// [`Simulation::start`] on the system of `b` built before.
    pub fn with_system(
        study: &Study,
        system: Arc<System>,
        b: &BuiltMechanism,
        spec: &MbsAnalysis,
    ) -> Result<Self, BoxError> {
        let state = initial_state(&system, study.mechanism.start);
        Self::with_start(study, system, b, spec, state)
    }

    /// [`Simulation::with_system`] from the state `start` (the final state of an earlier
    /// analysis: the time goes on from its time).
    pub fn with_start(
        study: &Study,
        system: Arc<System>,
        b: &BuiltMechanism,
        spec: &MbsAnalysis,
        state: State,
    ) -> Result<Self, BoxError> {
        let Some(settings) = dynamic_settings(spec, study.mechanism.output.every) else {
            return Err("a simulation steps a dynamic analysis; this one is not".into());
        };
        let (dt, t_end) = (settings.step, settings.end_time);
        let stepping = stepping(spec).ok_or("a simulation steps a dynamic analysis; this one is not")?;
        let plan = FixedPlan::new(state.time(), t_end, dt);
        let record = system.sensor_record();
        let columns = sensor_columns(&b.groups, &record)?;
        let mut sensor_indices = sensor_indices(&b.groups, &record)?;
        // `Integrator::sensor_values` takes them ascending (a group's sensors are consecutive
        // in the model and in order, so its columns keep their order).
        sensor_indices.iter_mut().for_each(|ks| ks.sort_unstable());
        let mut group_of = HashMap::with_capacity(b.groups.len());
        for (g, group) in b.groups.iter().enumerate() {
            group_of.entry(group.name.clone()).or_insert(g);
        }
        let integrator = Integrator::new_owned(system, state, settings).map_err(|e| {
            let message = "the initial accelerations cannot be solved".to_string();
            Box::new(b.stopped(study, message, None, e))
        })?;
        let locations = b.entities.iter().map(|(e, path)| (*e, study.at(path))).collect();
        Ok(Self {
            integrator,
            groups: b.groups.clone(),
            columns,
            sensor_indices,
            group_of,
            loads: b.loads.clone(),
            dt,
            t_end,
            stepping,
            plan,
            locations,
            recording: None,
        })
    }

    /// Where the study describes the entity a solver error of this simulation is about
    /// (`mbs::SolveError::entity`: the body whose floating frame failed), if it is one.
    pub fn locate(&self, error: &mbs::SolveError) -> Option<&Location> {
        error.entity().and_then(|e| self.locations.get(&e))
    }

    /// The time reached.
    pub fn time(&self) -> f64 {
        self.integrator.state().time()
    }

    /// The step size and the end time of the analysis.
    pub fn step_size(&self) -> f64 {
        self.dt
    }
    pub fn end_time(&self) -> f64 {
        self.t_end
    }

    /// Sets the size `h` of the next steps; the fixed steps to the end time are planned anew
    /// from the time reached (the last one shortened to land on it).
    pub fn set_step_size(&mut self, h: f64) {
        self.dt = h;
        self.integrator.set_step_size(h);
        self.plan = FixedPlan::new(self.time(), self.t_end, h);
    }

    /// Steps taken (a retried step's halved steps count one by one).
    pub fn steps(&self) -> usize {
        self.integrator.steps()
    }

    /// One step under the analysis' step control, as a run takes it: a fixed step of `dt`
    /// (the last one before the end time shortened to land on it) whose failure is retried
    /// with halved steps down to `dt_min`, or one adaptive step. On failure the state stays
    /// at the last converged step and the error says where (time, step, residual).
    pub fn step(&mut self) -> Result<mbs::Taken, Box<mbs::RetryFailure>> {
        let h = self.dt;
        let last = matches!(self.stepping, mbs::Stepping::Fixed { .. }) && self.plan.planned == self.plan.taken + 1;
        if last {
            self.integrator
                .set_step_size(mbs::last_step_size(self.time(), self.t_end, h));
        }
        let t_before = self.time();
        let taken = self.integrator.step_under(&self.stepping, self.t_end);
        if last {
            self.integrator.set_step_size(h);
        }
        let taken = taken?;
        self.plan.taken += 1;
        self.write_step(&taken, t_before)?;
        Ok(taken)
    }

    /// One step of size `h` (retried with halved steps down to the analysis' smallest step
    /// when it fails); the steps after it are of the analysis' size again, planned anew to
    /// the end time.
    pub fn step_by(&mut self, h: f64) -> Result<mbs::Taken, Box<mbs::RetryFailure>> {
        let min_step = match &self.stepping {
            mbs::Stepping::Fixed { min_step } => *min_step,
            mbs::Stepping::Adaptive(ad) => ad.min_step,
        };
        let (before, t_before) = (self.integrator.step_size(), self.time());
        self.integrator.set_step_size(h);
        let taken = self.integrator.step_under(
            &mbs::Stepping::Fixed {
                min_step: min_step.min(h),
            },
            self.t_end,
        );
        self.integrator.set_step_size(before);
        self.plan = FixedPlan::new(self.time(), self.t_end, self.dt);
        let taken = taken?;
        self.write_step(&taken, t_before)?;
        Ok(taken)
    }

    /// Writes the step `taken` from `t_before` into the results folder, if the simulation
    /// keeps one, at the output times of a run. A sensor that is not finite ends the results
    /// there (their summary says so) and is returned; a file that cannot be written ends them
    /// too, and [`Simulation::finish_results`] returns it.
    fn write_step(&mut self, taken: &mbs::Taken, t_before: f64) -> Result<(), Box<mbs::RetryFailure>> {
        let Some(rec) = self.recording.as_deref_mut() else {
            return Ok(());
        };
        let Some(output) = rec.output.as_mut() else {
            return Ok(());
        };
        let t = self.integrator.state().time();
        rec.totals.count(taken.clone(), t - t_before);
        let done = mbs::StepDone {
            k: rec.totals.steps,
            last: self.t_end - t <= 1e-12 * self.t_end.abs().max(1.0),
            planned: rec.totals.planned,
            time: t,
            start: t_before,
        };
        let Err(halt) = output.after_step(&done, &self.integrator, &rec.built, &mut rec.folder) else {
            return Ok(());
        };
        let sensor = match &halt {
            Halt::Sensor(e, _) => Some(e.clone()),
            Halt::Output(_) => None,
        };
        rec.halted = Some(halt);
        // The summary is written now: a script that stops here leaves a truthful folder.
        let _ = rec.finish(&self.integrator);
        match sensor {
            Some(error) => Err(Box::new(mbs::RetryFailure { error, retry: None })),
            None => Ok(()),
        }
    }

    /// The results folder of a simulation that keeps one ([`Simulation::writing_results`]):
    /// writes the rows still waiting, the report and the summary, and ends the results (the
    /// simulation can step on without them). `Ok(None)` when the simulation keeps no folder;
    /// the summary of the results otherwise. A file that could not be written, or the stop
    /// of a sensor that is not finite, is the error (the summary says `failed`).
    pub fn finish_results(&mut self) -> Result<Option<Summary>, BoxError> {
        let Some(mut rec) = self.recording.take() else {
            return Ok(None);
        };
        rec.finish(&self.integrator).map(Some)
    }

    /// Keeps `recording` as the results folder of the simulation.
    pub(crate) fn keep_results(&mut self, recording: Recording) {
        self.recording = Some(Box::new(recording));
    }

    /// The fixed steps planned to the end time when the simulation was started (`None`:
    /// adaptive steps).
    pub(crate) fn planned_steps(&self) -> Option<usize> {
        match self.stepping {
            mbs::Stepping::Fixed { .. } => Some(self.plan.planned),
            mbs::Stepping::Adaptive(_) => None,
        }
    }

    /// The integrator being stepped.
    pub fn integrator(&self) -> &mbs::Integrator<'static> {
        &self.integrator
    }

    /// Steps to the end time of the analysis under its step control, with `each` called
    /// after every step (`mbs::Integrator::run_to`).
    pub fn run_to<E>(
        &mut self,
        each: impl FnMut(&mbs::StepDone, &mbs::Integrator<'static>) -> Result<(), E>,
    ) -> Result<(mbs::StepTotals, Option<mbs::SolveError>), Box<mbs::Interrupted<E>>> {
        let run = self.integrator.run_to(self.t_end, &self.stepping, each);
        let taken = match &run {
            Ok((totals, _)) => totals.steps,
            Err(stop) => stop.totals.steps,
        };
        self.plan.taken += taken;
        run
    }

    /// Steps ([`Simulation::step`]) until the time reaches `t` (to a millionth of a step);
    /// returns the steps taken.
    pub fn advance_to(&mut self, t: f64) -> Result<usize, Box<mbs::RetryFailure>> {
        let mut n = 0;
        while self.time() < t - 1e-6 * self.dt {
            self.step()?;
            n += 1;
        }
        Ok(n)
    }

    /// The sensors of the study: names, `mbs` sensors and columns with units.
    pub fn sensors(&self) -> &[SensorGroup] {
        &self.groups
    }

    /// Every sensor at the current state: `values[g]` holds the columns of group `g`.
    pub fn read(&self) -> Result<Vec<Vec<f64>>, BoxError> {
        let mut record = self.integrator.system().sensor_record();
        self.integrator.record(&mut record)?;
        let row = record.rows.last().ok_or("no sensor row was recorded")?;
        Ok(self
            .columns
            .iter()
            .zip(&self.groups)
            .map(|(cols, g)| g.values(cols.iter().map(|&c| row[c])))
            .collect())
    }

    /// The columns of sensor `name` at the current state; the other sensors are not evaluated.
    pub fn sensor(&self, name: &str) -> Result<Vec<f64>, BoxError> {
        let Some(&g) = self.group_of.get(name) else {
            let names: Vec<String> = self.groups.iter().map(|g| g.name.clone()).collect();
            return Err(crate::input::source::unknown_reference("sensor", name, &names).into());
        };
        // Only this sensor's model sensors are evaluated (they are consecutive in the model).
        let values = self.integrator.sensor_values(&self.sensor_indices[g])?;
        // The group's columns are these values, in the same order.
        debug_assert_eq!(values.len(), self.columns[g].len());
        Ok(self.groups[g].values(values))
    }

    /// The state: time, coordinates, velocities and accelerations of the unknowns.
    pub fn state(&self) -> &State {
        self.integrator.state()
    }

    /// Position, orientation, velocity and acceleration of every node (`Model::nodes` order).
    pub fn node_motions(&self) -> Vec<NodeMotion> {
        self.integrator.system().node_motions(self.integrator.state())
    }

    /// The system being integrated.
    pub fn system(&self) -> &System {
        self.integrator.system()
    }

    /// The names of the point loads of the study (at nodes and at load points inside bodies).
    pub fn load_names(&self) -> Vec<&str> {
        self.loads.iter().map(|l| l.name.as_str()).collect()
    }

    /// The force and moment of point load `name` that can be set ([`Simulation::set_load`])
    /// with their values now \[N, N m, in the load's axes\]: a load at a node has those its
    /// study file gives, a load at a load point inside a body both.
    pub fn load_values(&self, name: &str) -> Result<Vec<(LoadKind, [f64; 3])>, BoxError> {
        let Some(l) = self.loads.iter().find(|l| l.name == name) else {
            let names: Vec<String> = self.loads.iter().map(|l| l.name.clone()).collect();
            return Err(crate::input::source::unknown_reference("load", name, &names).into());
        };
        let model = self.system().model();
        Ok(match &l.target {
            LoadTarget::Node(loads) => loads
                .iter()
                .map(|&(kind, index)| (kind, model.loads[index].value.into()))
                .collect(),
            LoadTarget::Body(index) => {
                let b = &model.body_loads[*index];
                vec![(LoadKind::Force, b.force.into()), (LoadKind::Moment, b.moment.into())]
            }
        })
    }

    /// Sets the force or moment `value` [N or N m, in the load's axes] of the point load
    /// `name`; from the next step the load is its time function times `value`. A load at a
    /// node has the force or moment its study file gives (even zero); a load at a load point
    /// inside a body has both.
    pub fn set_load(&mut self, name: &str, kind: LoadKind, value: [f64; 3]) -> Result<(), BoxError> {
        let Some(l) = self.loads.iter().find(|l| l.name == name) else {
            let names: Vec<String> = self.loads.iter().map(|l| l.name.clone()).collect();
            return Err(crate::input::source::unknown_reference("load", name, &names).into());
        };
        let target = l.target.clone();
        let system = self
            .integrator
            .system_mut()
            .ok_or("the simulation does not own its system")?;
        let value = nalgebra::Vector3::from(value);
        match target {
            LoadTarget::Node(loads) => {
                let Some(&(_, index)) = loads.iter().find(|(k, _)| *k == kind) else {
                    return Err(format!(
                        "load '{name}' has no {} (give it one in the study file, even zero)",
                        match kind {
                            LoadKind::Force => "force",
                            LoadKind::Moment => "moment",
                        }
                    )
                    .into());
                };
                system.set_load_value(index, value)?;
            }
            LoadTarget::Body(index) => system.set_body_load_value(index, kind, value)?,
        }
        Ok(())
    }

    /// The names of the study's actuators (`[[actuators]]`), in their order.
    pub fn actuator_names(&self) -> Vec<&str> {
        self.system()
            .model()
            .actuators
            .iter()
            .map(|a| a.name.as_str())
            .collect()
    }

    /// The index of actuator `name` in `Model::actuators`.
    fn actuator(&self, name: &str) -> Result<usize, BoxError> {
        let names = self.actuator_names();
        names.iter().position(|n| *n == name).ok_or_else(|| {
            let names: Vec<String> = names.iter().map(|n| n.to_string()).collect();
            crate::input::source::unknown_reference("actuator", name, &names).into()
        })
    }

    /// Holds actuator `name` at `effort` [N on a length, N m on an angle] in place of its
    /// `function` or `pid` from the next step on (a controller outside the study closes the
    /// loop); `None` releases it to its law again (a PID resumes from its integral, frozen
    /// while held). The `actuator-effort` sensors write the held value.
    pub fn set_actuator(&mut self, name: &str, effort: Option<f64>) -> Result<(), BoxError> {
        let index = self.actuator(name)?;
        let system = self
            .integrator
            .system_mut()
            .ok_or("the simulation does not own its system")?;
        system.set_actuator_effort(index, effort)?;
        Ok(())
    }

    /// The effort actuator `name` applies at the current state: the held value, or its law's.
    pub fn actuator_effort(&self, name: &str) -> Result<f64, BoxError> {
        let index = self.actuator(name)?;
        Ok(self.system().actuator_efforts(self.state())[index])
    }

    /// The effort actuator `name` is held at (`None`: its law acts).
    pub fn held_actuator(&self, name: &str) -> Result<Option<f64>, BoxError> {
        let index = self.actuator(name)?;
        Ok(self.system().held_actuator_effort(index))
    }

    /// Records the `mbs` sensors at the current state into `record`; a sensor value that is not
    /// finite is [`mbs::SolveError::NonFiniteSensor`] (the row stays in `record`).
    pub fn record(&self, record: &mut SensorRecord) -> Result<(), mbs::SolveError> {
        self.integrator.record(record)
    }
}

/// A simulation's point in time kept by [`Simulation::save`]: the integrator as it was (state,
/// algorithmic accelerations, factorised matrix, predictor history, the system with its load
/// values and held actuator efforts) and the plan of fixed steps.
#[derive(Clone)]
pub struct SavedSimulation {
    integrator: Integrator<'static>,
    dt: f64,
    plan: FixedPlan,
}

impl SavedSimulation {
    /// The time of the saved state.
    pub fn time(&self) -> f64 {
        self.integrator.state().time()
    }
}

impl Simulation {
    /// The whole state of the simulation, to go back to with [`Simulation::restore`]: the
    /// steps from a restored state are those from the saved one bit for bit (a co-simulation
    /// master that rejects a step and redoes it shorter, or compares two inputs).
    pub fn save(&self) -> SavedSimulation {
        SavedSimulation {
            integrator: self.integrator.clone(),
            dt: self.dt,
            plan: self.plan,
        }
    }

    /// Goes back to `saved` (of this simulation: a state saved from another one, of another
    /// mechanism, is refused). A simulation writing a results folder cannot go back (its
    /// files hold the steps taken).
    pub fn restore(&mut self, saved: &SavedSimulation) -> Result<(), BoxError> {
        if self.recording.is_some() {
            return Err("a simulation writing a results folder cannot go back to a saved state".into());
        }
        let (a, b) = (self.integrator.state(), saved.integrator.state());
        let same = a.velocity().len() == b.velocity().len()
            && self.integrator.system().model().sensors.len() == saved.integrator.system().model().sensors.len()
            && self.integrator.system().model().actuators.len() == saved.integrator.system().model().actuators.len();
        if !same {
            return Err("the saved state is of another mechanism".into());
        }
        self.integrator = saved.integrator.clone();
        self.dt = saved.dt;
        self.plan = saved.plan;
        Ok(())
    }
}

impl Drop for Simulation {
    /// A simulation dropped while it writes results ends them with a truthful summary.
    fn drop(&mut self) {
        if let Some(mut rec) = self.recording.take() {
            let _ = rec.finish(&self.integrator);
        }
    }
}

/// The first state of a `dynamic` analysis: the initial state as `[[initial]] start` chooses
/// (`choice`), or the final state of the analysis named in `start` (from an equilibrium: at
/// rest in its configuration at its time).
pub fn dynamic_start(sys: &System, start: Option<&mbs::State>, choice: StartChoice) -> mbs::State {
    match start {
        Some(s) if s.velocity().iter().all(|v| *v == 0.0) => sys.at_rest(s, s.time()),
        Some(s) => s.clone(),
        None => initial_state(sys, choice),
    }
}

/// The mechanism's state at t = 0 as `[[initial]] start` chooses: consistent (the start
/// analysis of `mbs::System::initial_state`) or at rest.
pub fn initial_state(sys: &System, choice: StartChoice) -> mbs::State {
    match choice {
        StartChoice::Consistent => sys.initial_state(),
        StartChoice::AtRest => sys.initial_state_at_rest(),
    }
}
