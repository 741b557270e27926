//! A dynamic analysis of a study as an FMI 2.0 or FMI 3.0 Co-Simulation FMU (Functional
//! Mock-up Unit, [`FmiVersion`]): the variables it exposes ([`Variable`]), its
//! `modelDescription.xml`, the archive
//! (`export`), and the instance a master steps ([`Instance`]). No `unsafe` here: the C
//! functions of the FMI standard are the crate `flexmbs-fmu`, a thin boundary that checks
//! every pointer and hands the checked values to an [`Instance`].
//!
//! | item | what it is |
//! |---|---|
//! | inputs | every actuator's effort (held over a communication step; until the master sets it the actuator follows its law), every point load's force and moment components (start: the study's values) |
//! | outputs | every column of every sensor, with its unit |
//! | parameters | the study values named by `[fmu] parameters` (key paths), set before the initialisation ends; a value the study refuses is refused at set time with its message |
//!
//! The archive carries the study file and the files it names (meshes, reduced bodies,
//! matrices, tables) under `resources/files/`, the reduced-body cache under
//! `resources/cache/`, and `resources/flexmbs-fmu.json` (the [`Manifest`]: the study file,
//! the analysis, the variables), so that it runs without the program.

pub mod instance;
pub mod zip;

pub use instance::{Instance, SavedInstance};

use crate::error::BoxError;
use crate::input::document::Document;
use crate::input::validate::Study;
use crate::run::{Options, Simulation};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

/// The file in the FMU's `resources` folder that describes it to the instance.
pub const MANIFEST: &str = "flexmbs-fmu.json";

/// The version of the FMI standard an FMU is written for. An archive holds one
/// `modelDescription.xml`, so one version per FMU; the library it carries exports the
/// functions of both (their names do not clash), so the two differ only in the description
/// and the folder of the binary.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum FmiVersion {
    /// FMI 2.0 Co-Simulation, the version most masters import.
    #[default]
    V2,
    /// FMI 3.0 Co-Simulation.
    V3,
}

impl FmiVersion {
    /// `"2"`, `"2.0"`, `"3"` or `"3.0"`.
    pub fn parse(text: &str) -> Result<Self, BoxError> {
        match text.trim() {
            "2" | "2.0" => Ok(Self::V2),
            "3" | "3.0" => Ok(Self::V3),
            other => Err(format!("the FMI version is 2 or 3, not '{other}'").into()),
        }
    }

    /// `"2.0"` or `"3.0"`.
    pub fn name(self) -> &'static str {
        match self {
            Self::V2 => "2.0",
            Self::V3 => "3.0",
        }
    }

    /// The folder of the archive that holds the binary for 64-bit Linux.
    pub fn binaries(self) -> &'static str {
        match self {
            Self::V2 => "binaries/linux64",
            Self::V3 => "binaries/x86_64-linux",
        }
    }
}

/// The FMI type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum VarType {
    Real,
    Integer,
    Boolean,
    String,
}

/// What a variable is in the study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum VarKind {
    /// Column `column` of sensor group `group` (`Simulation::sensors` order).
    Output { group: usize, column: usize },
    /// The effort of actuator `name`.
    Actuator { name: String },
    /// Component `axis` (0, 1, 2) of the force (`moment` false) or moment of point load `name`.
    Load { name: String, moment: bool, axis: usize },
    /// The study value at key path `path` (`[fmu] parameters`).
    Parameter { path: String },
}

/// A value of a parameter or input, by its FMI type.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Value {
    Real(f64),
    Integer(i32),
    Boolean(bool),
    String(String),
}

impl Value {
    /// The value as TOML text, as `Document::set` takes it.
    pub fn toml(&self) -> String {
        match self {
            Value::Real(x) => {
                // `{:?}` keeps every digit and a decimal point or exponent (TOML floats need one).
                let s = format!("{x:?}");
                if s.contains('.') || s.contains('e') || s.contains("inf") || s.contains("NaN") {
                    s
                } else {
                    format!("{s}.0")
                }
            }
            Value::Integer(i) => i.to_string(),
            Value::Boolean(b) => b.to_string(),
            Value::String(s) => toml_edit::Value::from(s.as_str()).to_string(),
        }
    }

