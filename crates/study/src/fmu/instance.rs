//! The instance of an FMU that a co-simulation master steps: the study read from the FMU's
//! resources, its parameters set, the mechanism built and the analysis started when the
//! initialisation ends, then stepped from communication point to communication point with
//! the inputs held over each step.

use super::{Manifest, Value, VarKind, VarType, Variable, MANIFEST};
use crate::error::BoxError;
use crate::input::document::Document;
use crate::run::{Options, SavedSimulation, Simulation};
use std::path::{Path, PathBuf};

/// An FMU instance (module docs). Every method that fails leaves the instance as it was
/// and returns the message the master's logger receives.
pub struct Instance {
    manifest: Manifest,
    resources: PathBuf,
    doc: Document,
    /// The value of every input and parameter (`None` for outputs), by value reference.
    values: Vec<Option<Value>>,
    /// Per variable: an input the master has set since it was last given to the simulation.
    dirty: Vec<bool>,
    /// Per actuator input: set by the master at least once (until then its law acts).
    held: Vec<bool>,
    /// The started simulation (after the initialisation), and the outputs at its time.
    sim: Option<Simulation>,
    outputs: Vec<f64>,
    /// The time the master starts at and stops at (`fmi2SetupExperiment`).
    start_time: Option<f64>,
    stop_time: Option<f64>,
}

/// The state of an [`Instance`] kept by [`Instance::save`].
#[derive(Clone)]
pub struct SavedInstance {
    sim: Option<SavedSimulation>,
    values: Vec<Option<Value>>,
    dirty: Vec<bool>,
    held: Vec<bool>,
    outputs: Vec<f64>,
}

/// `Ok` for a variable of type `ty`, else the error naming it.
fn check_type(v: &Variable, vr: u32, ty: VarType) -> Result<(), BoxError> {
    if v.ty == ty {
        return Ok(());
    }
    Err(format!(
        "value reference {vr} ('{}') is a {:?} variable, not a {ty:?} one",
        v.name, v.ty
    )
    .into())
}

