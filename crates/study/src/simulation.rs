//! A dynamic analysis of the mechanism stepped by the caller: [`Simulation::step`] or
//! [`Simulation::advance_to`], and between steps every sensor, the state and the node
//! motions can be read and the value of named loads changed. The `dynamic` analyses of a
//! study run (`crate::mechanism::run_analysis`) step the same type, so a script that steps a
//! simulation to the end gets the numbers the program writes.

use crate::error::BoxError;
use crate::mechanism::{BuiltMechanism, NamedLoad};
use crate::observer::SensorGroup;
use crate::validate::{MbsAnalysis, Study};
use mbs::{DynamicSettings, Integrator, LoadKind, NodeMotion, SensorRecord, State, StepReport, System};
use std::sync::Arc;

/// A generalized-α time integration of the study's mechanism (module docs).
pub struct Simulation {
    integrator: Integrator<'static>,
    groups: Vec<SensorGroup>,
    /// Per sensor group: its columns in a row of the `mbs` sensor record.
    columns: Vec<Vec<usize>>,
    loads: Vec<NamedLoad>,
    /// The step size and end time of the analysis.
    dt: f64,
    t_end: f64,
}

/// Per group: its columns in a row of `record` (the `mbs` sensors it is made of, in order).
pub fn sensor_columns(groups: &[SensorGroup], record: &SensorRecord) -> Result<Vec<Vec<usize>>, BoxError> {
    let mut offsets = Vec::new();
    let mut at = 0;
    for w in &record.widths {
        offsets.push(at);
        at += w;
    }
    let mut columns = Vec::new();
    for g in groups {
        let mut cols = Vec::new();
        for n in &g.mbs_names {
            let Some(k) = record.names.iter().position(|x| x == n) else {
                return Err(format!("sensor '{}': the model has no sensor '{n}'", g.name).into());
            };
            cols.extend(offsets[k]..offsets[k] + record.widths[k]);
        }
        columns.push(cols);
    }
    Ok(columns)
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
    } = spec
    else {
        return None;
    };
    let mut settings = DynamicSettings::new(*dt, *t_end, *rho_inf);
    settings.tolerance = *tolerance;
    settings.max_iterations = *max_iterations;
    settings.newton = *newton;
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
        let Some(settings) = dynamic_settings(spec, study.mechanism.output.every) else {
            return Err("a simulation steps a dynamic analysis; this one is not".into());
        };
        let (dt, t_end) = (settings.step, settings.end_time);
        let state = system.initial_state();
        let record = system.sensor_record();
        let columns = sensor_columns(&b.groups, &record)?;
        let integrator =
            Integrator::new_owned(system, state, settings).map_err(|e| format!("the initial accelerations: {e}"))?;
        Ok(Self {
            integrator,
            groups: b.groups.clone(),
            columns,
            loads: b.loads.clone(),
            dt,
            t_end,
        })
    }

    /// Builds the mechanism of `study` (bodies reduced through the cache of `options`) and
    /// starts its dynamic analysis called `analysis`.
    pub fn new(study: &Study, analysis: &str, options: &crate::run::Options) -> Result<Self, BoxError> {
        let Some(a) = study.analyses.iter().find(|a| a.name == analysis) else {
            let names: Vec<String> = study.analyses.iter().map(|a| a.name.clone()).collect();
            return Err(crate::source::unknown_reference("analysis", analysis, &names).into());
        };
        let crate::validate::AnalysisSpec::Mbs(spec) = &a.spec else {
            return Err(format!("analysis '{analysis}' is not an analysis of the mechanism").into());
        };
        let built = crate::mechanism::build(study, &options.cache_dir(study), &mut ())?;
        Self::start(study, &built, spec)
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

    /// Steps taken.
    pub fn steps(&self) -> usize {
        self.integrator.steps()
    }

    /// One time step. On failure the state stays at the last converged step and the error
    /// says where (time, step, residual).
    pub fn step(&mut self) -> Result<StepReport, mbs::SolveError> {
        self.integrator.step()
    }

    /// `n_steps` steps with `each` called after every one (`mbs::Integrator::run_steps`).
    pub fn run_steps<E>(
        &mut self,
        n_steps: usize,
        each: impl FnMut(usize, &mbs::Integrator<'static>, &StepReport) -> Result<(), E>,
    ) -> Result<(mbs::StepTotals, Option<mbs::SolveError>), E> {
        self.integrator.run_steps(n_steps, each)
    }

    /// The number of steps from the current time to the end time of the analysis.
    pub fn steps_to_end(&self) -> usize {
        self.integrator.steps_to(self.t_end)
    }

    /// Steps until the time reaches `t` (to a millionth of a step); returns the steps taken.
    pub fn advance_to(&mut self, t: f64) -> Result<usize, mbs::SolveError> {
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
            .map(|cols| cols.iter().map(|&c| row[c]).collect())
            .collect())
    }

    /// The columns of sensor `name` at the current state.
    pub fn sensor(&self, name: &str) -> Result<Vec<f64>, BoxError> {
        let Some(g) = self.groups.iter().position(|g| g.name == name) else {
            let names: Vec<String> = self.groups.iter().map(|g| g.name.clone()).collect();
            return Err(crate::source::unknown_reference("sensor", name, &names).into());
        };
        Ok(self.read()?.swap_remove(g))
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

    /// The names of the point loads of the study.
    pub fn load_names(&self) -> Vec<&str> {
        self.loads.iter().map(|l| l.name.as_str()).collect()
    }

    /// Sets the force or moment `value` [N or N m, in the load's axes] of the point load
    /// `name`; from the next step the load is its time function times `value`.
    pub fn set_load(&mut self, name: &str, kind: LoadKind, value: [f64; 3]) -> Result<(), BoxError> {
        let Some(l) = self.loads.iter().find(|l| l.name == name) else {
            let names: Vec<String> = self.loads.iter().map(|l| l.name.clone()).collect();
            return Err(crate::source::unknown_reference("load", name, &names).into());
        };
        let Some(&(_, index)) = l.loads.iter().find(|(k, _)| *k == kind) else {
            return Err(format!(
                "load '{name}' has no {} (give it one in the study file, even zero)",
                match kind {
                    LoadKind::Force => "force",
                    LoadKind::Moment => "moment",
                }
            )
            .into());
        };
        let system = self
            .integrator
            .system_mut()
            .ok_or("the simulation does not own its system")?;
        system.set_load_value(index, nalgebra::Vector3::from(value))?;
        Ok(())
    }

    /// Records the `mbs` sensors at the current state into `record`.
    pub fn record(&self, record: &mut SensorRecord) -> Result<(), BoxError> {
        Ok(self.integrator.record(record)?)
    }
}