    fn xml(&self) -> String {
        match self {
            Value::Real(x) => format!("{x:?}"),
            Value::Integer(i) => i.to_string(),
            Value::Boolean(b) => b.to_string(),
            Value::String(s) => xml_escape(s),
        }
    }
}

/// One variable of the FMU; its value reference is its index in [`Manifest::variables`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Variable {
    pub name: String,
    pub kind: VarKind,
    pub ty: VarType,
    pub unit: Option<String>,
    pub description: String,
    /// Inputs and parameters: the value before the master sets one.
    pub start: Option<Value>,
}

impl Variable {
    pub fn causality(&self) -> &'static str {
        match self.kind {
            VarKind::Output { .. } => "output",
            VarKind::Actuator { .. } | VarKind::Load { .. } => "input",
            VarKind::Parameter { .. } => "parameter",
        }
    }
}

/// What the instance reads from `resources/flexmbs-fmu.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Manifest {
    /// The FMU's `guid` (a hash of the study text, the analysis and the variables).
    pub guid: String,
    pub model_identifier: String,
    /// The study file, relative to the resources folder.
    pub study: String,
    pub analysis: String,
    /// The start and end time and the step of the analysis (the default experiment).
    pub start_time: f64,
    pub end_time: f64,
    pub step: f64,
    pub variables: Vec<Variable>,
}

/// A sensor column `"deflection [m]"` as its name and unit.
fn split_column(column: &str) -> (String, Option<String>) {
    match column.rsplit_once(" [") {
        Some((name, unit)) if unit.ends_with(']') => {
            let unit = &unit[..unit.len() - 1];
            (name.to_string(), (!unit.is_empty()).then(|| unit.to_string()))
        }
        _ => (column.to_string(), None),
    }
}