impl Instance {
    /// Reads the FMU in the folder `resources` (its `flexmbs-fmu.json` and the study file);
    /// `guid`, when given, must be the FMU's.
    pub fn new(resources: &Path, guid: Option<&str>) -> Result<Self, BoxError> {
        let path = resources.join(MANIFEST);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            format!(
                "cannot read {}: {e} (the resources folder of the FMU is incomplete)",
                path.display()
            )
        })?;
        let manifest: Manifest =
            serde_json::from_str(&text).map_err(|e| format!("{}: not an FMU manifest: {e}", path.display()))?;
        if let Some(g) = guid {
            if g != manifest.guid {
                return Err(format!(
                    "the GUID {g} given is not the FMU's ({}): the modelDescription.xml is of another FMU",
                    manifest.guid
                )
                .into());
            }
        }
        let study = resources.join(&manifest.study);
        let doc = Document::open(&study)?;
        // Refused now rather than at the initialisation: a study that no longer validates.
        doc.study()?;
        let n = manifest.variables.len();
        let values = manifest.variables.iter().map(|v| v.start.clone()).collect();
        Ok(Self {
            manifest,
            resources: resources.to_path_buf(),
            doc,
            values,
            dirty: vec![false; n],
            held: vec![false; n],
            sim: None,
            outputs: Vec::new(),
            start_time: None,
            stop_time: None,
        })
    }

    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The started simulation, once initialised.
    pub fn simulation(&self) -> Option<&Simulation> {
        self.sim.as_ref()
    }

    /// The start and, if given, stop time of the master: a stop after the analysis' end time
    /// moves its end there.
    pub fn setup_experiment(&mut self, start: f64, stop: Option<f64>) -> Result<(), BoxError> {
        if self.sim.is_some() {
            return Err("the experiment is set up before the initialisation".into());
        }
        if !start.is_finite() || stop.is_some_and(|s| !s.is_finite() || s < start) {
            return Err(format!("the experiment's start {start} and stop {stop:?} are not an interval of time").into());
        }
        self.start_time = Some(start);
        self.stop_time = stop;
        Ok(())
    }

    fn variable(&self, vr: u32) -> Result<&Variable, BoxError> {
        self.manifest.variables.get(vr as usize).ok_or_else(|| {
            format!(
                "no variable has the value reference {vr} (the FMU has {}: 0 to {})",
                self.manifest.variables.len(),
                self.manifest.variables.len().saturating_sub(1)
            )
            .into()
        })
    }

    /// Builds the mechanism and starts the analysis, if not yet done: the end of the
    /// initialisation (or an output read during it).
    pub fn initialize(&mut self) -> Result<(), BoxError> {
        if self.sim.is_some() {
            return Ok(());
        }
        let mut doc = self.doc.clone();
        if let Some(stop) = self.stop_time {
            if stop > self.manifest.end_time {
                let path = format!("analyses.{}.t_end", self.manifest.analysis);
                doc.set(&path, &Value::Real(stop).toml())?;
            }
        }
        let study = doc.study()?;
        let options = Options {
            cache: Some(self.resources.join("cache")),
            ..Options::default()
        };
        let sim = Simulation::new(&study, &self.manifest.analysis, &options)?;
        if let Some(t0) = self.start_time {
            if (t0 - sim.time()).abs() > 1e-9 * sim.step_size() {
                return Err(format!(
                    "the experiment starts at t = {t0}, the analysis '{}' at t = {}",
                    self.manifest.analysis,
                    sim.time()
                )
                .into());
            }
        }
        // The sensors as exported (a parameter may not change what the outputs are).
        for v in &self.manifest.variables {
            if let VarKind::Output { group, column } = v.kind {
                let ok = sim
                    .sensors()
                    .get(group)
                    .is_some_and(|g| column < g.columns.len() && v.name.starts_with(&format!("{}.", g.name)));
                if !ok {
                    return Err(format!(
                        "output '{}' is no longer a sensor column of the study (a parameter changed the sensors)",
                        v.name
                    )
                    .into());
                }
            }
        }
        self.sim = Some(sim);
        if let Err(e) = self.apply_inputs().and_then(|()| self.read_outputs()) {
            self.sim = None;
            return Err(e);
        }
        Ok(())
    }

    /// Gives the inputs the master set to the simulation.
    fn apply_inputs(&mut self) -> Result<(), BoxError> {
        let Some(sim) = self.sim.as_mut() else {
            return Ok(());
        };
        let vars = &self.manifest.variables;
        for i in 0..vars.len() {
            if !self.dirty[i] {
                continue;
            }
            match &vars[i].kind {
                VarKind::Actuator { name } => {
                    let Some(Value::Real(u)) = self.values[i] else { continue };
                    sim.set_actuator(name, Some(u))?;
                }
                VarKind::Load { name, moment, .. } => {
                    // The three components of the vector, as set now.
                    let mut value = [0.0; 3];
                    for (j, v) in vars.iter().enumerate() {
                        if let VarKind::Load {
                            name: n,
                            moment: m,
                            axis,
                        } = &v.kind
                        {
                            if n == name && m == moment {
                                if let Some(Value::Real(x)) = self.values[j] {
                                    value[*axis] = x;
                                }
                                self.dirty[j] = false;
                            }
                        }
                    }
                    let kind = if *moment {
                        mbs::LoadKind::Moment
                    } else {
                        mbs::LoadKind::Force
                    };
                    sim.set_load(name, kind, value)?;
                }
                _ => {}
            }
            self.dirty[i] = false;
        }
        Ok(())
    }

    fn read_outputs(&mut self) -> Result<(), BoxError> {
        let Some(sim) = self.sim.as_ref() else {
            return Ok(());
        };
        let values = sim.read()?;
        self.outputs = self
            .manifest
            .variables
            .iter()
            .map(|v| match v.kind {
                VarKind::Output { group, column } => values[group][column],
                _ => f64::NAN,
            })
            .collect();
        Ok(())
    }

    /// Sets the value of `vr`: an input (held from the next communication step) or, before
    /// the initialisation ends, a parameter (the study checks it now).
    pub fn set(&mut self, vr: u32, value: Value) -> Result<(), BoxError> {
        let v = self.variable(vr)?.clone();
        let ty = match value {
            Value::Real(_) => VarType::Real,
            Value::Integer(_) => VarType::Integer,
            Value::Boolean(_) => VarType::Boolean,
            Value::String(_) => VarType::String,
        };
        check_type(&v, vr, ty)?;
        match &v.kind {
            VarKind::Output { .. } => Err(format!("'{}' is an output: the master cannot set it", v.name).into()),
            VarKind::Actuator { .. } | VarKind::Load { .. } => {
                let Value::Real(x) = value else {
                    unreachable!("checked: a Real")
                };
                if !x.is_finite() {
                    return Err(format!("input '{}' must be a finite number, not {x}", v.name).into());
                }
                self.values[vr as usize] = Some(value);
                self.dirty[vr as usize] = true;
                self.held[vr as usize] = true;
                Ok(())
            }
            VarKind::Parameter { path } => {
                if self.sim.is_some() {
                    return Err(format!(
                        "parameter '{}' is set before the initialisation ends (the mechanism is built then)",
                        v.name
                    )
                    .into());
                }
                if let Value::Real(x) = value {
                    if !x.is_finite() {
                        return Err(format!("parameter '{}' must be a finite number, not {x}", v.name).into());
                    }
                }
                self.doc
                    .set(path, &value.toml())
                    .map_err(|e| format!("parameter '{}' = {}: {e}", v.name, value.toml()))?;
                self.values[vr as usize] = Some(value);
                Ok(())
            }
        }
    }

    /// The value of `vr` as type `ty`; an output read during the initialisation starts the
    /// simulation (the parameters are then final).
    pub fn get(&mut self, vr: u32, ty: VarType) -> Result<Value, BoxError> {
        let v = self.variable(vr)?;
        check_type(v, vr, ty)?;
        if let VarKind::Output { .. } = v.kind {
            self.initialize()?;
            return Ok(Value::Real(self.outputs[vr as usize]));
        }
        self.values[vr as usize]
            .clone()
            .ok_or_else(|| format!("'{}' has no value", self.manifest.variables[vr as usize].name).into())
    }

    /// The time reached.
    pub fn time(&self) -> Option<f64> {
        self.sim.as_ref().map(Simulation::time)
    }

    /// One communication step from `t` to `t + h`: the inputs set are held, the analysis
    /// steps under its step control (several steps when `h` is longer than its step, the
    /// last one shortened to land on `t + h`), and the outputs are read at `t + h`. A step
    /// that fails leaves the simulation at the last converged step and says where.
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), BoxError> {
        if !(h > 0.0) || !t.is_finite() || !h.is_finite() {
            return Err(format!("a communication step needs a positive size (got {h} at t = {t})").into());
        }
        self.initialize()?;
        let analysis = self.manifest.analysis.clone();
        self.apply_inputs()?;
        let sim = self.sim.as_mut().ok_or("the FMU is not initialised")?;
        let now = sim.time();
        let dt = sim.step_size();
        if (t - now).abs() > 1e-9 * dt.max(now.abs() * 1e-3) {
            return Err(format!(
                "the communication step starts at t = {t}, the FMU is at t = {now} (restore a saved state to go back)"
            )
            .into());
        }
        let target = t + h;
        if target > sim.end_time() * (1.0 + 1e-12) + 1e-12 {
            return Err(format!(
                "t = {target} is after the end of the analysis '{analysis}' (t_end = {}; give the master's stop time at set-up (fmi2SetupExperiment, fmi3EnterInitializationMode), or a longer t_end)",
                sim.end_time()
            )
            .into());
        }
        let eps = 1e-9 * dt;
        loop {
            let time = sim.time();
            let remaining = target - time;
            if remaining <= eps {
                break;
            }
            let next = sim.integrator().step_size();
            let result = if remaining > next * (1.0 - 1e-9) {
                sim.step()
            } else {
                sim.step_by(remaining)
            };
            if let Err(f) = result {
                let at = sim.locate(&f.error).map(|l| format!(" ({l})")).unwrap_or_default();
                let message = format!(
                    "analysis '{analysis}': {}{at}; the FMU stays at t = {}",
                    f.error,
                    sim.time()
                );
                let _ = self.read_outputs();
                return Err(message.into());
            }
        }
        self.read_outputs()
    }

    /// The whole state, to go back to with [`Instance::restore`].
    pub fn save(&self) -> SavedInstance {
        SavedInstance {
            sim: self.sim.as_ref().map(Simulation::save),
            values: self.values.clone(),
            dirty: self.dirty.clone(),
            held: self.held.clone(),
            outputs: self.outputs.clone(),
        }
    }

    /// Goes back to `saved`: the steps from it are those from the saved state bit for bit.
    pub fn restore(&mut self, saved: &SavedInstance) -> Result<(), BoxError> {
        if saved.values.len() != self.values.len() {
            return Err("the saved state is of another FMU".into());
        }
        match (&mut self.sim, &saved.sim) {
            (Some(sim), Some(s)) => sim.restore(s)?,
            (_, None) => self.sim = None,
            (None, Some(_)) => {
                return Err("the FMU is not initialised; a state saved after the initialisation cannot be set".into())
            }
        }
        self.values.clone_from(&saved.values);
        self.dirty.clone_from(&saved.dirty);
        self.held.clone_from(&saved.held);
        self.outputs.clone_from(&saved.outputs);
        Ok(())
    }

    /// Back to the state after [`Instance::new`]: parameters and inputs at their start values.
    pub fn reset(&mut self) -> Result<(), BoxError> {
        let fresh = Self::new(&self.resources, Some(&self.manifest.guid.clone()))?;
        *self = fresh;
        Ok(())
    }
}