/// The variables of the FMU of `analysis`, from the simulation `sim` started from `study`
/// (read from `doc`).
pub fn variables(study: &Study, doc: &Document, sim: &Simulation) -> Result<Vec<Variable>, BoxError> {
    let mut vars = Vec::new();
    for (g, group) in sim.sensors().iter().enumerate() {
        for (c, column) in group.columns.iter().enumerate() {
            let (col, unit) = split_column(column);
            vars.push(Variable {
                // `rate 0 [rad/s]` of sensor `rate` is `rate.rate_0`: no spaces in the names
                // of ports and signals.
                name: format!("{}.{}", group.name, col.replace(' ', "_")),
                kind: VarKind::Output { group: g, column: c },
                ty: VarType::Real,
                unit,
                description: format!("sensor '{}': {col}", group.name),
                start: None,
            });
        }
    }
    let m = &study.mechanism;
    for name in sim.actuator_names() {
        let unit = m
            .actuators
            .iter()
            .find(|a| a.name == name)
            .map(|a| {
                if crate::input::validate::mechanism::joint_is_angle(m, a.joint, a.coordinate) {
                    "N m"
                } else {
                    "N"
                }
            })
            .unwrap_or("N");
        vars.push(Variable {
            name: name.to_string(),
            kind: VarKind::Actuator { name: name.to_string() },
            ty: VarType::Real,
            unit: Some(unit.to_string()),
            description: format!(
                "effort of actuator '{name}', held over a communication step (its law of the study acts until the first value is set)"
            ),
            start: Some(Value::Real(0.0)),
        });
    }
    for name in sim.load_names() {
        for (kind, value) in sim.load_values(name)? {
            let moment = matches!(kind, mbs::LoadKind::Moment);
            let (what, unit) = if moment { ("moment", "N m") } else { ("force", "N") };
            for (axis, x) in ["x", "y", "z"].iter().enumerate() {
                vars.push(Variable {
                    name: format!("{name}.{what}.{x}"),
                    kind: VarKind::Load {
                        name: name.to_string(),
                        moment,
                        axis,
                    },
                    ty: VarType::Real,
                    unit: Some(unit.to_string()),
                    description: format!(
                        "{what} of load '{name}' along {x} (times its time function), held over a communication step"
                    ),
                    start: Some(Value::Real(value[axis])),
                });
            }
        }
    }
    for path in &study.fmu_parameters {
        let value = doc.get(path).map_err(|e| format!("[fmu] parameters: '{path}': {e}"))?;
        let start = match value {
            serde_json::Value::Bool(b) => Value::Boolean(b),
            serde_json::Value::Number(n) if n.is_i64() => Value::Integer(
                i32::try_from(n.as_i64().unwrap_or_default())
                    .map_err(|_| format!("[fmu] parameters: '{path}' = {n} does not fit an FMI Integer"))?,
            ),
            serde_json::Value::Number(n) => Value::Real(n.as_f64().unwrap_or(f64::NAN)),
            serde_json::Value::String(s) => Value::String(s),
            other => {
                return Err(format!(
                    "[fmu] parameters: '{path}' is {other}; a parameter is a number, a boolean or a string"
                )
                .into())
            }
        };
        let ty = match start {
            Value::Real(_) => VarType::Real,
            Value::Integer(_) => VarType::Integer,
            Value::Boolean(_) => VarType::Boolean,
            Value::String(_) => VarType::String,
        };
        vars.push(Variable {
            name: path.clone(),
            kind: VarKind::Parameter { path: path.clone() },
            ty,
            unit: None,
            description: format!("study value {path}"),
            start: Some(start),
        });
    }
    let mut seen = BTreeSet::new();
    for v in &vars {
        if v.name == "time" {
            return Err(format!(
                "the FMU's independent variable is called 'time'; {} cannot have that name: rename it in the study",
                v.description
            )
            .into());
        }
        if !seen.insert(v.name.as_str()) {
            return Err(format!(
                "two FMU variables are called '{}' (a sensor column, an actuator, a load component or a parameter): rename one in the study",
                v.name
            )
            .into());
        }
    }
    Ok(vars)
}

/// A C identifier from the study's file name (`slider_crank`).
pub fn model_identifier(study_path: &Path) -> String {
    let stem = study_path.file_stem().and_then(|s| s.to_str()).unwrap_or("model");
    let mut id: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic()) {
        id.insert_str(0, "fmu_");
    }
    id
}

/// A variable's `variability` and its `initial` attribute (with its leading space, or empty),
/// the same in FMI 2.0 and 3.0: outputs are calculated, inputs have no `initial`, parameters
/// are fixed and exact; a variable that is not a real is fixed.
fn variability_and_initial(v: &Variable) -> (&'static str, String) {
    let (variability, initial) = match v.kind {
        VarKind::Output { .. } => ("continuous", Some("calculated")),
        VarKind::Actuator { .. } | VarKind::Load { .. } => ("continuous", None),
        VarKind::Parameter { .. } => ("fixed", Some("exact")),
    };
    let variability = if v.ty == VarType::Real { variability } else { "fixed" };
    (
        variability,
        initial.map(|i| format!(r#" initial="{i}""#)).unwrap_or_default(),
    )
}

fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// The `modelDescription.xml` of the FMU `m` (FMI 2.0 Co-Simulation).
pub fn model_description(m: &Manifest, model_name: &str, description: &str) -> String {
    use std::fmt::Write;
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" generationTool="flexmbs {}" variableNamingConvention="flat" numberOfEventIndicators="0">"#,
        xml_escape(model_name),
        m.guid,
        xml_escape(description),
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false" maxOutputDerivativeOrder="0" canRunAsynchronuously="false" canBeInstantiatedOnlyOncePerProcess="false" canNotUseMemoryManagementFunctions="true" canGetAndSetFMUstate="true" canSerializeFMUstate="false" providesDirectionalDerivative="false"/>"#,
        m.model_identifier
    );
    let units: BTreeSet<&str> = m.variables.iter().filter_map(|v| v.unit.as_deref()).collect();
    if !units.is_empty() {
        let _ = writeln!(x, "  <UnitDefinitions>");
        for u in units {
            let _ = writeln!(x, r#"    <Unit name="{}"/>"#, xml_escape(u));
        }
        let _ = writeln!(x, "  </UnitDefinitions>");
    }
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="{:?}" stopTime="{:?}" stepSize="{:?}"/>"#,
        m.start_time, m.end_time, m.step
    );
    let _ = writeln!(x, "  <ModelVariables>");
    for (vr, v) in m.variables.iter().enumerate() {
        let (variability, initial) = variability_and_initial(v);
        let _ = writeln!(x, r#"    <!-- index {} -->"#, vr + 1);
        let _ = writeln!(
            x,
            r#"    <ScalarVariable name="{}" valueReference="{vr}" description="{}" causality="{}" variability="{variability}"{initial}>"#,
            xml_escape(&v.name),
            xml_escape(&v.description),
            v.causality()
        );
        let ty = match v.ty {
            VarType::Real => "Real",
            VarType::Integer => "Integer",
            VarType::Boolean => "Boolean",
            VarType::String => "String",
        };
        let unit = v
            .unit
            .as_ref()
            .map(|u| format!(r#" unit="{}""#, xml_escape(u)))
            .unwrap_or_default();
        let start = v
            .start
            .as_ref()
            .map(|s| format!(r#" start="{}""#, s.xml()))
            .unwrap_or_default();
        let _ = writeln!(x, "      <{ty}{unit}{start}/>");
        let _ = writeln!(x, "    </ScalarVariable>");
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let outputs: Vec<usize> = m
        .variables
        .iter()
        .enumerate()
        .filter(|(_, v)| matches!(v.kind, VarKind::Output { .. }))
        .map(|(i, _)| i + 1)
        .collect();
    if !outputs.is_empty() {
        let _ = writeln!(x, "    <Outputs>");
        for i in &outputs {
            let _ = writeln!(x, r#"      <Unknown index="{i}"/>"#);
        }
        let _ = writeln!(x, "    </Outputs>");
        let _ = writeln!(x, "    <InitialUnknowns>");
        for i in &outputs {
            let _ = writeln!(x, r#"      <Unknown index="{i}"/>"#);
        }
        let _ = writeln!(x, "    </InitialUnknowns>");
    }
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

/// The value reference of the independent variable `time` of an FMI 3.0 FMU: the one after
/// the variables'.
pub fn time_reference(m: &Manifest) -> u32 {
    u32::try_from(m.variables.len()).unwrap_or(u32::MAX)
}

/// The `modelDescription.xml` of the FMU `m` (FMI 3.0 Co-Simulation): the variables by
/// their value references, Reals as `Float64`, Integers as `Int32`; its instantiation token
/// is the manifest's `guid`. FMI 3.0 asks for the independent variable: `time` \[s\], value
/// reference the number of variables ([`time_reference`]).
pub fn model_description_3(m: &Manifest, model_name: &str, description: &str) -> String {
    use std::fmt::Write;
    let mut x = String::new();
    let _ = writeln!(x, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        x,
        r#"<fmiModelDescription fmiVersion="3.0" modelName="{}" instantiationToken="{}" description="{}" generationTool="flexmbs {}" variableNamingConvention="flat">"#,
        xml_escape(model_name),
        m.guid,
        xml_escape(description),
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        x,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUState="true" canSerializeFMUState="false" providesDirectionalDerivatives="false" providesAdjointDerivatives="false" canBeInstantiatedOnlyOncePerProcess="false" maxOutputDerivativeOrder="0" providesIntermediateUpdate="false" mightReturnEarlyFromDoStep="false" canReturnEarlyAfterIntermediateUpdate="false" hasEventMode="false" providesEvaluateDiscreteStates="false"/>"#,
        m.model_identifier
    );
    let mut units: BTreeSet<&str> = m.variables.iter().filter_map(|v| v.unit.as_deref()).collect();
    units.insert("s");
    let _ = writeln!(x, "  <UnitDefinitions>");
    for u in units {
        let _ = writeln!(x, r#"    <Unit name="{}"/>"#, xml_escape(u));
    }
    let _ = writeln!(x, "  </UnitDefinitions>");
    let _ = writeln!(
        x,
        r#"  <DefaultExperiment startTime="{:?}" stopTime="{:?}" stepSize="{:?}"/>"#,
        m.start_time, m.end_time, m.step
    );
    let _ = writeln!(x, "  <ModelVariables>");
    let _ = writeln!(
        x,
        r#"    <Float64 name="time" valueReference="{}" description="time of the analysis" causality="independent" variability="continuous" unit="s"/>"#,
        time_reference(m)
    );
    for (vr, v) in m.variables.iter().enumerate() {
        let (variability, initial) = variability_and_initial(v);
        let ty = match v.ty {
            VarType::Real => "Float64",
            VarType::Integer => "Int32",
            VarType::Boolean => "Boolean",
            VarType::String => "String",
        };
        let unit = v
            .unit
            .as_ref()
            .map(|u| format!(r#" unit="{}""#, xml_escape(u)))
            .unwrap_or_default();
        let head = format!(
            r#"    <{ty} name="{}" valueReference="{vr}" description="{}" causality="{}" variability="{variability}"{initial}"#,
            xml_escape(&v.name),
            xml_escape(&v.description),
            v.causality()
        );
        match (&v.start, v.ty) {
            // A String's start value is an element of its own.
            (Some(s), VarType::String) => {
                let _ = writeln!(x, "{head}>");
                let _ = writeln!(x, r#"      <Start value="{}"/>"#, s.xml());
                let _ = writeln!(x, "    </String>");
            }
            (Some(s), _) => {
                let _ = writeln!(x, r#"{head}{unit} start="{}"/>"#, s.xml());
            }
            (None, _) => {
                let _ = writeln!(x, "{head}{unit}/>");
            }
        }
    }
    let _ = writeln!(x, "  </ModelVariables>");
    let _ = writeln!(x, "  <ModelStructure>");
    let outputs: Vec<usize> = m
        .variables
        .iter()
        .enumerate()
        .filter(|(_, v)| matches!(v.kind, VarKind::Output { .. }))
        .map(|(i, _)| i)
        .collect();
    for i in &outputs {
        let _ = writeln!(x, r#"    <Output valueReference="{i}"/>"#);
    }
    for i in &outputs {
        let _ = writeln!(x, r#"    <InitialUnknown valueReference="{i}"/>"#);
    }
    let _ = writeln!(x, "  </ModelStructure>");
    let _ = writeln!(x, "</fmiModelDescription>");
    x
}

/// The files a study names (meshes, reduced bodies, matrices, tables): every string of the
/// study that is the path of a file, relative to the study's folder.
fn named_files(study_path: &Path, text: &str) -> Result<Vec<PathBuf>, BoxError> {
    let table: toml::Table = toml::from_str(text)?;
    let dir = study_path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut found = BTreeSet::new();
    fn walk(v: &toml::Value, dir: &Path, found: &mut BTreeSet<PathBuf>) {
        match v {
            toml::Value::String(s) if !s.is_empty() => {
                let p = dir.join(s);
                if p.is_file() {
                    found.insert(p);
                }
            }
            toml::Value::Array(a) => a.iter().for_each(|v| walk(v, dir, found)),
            toml::Value::Table(t) => t.values().for_each(|v| walk(v, dir, found)),
            _ => {}
        }
    }
    walk(&toml::Value::Table(table), &dir, &mut found);
    Ok(found.into_iter().collect())
}

/// `path` relative to `root` with `..` and `.` resolved lexically (both made absolute).
fn lexical(path: &Path) -> Result<PathBuf, BoxError> {
    let abs = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()?.join(path)
    };
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    Ok(out)
}

/// The FMU written by [`export`].
#[derive(Clone, Debug)]
pub struct Exported {
    pub path: PathBuf,
    pub analysis: String,
    pub model_identifier: String,
    pub variables: Vec<Variable>,
    pub version: FmiVersion,
    /// The files of the archive, with their sizes.
    pub files: Vec<(String, usize)>,
}

/// Writes the FMU of analysis `analysis` (or the study's only dynamic one) of the study file
/// `study_path` to `out`, with the shared library `library` (the build of `flexmbs-fmu`) as
/// its binary. Builds the mechanism and starts the analysis once (its bodies reduced into the
/// archive's cache), so that a study the FMU could not start is refused here.
pub fn export(
    study_path: &Path,
    analysis: Option<&str>,
    version: FmiVersion,
    library: &Path,
    out: &Path,
) -> Result<Exported, BoxError> {
    export_document(&Document::open(study_path)?, analysis, version, library, out)
}

/// [`export`] of a study held in memory (its path anchors the files it names).
pub fn export_document(
    doc: &Document,
    analysis: Option<&str>,
    version: FmiVersion,
    library: &Path,
    out: &Path,
) -> Result<Exported, BoxError> {
    let study = doc.study()?;
    let analysis = study.dynamic_analysis(analysis)?;
    let binary = std::fs::read(library).map_err(|e| {
        format!(
            "cannot read the FMU library {}: {e}; build it with `cargo build --release -p flexmbs-fmu`",
            library.display()
        )
    })?;
    // The bodies reduced into a cache of its own, which the archive carries.
    let cache = std::env::temp_dir().join(format!(
        "flexmbs-fmu-cache-{}-{}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or_default()
    ));
    let result = export_with_cache(doc, &study, &analysis, version, binary, out, &cache);
    let _ = std::fs::remove_dir_all(&cache);
    result
}

fn export_with_cache(
    doc: &Document,
    study: &Study,
    analysis: &str,
    version: FmiVersion,
    binary: Vec<u8>,
    out: &Path,
    cache: &Path,
) -> Result<Exported, BoxError> {
    let options = Options {
        cache: Some(cache.to_path_buf()),
        ..Options::default()
    };
    let sim = Simulation::new(study, analysis, &options)?;
    let variables = variables(study, doc, &sim)?;
    let study_path = &study.source.path;
    let text = doc.text();
    // The study and the files it names, under the folder that holds them all.
    let files = named_files(study_path, &text)?;
    let study_abs = lexical(study_path)?;
    let mut root = study_abs.parent().map(Path::to_path_buf).unwrap_or_default();
    for f in &files {
        let f = lexical(f)?;
        while !f.starts_with(&root) {
            if !root.pop() {
                break;
            }
        }
    }
    let rel = |p: &Path| -> Result<String, BoxError> {
        let p = lexical(p)?;
        let r = p
            .strip_prefix(&root)
            .map_err(|_| format!("{} is outside {}", p.display(), root.display()))?;
        Ok(r.components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/"))
    };
    let model_identifier = model_identifier(study_path);
    let study_rel = format!("files/{}", rel(study_path)?);
    let mut hasher = <sha2::Sha256 as sha2::Digest>::new();
    sha2::Digest::update(&mut hasher, text.as_bytes());
    sha2::Digest::update(&mut hasher, analysis.as_bytes());
    sha2::Digest::update(&mut hasher, serde_json::to_string(&variables)?.as_bytes());
    let h = sha2::Digest::finalize(hasher);
    let hex: String = h.iter().map(|b| format!("{b:02x}")).collect();
    let guid = format!(
        "{{{}-{}-{}-{}-{}}}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    );
    let manifest = Manifest {
        guid,
        model_identifier: model_identifier.clone(),
        study: study_rel.clone(),
        analysis: analysis.to_string(),
        start_time: sim.time(),
        end_time: sim.end_time(),
        step: sim.step_size(),
        variables: variables.clone(),
    };
    let title = study.title.clone().unwrap_or_else(|| model_identifier.clone());
    let description = format!("{title}: dynamic analysis '{analysis}' (flexmbs)");
    let xml = match version {
        FmiVersion::V2 => model_description(&manifest, &model_identifier, &description),
        FmiVersion::V3 => model_description_3(&manifest, &model_identifier, &description),
    };
    let mut entries: Vec<(String, Vec<u8>)> = vec![
        ("modelDescription.xml".into(), xml.into_bytes()),
        (format!("{}/{model_identifier}.so", version.binaries()), binary),
        (
            format!("resources/{MANIFEST}"),
            serde_json::to_string_pretty(&manifest)?.into_bytes(),
        ),
        (format!("resources/{study_rel}"), text.into_bytes()),
    ];
    for f in &files {
        let bytes = std::fs::read(f).map_err(|e| format!("cannot read {}: {e}", f.display()))?;
        entries.push((format!("resources/files/{}", rel(f)?), bytes));
    }
    // The reduced bodies, so that the FMU does not reduce them again.
    let mut stack = vec![cache.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(read) = std::fs::read_dir(&d) else { continue };
        let mut paths: Vec<PathBuf> = read.filter_map(|e| e.ok().map(|e| e.path())).collect();
        paths.sort();
        for p in paths {
            if p.is_dir() {
                stack.push(p);
            } else {
                let r = p.strip_prefix(cache)?;
                let r: Vec<String> = r
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                entries.push((format!("resources/cache/{}", r.join("/")), std::fs::read(&p)?));
            }
        }
    }
    let listing = entries.iter().map(|(n, b)| (n.clone(), b.len())).collect();
    zip::write(out, &entries).map_err(|e| format!("cannot write {}: {e}", out.display()))?;
    Ok(Exported {
        path: out.to_path_buf(),
        analysis: analysis.to_string(),
        model_identifier,
        variables,
        version,
        files: listing,
    })
}

/// The shared library of `flexmbs-fmu` a program exports FMUs with: `$FLEXMBS_FMU_LIBRARY`,
/// else `libflexmbs_fmu.so` next to the running program (where cargo builds both).
pub fn library_path() -> Result<PathBuf, BoxError> {
    if let Some(p) = std::env::var_os("FLEXMBS_FMU_LIBRARY") {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        return Err(format!(
            "FLEXMBS_FMU_LIBRARY names {}, which is not a file; build the library with `cargo build --release -p flexmbs-fmu` (target/release/libflexmbs_fmu.so)",
            p.display()
        )
        .into());
    }
    let exe = std::env::current_exe()?;
    let mut tried = Vec::new();
    if let Some(dir) = exe.parent() {
        for d in [Some(dir), dir.parent()].into_iter().flatten() {
            let p = d.join("libflexmbs_fmu.so");
            if p.is_file() {
                return Ok(p);
            }
            tried.push(p.display().to_string());
        }
    }
    Err(format!(
        "the FMU library libflexmbs_fmu.so is not next to the program (looked for {}); build it with `cargo build --release -p flexmbs-fmu`, or name it with FLEXMBS_FMU_LIBRARY",
        tried.join(", ")
    )
    .into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_split_into_name_and_unit() {
        assert_eq!(split_column("deflection [m]"), ("deflection".into(), Some("m".into())));
        assert_eq!(split_column("effort [N m]"), ("effort".into(), Some("N m".into())));
        assert_eq!(split_column("node"), ("node".into(), None));
    }

    #[test]
    fn values_as_toml_text() {
        assert_eq!(Value::Real(2.0).toml(), "2.0");
        assert_eq!(Value::Real(2e11).toml(), "200000000000.0");
        assert_eq!(Value::Real(1e-4).toml(), "0.0001");
        assert_eq!(Value::Integer(4).toml(), "4");
        assert_eq!(model_identifier(Path::new("x/2-link arm.toml")), "fmu_2_link_arm");
    }
}
