//! Validation: from the raw [`StudyFile`] to a [`Study`] in which every reference is
//! resolved (materials, sections, parts, node sets, interfaces), every value is checked
//! against its range, and every part's FE model is built, before any analysis runs.
//!
//! The validator collects all the errors it finds rather than stopping at the first, and
//! each names its file, line, column and key ([`crate::input::source`]). A reference to something
//! undefined lists the close matches. Nothing here panics on any input: the property test
//! `tests/cli.rs::random_and_mutated_study_files_fail_cleanly` feeds it random and mutated
//! files.

// Material constants keep their physical names (E, G), as in fe_model.
#![allow(non_snake_case)]

use crate::input::keys;
use crate::input::part::{
    mass_kind, model_size, InterfaceSpec, InterfaceTarget, LoadSpec, NodeRef, Part, PartKind, Reduction, SupportSpec,
};
use crate::input::schema::*;
use crate::input::source::{
    close_matches, quote_list, suggestions, unknown_reference, KeyPath, Source, StudyError, StudyErrors,
};
use fe_model::generate::{beam_arc, frame, straight_beam, Member};
use fe_model::{
    BeamProperties, BeamSection, BeamTheory, CellKind, DofMask, FeError, FeModel, IsotropicMaterial, NodeId,
    SpiderKind, DOF_NAMES,
};
use nalgebra::{Point3, Vector3};
use reduction::ModeSelection;
use std::collections::{HashMap, HashSet};
use std::path::Path;

pub mod mechanism;
pub use mechanism::{MbsAnalysis, Mechanism};

/// Largest number of solid cells a generated box may have (six tets per brick count six).
pub const MAX_BOX_CELLS: usize = 2_000_000;

/// A modal analysis's eigensolver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Solver {
    /// Dense up to [`DENSE_AUTO_LIMIT`] free dofs, sparse above.
    Auto,
    Dense,
    Sparse,
}

/// `Solver::Auto` uses the dense path up to this many free dofs.
pub const DENSE_AUTO_LIMIT: usize = 1500;

#[derive(Clone, Debug)]
pub enum AnalysisSpec {
    /// Linear statics of the part with supports and nodal loads.
    Static {
        supports: Vec<SupportSpec>,
        loads: Vec<LoadSpec>,
    },
    /// The lowest `modes` modes of the part (free, or on supports).
    Modal {
        modes: usize,
        solver: Solver,
        supports: Vec<SupportSpec>,
    },
    /// Craig-Bampton reduction of the part to a reduced-body file.
    Reduce,
    /// An analysis of the mechanism (equilibrium, dynamic, linearized).
    Mbs(MbsAnalysis),
}

#[derive(Clone, Debug)]
pub struct Analysis {
    /// Unique; names the results folder.
    pub name: String,
    /// `analyses[i]`, for messages.
    pub path: KeyPath,
    /// Index into [`Study::parts`]; `None` for the analyses of the mechanism.
    pub part: Option<usize>,
    pub spec: AnalysisSpec,
    /// `start`: the earlier analysis of the mechanism whose final state this one starts from
    /// (index into [`Study::analyses`]).
    pub start: Option<usize>,
}

impl Analysis {
    pub fn kind_name(&self) -> &'static str {
        match self.spec {
            AnalysisSpec::Static { .. } => "static",
            AnalysisSpec::Modal { .. } => "modal",
            AnalysisSpec::Reduce => "reduce",
            AnalysisSpec::Mbs(MbsAnalysis::Equilibrium { .. }) => "equilibrium",
            AnalysisSpec::Mbs(MbsAnalysis::Dynamic { .. }) => "dynamic",
            AnalysisSpec::Mbs(MbsAnalysis::Linearized { .. }) => "linearized",
            AnalysisSpec::Mbs(MbsAnalysis::Buckling { .. }) => "buckling",
        }
    }
}

/// A validated study.
#[derive(Clone, Debug)]
pub struct Study {
    pub source: Source,
    pub title: Option<String>,
    pub parts: Vec<Part>,
    pub analyses: Vec<Analysis>,
    /// The mechanism (empty without `[[bodies]]`, `[[rigid_bodies]]`, `[[point_masses]]`).
    pub mechanism: Mechanism,
    /// Rendered warnings (suspicious units), printed on stderr.
    pub warnings: Vec<String>,
    /// `[fmu] parameters`: key paths of the values the study's FMU exposes as parameters.
    pub fmu_parameters: Vec<String>,
}

impl Study {
    /// `file:line:col` of the value at `path`, for messages about runtime failures.
    pub fn location(&self, path: &KeyPath) -> String {
        self.at(path).to_string()
    }

    /// File, line, column and key path of the value at `path` (no line when the path is
    /// not in the file).
    pub fn at(&self, path: &KeyPath) -> crate::error::Location {
        let line_column = self
            .source
            .locate(path)
            .map(|span| crate::input::source::line_column(&self.source.text, span.start));
        crate::error::Location {
            file: self.source.path.clone(),
            line_column,
            key: path.clone(),
        }
    }

    /// The part called `name`, or an error with the close matches.
    pub fn part(&self, name: &str) -> Result<usize, String> {
        self.parts.iter().position(|p| p.name == name).ok_or_else(|| {
            let names: Vec<String> = self.parts.iter().map(|p| p.name.clone()).collect();
            format!(
                "{} in {}",
                unknown_reference("part", name, &names),
                self.source.path.display()
            )
        })
    }
}

/// Reads, parses and validates the study file at `path`.
pub fn load(path: &Path) -> Result<Study, Box<dyn std::error::Error + Send + Sync>> {
    let source = Source::read(path).map_err(|e| format!("cannot read study file {}: {e}", path.display()))?;
    Ok(parse_and_validate(source)?)
}

/// Parses and validates a study held in memory.
pub fn parse_and_validate(source: Source) -> Result<Study, StudyErrors> {
    let file: StudyFile = match toml::from_str(&source.text) {
        Ok(f) => f,
        Err(e) => {
            let error = source.toml_error(&e);
            return Err(StudyErrors {
                source,
                errors: vec![error],
            });
        }
    };
    validate(source, &file)
}

/// The checks of the module docs.
pub fn validate(source: Source, file: &StudyFile) -> Result<Study, StudyErrors> {
    let mut v = Validator {
        src: &source,
        errors: Vec::new(),
        warnings: Vec::new(),
        failed: HashSet::new(),
        file_spiders: Vec::new(),
        index: HashMap::new(),
    };
    // The registry's own checks (required keys, ranges) once for the whole file; the checks
    // below add what the registry cannot state.
    if let Ok(doc) = source.text.parse::<toml::Table>() {
        v.errors.extend(keys::check(&doc));
    }
    let materials = v.materials(&file.materials);
    let sections = v.sections(&file.sections);
    let mut parts: Vec<(String, Option<Part>)> = Vec::new();
    for (i, p) in file.parts.iter().enumerate() {
        let path = KeyPath::root().key("parts").index(i);
        if v.lookup("part", &p.name).is_some() {
            let first = file.parts.iter().position(|q| q.name == p.name).unwrap_or(i);
            v.duplicate(&path, "part", &p.name, &KeyPath::root().key("parts").index(first), "");
            continue;
        }
        let part = v.part(&path, p, &materials, &sections, file);
        v.register("part", &p.name, parts.len());
        parts.push((p.name.clone(), part));
    }
    let mechanism = v.mechanism(file, &parts);
    let analyses = v.analyses(&file.analyses, &mut parts, &mechanism);
    let fmu_parameters = v.fmu_parameters(file);
    let warnings = v.warnings.iter().map(|w| source.render(w)).collect();
    let errors = std::mem::take(&mut v.errors);
    if !errors.is_empty() {
        return Err(StudyErrors { source, errors });
    }
    let parts = parts.into_iter().filter_map(|(_, p)| p).collect();
    Ok(Study {
        title: file.study.as_ref().and_then(|s| s.title.clone()),
        source,
        parts,
        analyses,
        mechanism,
        warnings,
        fmu_parameters,
    })
}

/// A material as resolved: its name and the checked value.
struct Materials(Vec<(String, IsotropicMaterial)>);

impl Materials {
    fn names(&self) -> Vec<String> {
        self.0.iter().map(|(n, _)| n.clone()).collect()
    }
}

/// Sections are built per part, with the Poisson's ratio of the part's material (shear
/// factors by shape depend on it).
struct Sections<'f>(Vec<(String, KeyPath, &'f SectionFile)>);

impl Sections<'_> {
    fn names(&self) -> Vec<String> {
        self.0.iter().map(|(n, _, _)| n.clone()).collect()
    }
}

struct Validator<'s> {
    src: &'s Source,
    errors: Vec<StudyError>,
    warnings: Vec<StudyError>,
    /// Entities that are defined but failed their own checks, as "material:NAME",
    /// "body:NAME": their errors are reported once, where they are defined, and a reference
    /// to them elsewhere is not reported again as unknown.
    failed: HashSet<String>,
    /// The spiders (RBE2/RBE3) of the part being validated, when its mesh file defines them:
    /// an interface on one of their node sets takes its kind and node position by default.
    file_spiders: Vec<fe_model::mesh::import::ImportedSpider>,
    /// Where each valid named entity is in its list, by kind ("material", "section", "part",
    /// "flexible", "rigid", "joint", "driver", "sensor", "actuator") and name: duplicate checks and
    /// references are one hash look-up each, so validation time grows linearly with the
    /// number of entries (a linear search per entry made it quadratic).
    index: HashMap<(&'static str, String), usize>,
}

/// Names become file names (results folders, cache files): keep them portable.
fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("the name is empty".into());
    }
    if name.len() > 100 {
        return Err("the name is longer than 100 characters".into());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.')))
    {
        return Err(format!(
            "the name '{name}' contains '{c}': names may only contain ASCII letters, digits, '-', '_' and '.' (they name files)"
        ));
    }
    if name.starts_with('.') {
        return Err(format!("the name '{name}' starts with '.' (it names files)"));
    }
    Ok(())
}

/// The number of interior dofs (free, not on an interface) of the part `name` as built for
/// its reduction (`planar`: in-plane dofs only), as the reduction partitions them; `None`
/// when the partition fails (the reduction reports why, with its own message).
fn interior_dofs(name: &str, built: &crate::input::part::Built, planar: bool) -> Option<usize> {
    let mut interfaces = built.interfaces.clone();
    if let Some(node) = built.auxiliary {
        interfaces.push(("auxiliary".to_string(), node));
    }
    let flat;
    let model = if planar {
        let nodes: Vec<NodeId> = interfaces.iter().map(|(_, n)| *n).collect();
        flat = reduction::planar_model(&built.model, name, &nodes).ok()?;
        &flat
    } else {
        &built.model
    };
    let dofs = fe_model::DofMap::new(model).ok()?;
    let p = reduction::partition(model, &dofs, &interfaces).ok()?;
    Some(p.internal.len())
}

/// The beam theory's name, for descriptions.
fn theory_name(theory: BeamTheory) -> &'static str {
    match theory {
        BeamTheory::Timoshenko => "Timoshenko",
        BeamTheory::EulerBernoulli => "Euler-Bernoulli",
    }
}

fn vec3(v: &Vec3) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

fn point(v: &Vec3) -> Point3<f64> {
    Point3::new(v[0], v[1], v[2])
}

impl Validator<'_> {
    /// Records that the entity `name` of `kind` is at `position` in its list.
    fn register(&mut self, kind: &'static str, name: &str, position: usize) {
        self.index.entry((kind, name.to_string())).or_insert(position);
    }

    /// The position of the entity `name` of `kind` in its list.
    fn lookup(&self, kind: &'static str, name: &str) -> Option<usize> {
        self.index.get(&(kind, name.to_string())).copied()
    }

    /// Marks the entity `name` of `kind` as defined with errors of its own (reported where it
    /// is defined): references to it are not reported again as unknown.
    fn mark_failed(&mut self, kind: &'static str, name: &str) {
        if check_name(name).is_ok() && self.lookup(kind, name).is_none() {
            self.failed.insert(format!("{kind}:{name}"));
        }
    }

    /// Whether the entity `name` of `kind` is defined but failed its own checks.
    fn has_failed(&self, kind: &str, name: &str) -> bool {
        self.failed.contains(&format!("{kind}:{name}"))
    }

    /// `materials[0] (line 3)`: where the first entity of a duplicated name is defined, for
    /// the message about the second.
    fn first_defined(&self, path: &KeyPath) -> String {
        match self.src.locate(path) {
            Some(span) => {
                let (line, _) = crate::input::source::line_column(&self.src.text, span.start);
                format!("{path} (line {line})")
            }
            None => path.to_string(),
        }
    }

    /// Whether `name` is the first of its name in the list `list` (`seen`: the names so far
    /// and their positions); otherwise reports the duplicate at `path` with where the first
    /// is defined (two entries of one name contradict each other: neither silently wins).
    fn first_of_name<'n>(
        &mut self,
        seen: &mut HashMap<&'n str, usize>,
        path: &KeyPath,
        list: &str,
        i: usize,
        what: &str,
        name: &'n str,
    ) -> bool {
        match seen.get(name) {
            Some(&first) => {
                self.duplicate(path, what, name, &KeyPath::root().key(list).index(first), "");
                false
            }
            None => {
                seen.insert(name, i);
                true
            }
        }
    }

    /// Reports the entity at `path` named `name`, which the entity at `first` already is
    /// (`note`: why names are unique, if it needs saying).
    fn duplicate(&mut self, path: &KeyPath, what: &str, name: &str, first: &KeyPath, note: &str) {
        let first = self.first_defined(&first.key("name"));
        self.err(
            &path.key("name"),
            format!("a {what} named '{name}' is already defined at {first}{note}"),
        );
    }

    /// `[fmu] parameters`: each a key path to a number, boolean or string of the study,
    /// named once.
    fn fmu_parameters(&mut self, file: &StudyFile) -> Vec<String> {
        let Some(fmu) = &file.fmu else {
            return Vec::new();
        };
        let doc = self.src.text.parse::<toml_edit::DocumentMut>();
        let mut kept = Vec::new();
        for (i, p) in fmu.parameters.iter().enumerate() {
            let at = KeyPath::root().key("fmu").key("parameters").index(i);
            if kept.contains(p) {
                self.err(&at, format!("parameter '{p}' is named twice"));
                continue;
            }
            if p == "fmu" || p.starts_with("fmu.") {
                self.err(&at, format!("'{p}': the [fmu] table itself cannot be a parameter"));
                continue;
            }
            let value = match &doc {
                Ok(doc) => crate::input::toml_path::value_at(doc, p),
                Err(_) => continue,
            };
            match value {
                Ok(serde_json::Value::Number(_) | serde_json::Value::Bool(_) | serde_json::Value::String(_)) => {
                    kept.push(p.clone())
                }
                Ok(other) => self.err(
                    &at,
                    format!("'{p}' is {other}; a parameter is a number, a boolean or a string of the study"),
                ),
                Err(e) => self.err(&at, format!("'{p}' names no value of the study: {e}")),
            }
        }
        kept
    }

    fn err(&mut self, path: &KeyPath, message: impl Into<String>) {
        self.errors.push(StudyError::at(path, message));
    }

    fn err_key(&mut self, path: &KeyPath, message: impl Into<String>) {
        self.errors.push(StudyError::at_key(path, message));
    }

    fn warn(&mut self, path: &KeyPath, message: impl Into<String>) {
        self.warnings.push(StudyError::at(path, message));
    }

    /// Refuses the keys of the table at `path` that the kind `kind` of the registry's table
    /// `table` does not take ([`crate::input::keys`]; the schema accepts the union of the keys
    /// of every kind, this checks the kind's own).
    fn only_keys(&mut self, path: &KeyPath, table: &str, kind: &str, what: &str) {
        let allowed = keys::allowed(table, kind);
        for k in self.src.keys(path) {
            if !allowed.contains(&k.as_str()) {
                let close = close_matches(&k, allowed.iter().copied());
                let hint = if close.is_empty() {
                    String::new()
                } else {
                    format!("; did you mean {}?", quote_list(&close, "or"))
                };
                self.err_key(
                    &path.key(&k),
                    format!(
                        "key `{k}` does not apply to {what}{hint} (its keys: {})",
                        allowed.join(", ")
                    ),
                );
            }
        }
    }

    /// Whether the numbers `values` of a table of kind `kind` (the registry's table `table`)
    /// are complete and in range: every required key of the kind given, every given one in
    /// its range. Reports nothing: [`keys::check`] did.
    fn complete(&self, table: &str, kind: &str, values: &[(&str, Option<f64>)]) -> bool {
        let t = keys::table(table);
        values.iter().all(|(key, value)| {
            let Some(k) = t.key(key).filter(|k| k.applies_to(kind)) else {
                return true;
            };
            match value {
                Some(x) => k.range().admits(*x),
                None => k.presence != keys::Presence::Required,
            }
        })
    }

    /// The value, or a "missing key" error on the table at `path`: for a key the registry
    /// cannot call required (required by one kind, optional for another, as `dt`).
    fn require<T: Copy>(&mut self, path: &KeyPath, value: Option<T>, key: &str, what: &str) -> Option<T> {
        if value.is_none() {
            self.err(path, format!("missing key `{key}` ({what})"));
        }
        value
    }

    fn finite3(&mut self, path: &KeyPath, v: &Vec3, what: &str) -> Option<Vector3<f64>> {
        if v.iter().all(|x| x.is_finite()) {
            Some(vec3(v))
        } else {
            self.err(path, format!("{what} must have finite components, got {v:?}"));
            None
        }
    }

    fn materials(&mut self, list: &[MaterialFile]) -> Materials {
        let mut out = Vec::new();
        let mut seen = HashMap::new();
        for (i, m) in list.iter().enumerate() {
            let path = KeyPath::root().key("materials").index(i);
            if let Err(e) = check_name(&m.name) {
                self.err(&path.key("name"), e);
                continue;
            }
            if !self.first_of_name(&mut seen, &path, "materials", i, "material", &m.name) {
                continue;
            }
            let E = keys::ranged("materials", "E", m.E);
            if let Some(implausible) = E.and_then(fe_model::units::implausible_E) {
                self.warn(
                    &path.key("E"),
                    format!("{implausible}: study files are in SI units (Pa, not MPa or GPa)"),
                );
            }
            let rho_ok = keys::in_range("materials", "rho", m.rho);
            if let Some(implausible) = fe_model::units::implausible_rho(m.rho).filter(|_| rho_ok) {
                self.warn(
                    &path.key("rho"),
                    format!("{implausible}: study files are in SI units (kg/m^3, not g/cm^3 or t/mm^3)"),
                );
            }
            let made = match (m.nu, m.G) {
                (Some(_), Some(_)) => {
                    self.err_key(
                        &path.key("G"),
                        "give Poisson's ratio `nu` or the shear modulus `G`, not both",
                    );
                    continue;
                }
                (None, None) => {
                    self.err(
                        &path,
                        "missing key `nu` or `G` (Poisson's ratio, or shear modulus [Pa])",
                    );
                    continue;
                }
                (Some(nu), None) => {
                    if !keys::in_range("materials", "nu", nu) {
                        continue;
                    }
                    E.filter(|_| rho_ok)
                        .map(|E| IsotropicMaterial::new(&m.name, E, nu, m.rho))
                }
                (None, Some(G)) => {
                    let Some(G) = keys::ranged("materials", "G", G) else {
                        continue;
                    };
                    if let Some(E) = E {
                        let nu = E / (2.0 * G) - 1.0;
                        if !(nu > -1.0 && nu < 0.5) {
                            self.err(
                                &path.key("G"),
                                format!("E = {E} and G = {G} give Poisson's ratio nu = E/(2G) - 1 = {nu:.4}, outside (-1, 0.5)"),
                            );
                            continue;
                        }
                    }
                    E.filter(|_| rho_ok)
                        .map(|E| IsotropicMaterial::from_E_G(&m.name, E, G, m.rho))
                }
            };
            match made {
                Some(Ok(material)) => {
                    self.register("material", &m.name, out.len());
                    out.push((m.name.clone(), material));
                }
                Some(Err(e)) => self.err(&path, e.to_string()),
                None => {}
            }
        }
        // A material with errors is known, not unknown, to the parts that use it.
        for m in list {
            self.mark_failed("material", &m.name);
        }
        Materials(out)
    }

    fn sections<'f>(&mut self, list: &'f [SectionFile]) -> Sections<'f> {
        let mut out: Vec<(String, KeyPath, &'f SectionFile)> = Vec::new();
        let mut seen = HashMap::new();
        for (i, s) in list.iter().enumerate() {
            let path = KeyPath::root().key("sections").index(i);
            if let Err(e) = check_name(&s.name) {
                self.err(&path.key("name"), e);
                continue;
            }
            if !self.first_of_name(&mut seen, &path, "sections", i, "section", &s.name) {
                continue;
            }
            let what = match s.shape {
                SectionShape::Rectangle => "a rectangle section (width b along local y, height h along local z, m)",
                SectionShape::Circle => "a circle section (diameter d, m)",
                SectionShape::Tube => "a tube section (diameters d_outer, d_inner, m)",
                SectionShape::Values => "a section by values (A [m^2], Iy, Iz, J [m^4], shear factors ky, kz)",
            };
            self.only_keys(&path, "sections", s.shape.name(), what);
            let values: [(&str, Option<f64>); 11] = [
                ("b", s.b),
                ("h", s.h),
                ("d", s.d),
                ("d_outer", s.d_outer),
                ("d_inner", s.d_inner),
                ("A", s.A),
                ("Iy", s.Iy),
                ("Iz", s.Iz),
                ("J", s.J),
                ("ky", s.ky),
                ("kz", s.kz),
            ];
            let mut ok = self.complete("sections", s.shape.name(), &values);
            if let (SectionShape::Tube, Some(o), Some(i)) = (s.shape, s.d_outer, s.d_inner) {
                if i >= o {
                    self.err(
                        &path.key("d_inner"),
                        format!("d_inner = {i} must be smaller than d_outer = {o}"),
                    );
                    ok = false;
                }
            }
            if ok {
                self.register("section", &s.name, out.len());
                out.push((s.name.clone(), path, s));
            }
        }
        // A section with errors is known, not unknown, to the parts that use it.
        for s in list {
            self.mark_failed("section", &s.name);
        }
        Sections(out)
    }

    /// The section `name` built with Poisson's ratio `nu`, or an error at `at`.
    fn section(&mut self, at: &KeyPath, name: &str, sections: &Sections<'_>, nu: f64) -> Option<BeamSection> {
        let Some((_, path, s)) = self.lookup("section", name).map(|k| &sections.0[k]) else {
            if !self.has_failed("section", name) {
                self.err(at, unknown_reference("section", name, &sections.names()));
            }
            return None;
        };
        let k = 5.0 / 6.0;
        let made = match s.shape {
            SectionShape::Rectangle => BeamSection::rectangle(name, s.b?, s.h?, nu),
            SectionShape::Circle => BeamSection::circle(name, s.d?, nu),
            SectionShape::Tube => BeamSection::tube(name, s.d_outer?, s.d_inner?, nu),
            SectionShape::Values => {
                BeamSection::from_values(name, s.A?, s.Iy?, s.Iz?, s.J?, s.ky.unwrap_or(k), s.kz.unwrap_or(k))
            }
        };
        match made {
            Ok(section) => Some(section),
            Err(e) => {
                self.err(path, e.to_string());
                None
            }
        }
    }

    fn material<'m>(&mut self, at: &KeyPath, name: &str, materials: &'m Materials) -> Option<&'m IsotropicMaterial> {
        let m = self.lookup("material", name).map(|k| &materials.0[k].1);
        if m.is_none() && !self.has_failed("material", name) {
            self.err(at, unknown_reference("material", name, &materials.names()));
        }
        m
    }

    fn part(
        &mut self,
        path: &KeyPath,
        p: &PartFile,
        materials: &Materials,
        sections: &Sections<'_>,
        file: &StudyFile,
    ) -> Option<Part> {
        if let Err(e) = check_name(&p.name) {
            self.err(&path.key("name"), e);
            return None;
        }
        let given: Vec<&str> = [
            ("beam", p.beam.is_some()),
            ("box", p.box_.is_some()),
            ("mesh", p.mesh.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(k, _)| *k)
        .collect();
        if given.len() != 1 {
            let m = if given.is_empty() {
                "missing geometry: give one of [parts.beam] (a generated beam), [parts.box] (a generated solid box) or [parts.mesh] (a gmsh file)".to_string()
            } else {
                format!("give one geometry per part, not {}", given.join(" and "))
            };
            self.err(path, m);
            return None;
        }
        let mass = mass_kind(p.mass);
        let built = if let Some(beam) = &p.beam {
            let material = p
                .material
                .as_ref()
                .or_else(|| {
                    self.err(path, "missing key `material` (the beam's material)");
                    None
                })
                .and_then(|m| self.material(&path.key("material"), m, materials))?
                .clone();
            self.beam(&path.key("beam"), &p.name, beam, material, sections, mass)
                .map(|(m, d)| (m, d, PartKind::Beam, None))
        } else if let Some(b) = &p.box_ {
            let material = p
                .material
                .as_ref()
                .or_else(|| {
                    self.err(path, "missing key `material` (the box's material)");
                    None
                })
                .and_then(|m| self.material(&path.key("material"), m, materials))?
                .clone();
            self.solid_box(&path.key("box"), b, material, mass)
                .map(|(m, d)| (m, d, PartKind::Solid, None))
        } else if let Some(mesh) = &p.mesh {
            self.mesh(path, p, mesh, materials, mass)
                .map(|(m, d, f, kind)| (m, d, kind, Some(f)))
        } else {
            None
        };
        let (base, description, kind, mesh_file) = built?;
        let interfaces = self.interfaces(path, p, &base, kind)?;
        let reduction = match &p.reduction {
            Some(r) => Some(self.reduction(&path.key("reduction"), r, &interfaces, &base)?),
            None => None,
        };
        let mut part = Part {
            name: p.name.clone(),
            path: path.clone(),
            kind,
            description,
            mesh_file,
            base,
            interfaces,
            reduction,
        };
        // Build the spiders now: a surface that cannot carry an interface is an input error,
        // and should be reported with its key before anything runs.
        // The interior is counted only for a mode count (its partition costs a dof map).
        let planar = part
            .reduction
            .as_ref()
            .filter(|r| matches!(r.modes, ModeSelection::Count(m) if m > 0))
            .map(|r| r.planar);
        let interior =
            match part.check_build_for_reduction(|built| planar.map(|planar| interior_dofs(&p.name, built, planar))) {
                Ok(interior) => interior,
                Err(e) => {
                    self.fe_error(path, &part, &e);
                    return None;
                }
            };
        // A mode count the interior cannot give fails the reduction: say so now, not after
        // the analyses before it have run.
        if let (
            Some(Some(interior)),
            Some(Reduction {
                modes: ModeSelection::Count(m),
                ..
            }),
        ) = (interior, &part.reduction)
        {
            if *m > 0 && *m >= interior {
                let e = reduction::ReductionError::TooManyModes {
                    body: p.name.clone(),
                    requested: *m,
                    interior,
                };
                self.err(&path.key("reduction").key("modes"), e.to_string());
                return None;
            }
        }
        let _ = file;
        Some(part)
    }

    /// An FE error while building `part`, pointed at the interface it names, if any.
    fn fe_error(&mut self, path: &KeyPath, part: &Part, e: &FeError) {
        if let FeError::Interface { name, .. } = e {
            if name == "auxiliary" {
                self.err(&path.key("reduction").key("auxiliary_node"), e.to_string());
                return;
            }
            if let Some(i) = part.interfaces.iter().find(|i| i.name == *name) {
                self.err(&i.path, e.to_string());
                return;
            }
        }
        self.err(path, format!("part '{}': {e}", part.name));
    }

    fn theory(t: Option<TheoryFile>) -> BeamTheory {
        match t {
            Some(TheoryFile::EulerBernoulli) => BeamTheory::EulerBernoulli,
            _ => BeamTheory::Timoshenko,
        }
    }

    /// The orientation vector of a beam along `axis`: the given one (checked not parallel),
    /// or global z, or global y for a beam within about 6 degrees of z.
    fn orientation(&mut self, path: &KeyPath, given: Option<&Vec3>, axis: &Vector3<f64>) -> Option<Vector3<f64>> {
        let a = axis.normalize();
        match given {
            Some(v) => {
                let v = self.finite3(path, v, "the orientation vector")?;
                if v.norm() == 0.0 || a.cross(&v.normalize()).norm() < 1e-6 {
                    self.err(
                        path,
                        format!(
                            "the orientation vector {:?} is parallel to the beam axis {:?} (it must point into the local x-y plane)",
                            [v.x, v.y, v.z],
                            [a.x, a.y, a.z]
                        ),
                    );
                    return None;
                }
                Some(v)
            }
            None => Some(if a.cross(&Vector3::z()).norm() > 0.1 {
                Vector3::z()
            } else {
                Vector3::y()
            }),
        }
    }

    fn beam(
        &mut self,
        path: &KeyPath,
        name: &str,
        b: &BeamFile,
        material: IsotropicMaterial,
        sections: &Sections<'_>,
        mass: fe_model::MassKind,
    ) -> Option<(FeModel, String)> {
        let what = match b.kind {
            BeamKind::Straight => "a straight beam",
            BeamKind::Arc => "an arc",
            BeamKind::Frame => "a frame",
        };
        self.only_keys(path, "parts.beam", b.kind.name(), what);
        let theory = Self::theory(b.theory);
        let nu = material.nu();
        let mut model = FeModel::default();
        let material_id = model.add_material(material);
        let section = self.section(&path.key("section"), &b.section, sections, nu)?;
        let section_id = model.add_section(section);
        let props = |orientation: Vector3<f64>, section| BeamProperties {
            section,
            material: material_id,
            orientation,
            theory,
            mass,
        };
        let theory_name = theory_name(theory);
        let result = match b.kind {
            BeamKind::Straight => {
                let (from, to, n) = (b.from?, b.to?, b.elements?);
                keys::in_range("parts.beam", "elements", n as f64).then_some(())?;
                let p0 = point(&self.finite3(&path.key("from"), &from, "`from`")?.into());
                let p1 = point(&self.finite3(&path.key("to"), &to, "`to`")?.into());
                let axis = p1 - p0;
                if !(axis.norm() > 0.0) {
                    self.err(&path.key("to"), "`to` coincides with `from`: the beam has zero length");
                    return None;
                }
                let orientation = self.orientation(&path.key("orientation"), b.orientation.as_ref(), &axis)?;
                straight_beam(&mut model, p0, p1, n, &props(orientation, section_id), Some(name))
                    .map(|_| format!("straight beam, {n} {theory_name} elements"))
            }
            BeamKind::Arc => {
                let (center, start, axis, angle, n) = (b.center?, b.start?, b.axis?, b.angle_deg?, b.elements?);
                keys::in_range("parts.beam", "elements", n as f64).then_some(())?;
                let c = point(&self.finite3(&path.key("center"), &center, "`center`")?.into());
                let s = point(&self.finite3(&path.key("start"), &start, "`start`")?.into());
                let axis = self.finite3(&path.key("axis"), &axis, "`axis`")?;
                if !(angle.is_finite() && angle != 0.0 && angle.abs() <= 360.0) {
                    self.err(
                        &path.key("angle_deg"),
                        format!("the angle must be non-zero and at most 360 degrees in size, got {angle}"),
                    );
                    return None;
                }
                beam_arc(
                    &mut model,
                    c,
                    s,
                    axis,
                    angle.to_radians(),
                    n,
                    &props(Vector3::z(), section_id),
                    Some(name),
                )
                .map(|_| format!("arc of {angle} degrees, {n} {theory_name} elements"))
            }
            BeamKind::Frame => {
                let base = props(Vector3::z(), section_id);
                self.frame_beam(path, name, b, sections, nu, &mut model, &base)?
            }
        };
        match result {
            Ok(description) => Some((model, description)),
            Err(e) => {
                self.err(path, e.to_string());
                None
            }
        }
    }

    /// A frame: its points and members (`base`: the properties of a member that overrides
    /// neither `section` nor `orientation`, but for the orientation); the description, or the
    /// generator's error.
    fn frame_beam(
        &mut self,
        path: &KeyPath,
        name: &str,
        b: &BeamFile,
        sections: &Sections<'_>,
        nu: f64,
        model: &mut FeModel,
        base: &BeamProperties,
    ) -> Option<Result<String, FeError>> {
        let (points, members) = (b.points.as_ref()?, b.members.as_ref()?);
        let mut pts = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            pts.push(point(&self.finite3(&path.key("points").index(i), p, "a point")?.into()));
        }
        if members.is_empty() {
            self.err(&path.key("members"), "a frame needs at least one member");
            return None;
        }
        let mut list = Vec::with_capacity(members.len());
        let mut total = 0;
        for (j, m) in members.iter().enumerate() {
            let mp = path.key("members").index(j);
            let mut bad = false;
            for (key, idx) in [("from", m.from), ("to", m.to)] {
                if idx >= pts.len() {
                    self.err(
                        &mp.key(key),
                        format!(
                            "point {idx} does not exist: the frame has {} points (0-based)",
                            pts.len()
                        ),
                    );
                    bad = true;
                }
            }
            if bad {
                continue;
            }
            if m.from == m.to || (pts[m.to] - pts[m.from]).norm() == 0.0 {
                self.err(&mp.key("to"), "the member starts and ends at the same point");
                continue;
            }
            let n = m.elements;
            if !keys::in_range("parts.beam.members", "elements", n as f64) {
                continue;
            }
            total += n;
            let section = match &m.section {
                Some(s) => match self.section(&mp.key("section"), s, sections, nu) {
                    Some(sec) => model.add_section(sec),
                    None => continue,
                },
                None => base.section,
            };
            let axis = pts[m.to] - pts[m.from];
            let given = m.orientation.as_ref().or(b.orientation.as_ref());
            let at = if m.orientation.is_some() {
                mp.key("orientation")
            } else {
                path.key("orientation")
            };
            let Some(orientation) = self.orientation(&at, given, &axis) else {
                continue;
            };
            list.push(Member {
                from: m.from,
                to: m.to,
                elements: n,
                props: BeamProperties {
                    section,
                    orientation,
                    ..base.clone()
                },
            });
        }
        if list.len() != members.len() {
            return None;
        }
        let theory_name = theory_name(base.theory);
        Some(
            frame(model, &pts, &list, name)
                .map(|_| format!("frame of {} members, {total} {theory_name} elements", list.len())),
        )
    }

    fn solid_box(
        &mut self,
        path: &KeyPath,
        b: &BoxFile,
        material: IsotropicMaterial,
        mass: fe_model::MassKind,
    ) -> Option<(FeModel, String)> {
        let ok = b.size.iter().all(|l| keys::in_range("parts.box", "size", *l))
            && b.divisions
                .iter()
                .all(|d| keys::in_range("parts.box", "divisions", *d as f64));
        let origin = match &b.origin {
            Some(o) => self.finite3(&path.key("origin"), o, "the origin")?,
            None => Vector3::zeros(),
        };
        if !ok {
            return None;
        }
        let (kind, per_brick) = match b.element {
            ElementFile::Hex8 => (CellKind::Hex8, 1),
            ElementFile::Hex20 => (CellKind::Hex20, 1),
            ElementFile::Tet4 => (CellKind::Tet4, 6),
            ElementFile::Tet10 => (CellKind::Tet10, 6),
            ElementFile::Wedge6 => (CellKind::Wedge6, 2),
        };
        let cells = b
            .divisions
            .iter()
            .try_fold(per_brick, |acc: usize, &d| acc.checked_mul(d))
            .unwrap_or(usize::MAX);
        if cells > MAX_BOX_CELLS {
            self.err(
                &path.key("divisions"),
                format!("{cells} cells is more than a generated box may have ({MAX_BOX_CELLS}); mesh it with gmsh"),
            );
            return None;
        }
        let mut mesh = match fe_model::box_mesh(kind, b.size, b.divisions) {
            Ok(m) => m,
            Err(e) => {
                self.err(path, e.to_string());
                return None;
            }
        };
        for p in &mut mesh.nodes {
            *p += origin;
        }
        let n_cells = mesh.cells.len();
        match fe_model::solid_model(mesh, material, mass) {
            Ok(model) => Some((model, format!("box {:?} m, {n_cells} {kind:?} cells", b.size))),
            Err(e) => {
                self.err(path, e.to_string());
                None
            }
        }
    }

    /// A part's mesh from a gmsh, Abaqus (`.inp`) or Nastran (`.bdf`, `.nas`, `.dat`) file.
    /// Abaqus and Nastran files bring their materials, which `material` or `mesh.materials`
    /// replace; their skipped keywords or cards and approximations become warnings.
    fn mesh(
        &mut self,
        path: &KeyPath,
        p: &PartFile,
        m: &MeshFile,
        materials: &Materials,
        mass: fe_model::MassKind,
    ) -> Option<(FeModel, String, std::path::PathBuf, PartKind)> {
        let file = self.src.dir().join(&m.file);
        let file_key = path.key("mesh").key("file");
        self.file_spiders.clear();
        let units = m.units.map_or(fe_model::units::UnitSystem::Si, |u| u.system());
        let (format, imported, mesh) = self.read_mesh(&file, &file_key, units)?;
        // An inverted or degenerate element fails the assembly: refuse it now, by its label in
        // the file (the assembly knows only its position in the model).
        if let Err(e) = fe_model::mesh::quality::check_solid_cells(&mesh) {
            self.err(
                &file_key,
                format!("part '{}': {} file {}: {e}", p.name, format, file.display()),
            );
            return None;
        }
        let volumes = mesh.cells.iter().filter(|c| c.kind.dimension() == 3).count();
        let beams = imported.as_ref().map_or(0, |i| {
            i.beam_sections
                .iter()
                .filter_map(|s| mesh.cell_sets.get(&s.cell_set))
                .map(Vec::len)
                .sum::<usize>()
        });
        if volumes == 0 && beams == 0 {
            self.err(
                &file_key,
                format!(
                    "{} has no volume cells (tet, hex, wedge){}: fe-model meshes solids only",
                    file.display(),
                    if imported.is_some() {
                        " and no beams with a beam section"
                    } else {
                        ""
                    }
                ),
            );
            return None;
        }
        if volumes > 0 && beams > 0 {
            self.err(
                &file_key,
                "the file has both solid and beam elements; a part is either (split it into two parts)",
            );
            return None;
        }
        let kind = if beams > 0 { PartKind::Beam } else { PartKind::Solid };
        let description = format!(
            "{format} mesh {}, {} nodes, {}",
            m.file,
            mesh.nodes.len(),
            if beams > 0 {
                format!("{beams} beam elements")
            } else {
                format!("{volumes} volume cells")
            }
        );
        // The sets that carry a section in the file: a study material replaces theirs.
        let section_sets: Vec<String> = imported.as_ref().map_or(Vec::new(), |i| {
            i.solid_sections
                .iter()
                .map(|s| s.cell_set.clone())
                .chain(i.beam_sections.iter().map(|s| s.cell_set.clone()))
                .collect()
        });
        let model = match (&p.material, &m.materials, &imported) {
            (Some(_), Some(_), _) => {
                self.err_key(
                    &path.key("mesh").key("materials"),
                    "give the part's `material` or `mesh.materials` (one per physical volume), not both",
                );
                return None;
            }
            (None, None, Some(i)) => i.to_fe_model(mass, None),
            (None, None, None) => {
                self.err(
                    path,
                    "missing key `material` (or `mesh.materials`, a material per physical volume)",
                );
                return None;
            }
            (Some(name), None, imported) => {
                let material = self.material(&path.key("material"), name, materials)?.clone();
                match imported {
                    Some(i) if !section_sets.is_empty() => {
                        let list: Vec<(&str, IsotropicMaterial)> =
                            section_sets.iter().map(|s| (s.as_str(), material.clone())).collect();
                        i.to_fe_model(mass, Some(&list))
                    }
                    _ => fe_model::solid_model(mesh, material, mass),
                }
            }
            (None, Some(map), imported) => {
                let mut list = Vec::new();
                let sets: Vec<String> = mesh.cell_sets.keys().cloned().collect();
                for (set, material) in map {
                    let at = path.key("mesh").key("materials").key(set);
                    if !mesh.cell_sets.contains_key(set) {
                        self.err_key(&at, unknown_reference("physical volume (cell set)", set, &sets));
                        continue;
                    }
                    if let Some(mat) = self.material(&at, material, materials) {
                        list.push((set.as_str(), mat.clone()));
                    }
                }
                if list.len() != map.len() {
                    return None;
                }
                match imported {
                    Some(i) => i.to_fe_model(mass, Some(&list)),
                    None => fe_model::solid_model_with_materials(mesh, &list, mass),
                }
            }
        };
        match model {
            Ok(model) => Some((model, description, file, kind)),
            Err(e) => {
                self.err(&path.key("mesh"), e.to_string());
                None
            }
        }
    }

    /// The mesh file of a part, written in `units`: its format, the model an Abaqus or
    /// Nastran file brings (with its spiders kept in `file_spiders`), and the mesh, in SI.
    fn read_mesh(
        &mut self,
        file: &Path,
        file_key: &KeyPath,
        units: fe_model::units::UnitSystem,
    ) -> Option<(&'static str, Option<fe_model::ImportedModel>, fe_model::mesh::Mesh)> {
        use fe_model::mesh::{abaqus, nastran};
        let extension = file.extension().map(|e| e.to_string_lossy().to_lowercase());
        let (format, imported) = match extension.as_deref() {
            Some("inp") => ("Abaqus", Some(abaqus::read(file, units))),
            Some("bdf" | "nas" | "dat") => ("Nastran", Some(nastran::read(file, units))),
            _ => ("gmsh", None),
        };
        let imported = match imported {
            Some(Ok(i)) => Some(i),
            Some(Err(e)) => {
                self.err(file_key, format!("cannot read the {format} file: {e}"));
                return None;
            }
            None => None,
        };
        let mesh = match &imported {
            Some(i) => i.mesh.clone(),
            None => match fe_model::mesh::gmsh::read(file) {
                Ok(mut mesh) => {
                    // A gmsh file has only lengths.
                    let length = units.to_si(fe_model::units::Quantity::Length);
                    mesh.nodes.iter_mut().for_each(|p| p.coords *= length);
                    mesh
                }
                Err(e) => {
                    self.err(file_key, format!("cannot read the mesh: {e}"));
                    return None;
                }
            },
        };
        if let Some(i) = &imported {
            if let Some(skipped) = i.ignored_summary() {
                self.warn(file_key, format!("{format} file: skipped {skipped}"));
            }
            for note in &i.notes {
                self.warn(file_key, format!("{format} file: {note}"));
            }
            self.file_spiders = i.spiders.clone();
        }
        Some((format, imported, mesh))
    }

    /// Every node whose position is within `radius` of `c`.
    fn nodes_near(model: &FeModel, c: &Point3<f64>, radius: f64) -> Vec<NodeId> {
        model
            .mesh
            .nodes
            .iter()
            .enumerate()
            .filter(|(_, p)| (*p - c).norm() <= radius)
            .map(|(i, _)| NodeId(i as u32))
            .collect()
    }

    /// The node at `x` (within a millionth of the model's size), or an error naming the
    /// nearest.
    fn node_at(&mut self, path: &KeyPath, model: &FeModel, x: &Vec3) -> Option<NodeId> {
        let x = point(&self.finite3(path, x, "the position")?.into());
        let Some(node) = model.mesh.nearest_node(&x) else {
            self.err(path, "the part has no nodes");
            return None;
        };
        let p = model.mesh.nodes[node.index()];
        let d = (p - x).norm();
        if d > 1e-6 * model_size(model) {
            self.err(
                path,
                format!(
                    "no node at ({}, {}, {}); the nearest, node {} at ({}, {}, {}), is {d:.3e} m away",
                    x.x,
                    x.y,
                    x.z,
                    model.mesh.node_tags[node.index()],
                    p.x,
                    p.y,
                    p.z
                ),
            );
            return None;
        }
        Some(node)
    }

    fn node_set<'m>(&mut self, path: &KeyPath, model: &'m FeModel, set: &str) -> Option<&'m [NodeId]> {
        let nodes = model.mesh.node_set(set);
        if nodes.is_none() {
            let known: Vec<String> = model.mesh.node_sets.keys().cloned().collect();
            self.err(path, unknown_reference("node set", set, &known));
        }
        nodes
    }

    fn interfaces(
        &mut self,
        path: &KeyPath,
        p: &PartFile,
        model: &FeModel,
        kind: PartKind,
    ) -> Option<Vec<InterfaceSpec>> {
        let mut out: Vec<InterfaceSpec> = Vec::new();
        let mut ok = true;
        for (k, i) in p.interfaces.iter().enumerate() {
            let ip = path.key("interfaces").index(k);
            if let Err(e) = check_name(&i.name) {
                self.err(&ip.key("name"), e);
                ok = false;
                continue;
            }
            if i.name == "auxiliary" {
                self.err(
                    &ip.key("name"),
                    "the name 'auxiliary' is reserved for the auxiliary node of the reduction",
                );
                ok = false;
                continue;
            }
            if out.iter().any(|o| o.name == i.name) {
                self.err(
                    &ip.key("name"),
                    format!("part '{}' already has an interface named '{}'", p.name, i.name),
                );
                ok = false;
                continue;
            }
            let target = match kind {
                PartKind::Beam => self.beam_interface(&ip, p, i, model),
                PartKind::Solid => self.solid_interface(&ip, i, model, &mut ok),
            };
            match target {
                Some(target) => out.push(InterfaceSpec {
                    name: i.name.clone(),
                    path: ip,
                    target,
                }),
                None => ok = false,
            }
        }
        // Two beam interfaces on one node would be one interface twice.
        for (a, ia) in out.iter().enumerate() {
            for ib in &out[a + 1..] {
                if let (InterfaceTarget::BeamNode(x), InterfaceTarget::BeamNode(y)) = (&ia.target, &ib.target) {
                    if x == y {
                        self.err(
                            &ib.path,
                            format!("interfaces '{}' and '{}' are the same node", ia.name, ib.name),
                        );
                        ok = false;
                    }
                }
            }
        }
        ok.then_some(out)
    }

    /// The node of an interface of a beam part: a one-node set or the node at a position.
    fn beam_interface(
        &mut self,
        ip: &KeyPath,
        p: &PartFile,
        i: &InterfaceFile,
        model: &FeModel,
    ) -> Option<InterfaceTarget> {
        self.only_keys(
            ip,
            "parts.interfaces",
            "beam",
            "an interface of a beam part (a beam node)",
        );
        match (&i.set, &i.node_at) {
            (Some(set), None) => self.node_set(&ip.key("set"), model, set).and_then(|nodes| {
                if nodes.len() == 1 {
                    Some(InterfaceTarget::BeamNode(nodes[0]))
                } else {
                    self.err(
                        &ip.key("set"),
                        format!(
                            "node set '{set}' has {} nodes; a beam interface is one node (such as '{}.end')",
                            nodes.len(),
                            p.name
                        ),
                    );
                    None
                }
            }),
            (None, Some(x)) => self
                .node_at(&ip.key("node_at"), model, x)
                .map(InterfaceTarget::BeamNode),
            _ => {
                self.err(ip, "give the interface's node by `set` (a one-node set such as 'beam.end') or by `node_at` = [x, y, z], one of them");
                None
            }
        }
    }

    /// The spider of an interface of a solid part: its surface nodes, kind and node position
    /// (`ok` turns false on an error that leaves the interface usable for further checks).
    fn solid_interface(
        &mut self,
        ip: &KeyPath,
        i: &InterfaceFile,
        model: &FeModel,
        ok: &mut bool,
    ) -> Option<InterfaceTarget> {
        self.only_keys(
            ip,
            "parts.interfaces",
            "solid",
            "an interface of a solid part (a spider on surface nodes)",
        );
        // A set of one of the file's spiders (RBE2_<eid>, RBE3_<eid>) brings its kind
        // and node position.
        let file_spider = i
            .set
            .as_ref()
            .and_then(|set| self.file_spiders.iter().find(|s| s.name == *set))
            .cloned();
        let spider = match i.spider {
            Some(SpiderFile::Rbe2) => Some(SpiderKind::Rbe2),
            Some(SpiderFile::Rbe3) => Some(SpiderKind::Rbe3),
            None if file_spider.is_some() => file_spider.as_ref().map(|s| s.kind),
            None => {
                self.err(ip, "missing key `spider` (\"rbe2\": rigid, or \"rbe3\": interpolating)");
                None
            }
        };
        let node_position = match &i.node_position {
            Some(x) => match self.finite3(&ip.key("node_position"), x, "the node position") {
                Some(v) => Some(Point3::from(v)),
                None => {
                    *ok = false;
                    None
                }
            },
            None => file_spider.as_ref().map(|s| s.position),
        };
        let surface = match (&i.set, &i.near, i.radius) {
            (Some(set), None, None) => self.node_set(&ip.key("set"), model, set).map(<[NodeId]>::to_vec),
            (None, Some(c), Some(r)) => {
                let c = self.finite3(&ip.key("near"), c, "`near`");
                let r = keys::ranged("parts.interfaces", "radius", r);
                match (c, r) {
                    (Some(c), Some(r)) => {
                        let nodes = Self::nodes_near(model, &Point3::from(c), r);
                        if nodes.is_empty() {
                            let nearest = model
                                .mesh
                                .nearest_node(&Point3::from(c))
                                .map(|n| (model.mesh.nodes[n.index()] - Point3::from(c)).norm());
                            self.err(
                                &ip.key("radius"),
                                format!(
                                    "no node within {r} m of {:?}{}",
                                    [c.x, c.y, c.z],
                                    nearest.map_or(String::new(), |d| format!("; the nearest is {d:.3e} m away"))
                                ),
                            );
                            None
                        } else {
                            Some(nodes)
                        }
                    }
                    _ => None,
                }
            }
            (None, Some(_), None) => {
                self.err(
                    ip,
                    "missing key `radius` (nodes within `radius` of `near` form the surface)",
                );
                None
            }
            _ => {
                self.err(ip, "give the surface nodes by `set` (a node set or physical group) or by `near` = [x, y, z] and `radius`, one of them");
                None
            }
        };
        match (surface, spider) {
            (Some(surface), Some(kind)) => Some(InterfaceTarget::Spider {
                surface,
                kind,
                node_position,
            }),
            _ => None,
        }
    }

    fn reduction(
        &mut self,
        path: &KeyPath,
        r: &ReductionFile,
        interfaces: &[InterfaceSpec],
        model: &FeModel,
    ) -> Option<Reduction> {
        let n_interfaces = interfaces.len();
        let modes = match (r.modes, r.cutoff_hz) {
            (Some(_), Some(_)) => {
                self.err_key(
                    &path.key("cutoff_hz"),
                    "give `modes` (a count) or `cutoff_hz` (a frequency), not both",
                );
                return None;
            }
            (None, None) => {
                self.err(path, "missing key `modes` (number of fixed-interface modes, 0 for static modes only) or `cutoff_hz` (keep the modes below this frequency)");
                return None;
            }
            (Some(0), None) => ModeSelection::StaticOnly,
            (Some(m), None) => ModeSelection::Count(keys::ranged("parts.reduction", "modes", m as f64).map(|_| m)?),
            (None, Some(f)) => ModeSelection::CutoffHz(keys::ranged("parts.reduction", "cutoff_hz", f)?),
        };
        let auxiliary_node = r.auxiliary_node.unwrap_or(false);
        if n_interfaces == 0 && !auxiliary_node {
            self.err(
                path,
                "a reduced part needs at least one interface ([[parts.interfaces]])",
            );
            return None;
        }
        let mut load_points: Vec<(String, NodeId)> = Vec::new();
        let mut ok = true;
        for (k, lp) in r.load_points.iter().flatten().enumerate() {
            let lpath = path.key("load_points").index(k);
            if load_points.iter().any(|(n, _)| *n == lp.name) || interfaces.iter().any(|i| i.name == lp.name) {
                self.err(
                    &lpath.key("name"),
                    format!("'{}' already names an interface or load point of this part", lp.name),
                );
                ok = false;
                continue;
            }
            let node = match (&lp.set, &lp.node_at) {
                (Some(set), None) => self.node_set(&lpath.key("set"), model, set).and_then(|nodes| {
                    if nodes.len() == 1 {
                        Some(nodes[0])
                    } else {
                        self.err(
                            &lpath.key("set"),
                            format!("node set '{set}' has {} nodes; a load point is one node", nodes.len()),
                        );
                        None
                    }
                }),
                (None, Some(x)) => self.node_at(&lpath.key("node_at"), model, x),
                _ => {
                    self.err(
                        &lpath,
                        "give the load point's node by `set` (a one-node set) or by `node_at` = [x, y, z], one of them",
                    );
                    None
                }
            };
            match node {
                Some(node)
                    if interfaces
                        .iter()
                        .any(|i| matches!(i.target, InterfaceTarget::BeamNode(b) if b == node)) =>
                {
                    self.err(
                        &lpath,
                        format!(
                            "load point '{}' is an interface node; loads there need no static correction",
                            lp.name
                        ),
                    );
                    ok = false;
                }
                Some(node) => load_points.push((lp.name.clone(), node)),
                None => ok = false,
            }
        }
        let factor = match r.factor.as_deref() {
            None | Some("auto") => reduction::FactorPrecision::Auto,
            Some("double") => reduction::FactorPrecision::Double,
            Some("single") => reduction::FactorPrecision::Single,
            Some(other) => {
                self.err(
                    &path.key("factor"),
                    format!("'{other}' is not a precision of the factor: use \"auto\", \"double\" or \"single\""),
                );
                return None;
            }
        };
        if !ok {
            return None;
        }
        Some(Reduction {
            factor,
            modes,
            auxiliary_node,
            keep_mesh_shapes: r.keep_mesh_shapes.unwrap_or(true),
            geometric_stiffening: r.geometric_stiffening.unwrap_or(false),
            inertia_correction: r.inertia_correction.unwrap_or(false),
            planar: r.planar.unwrap_or(false),
            stress_shapes: r.stress_shapes.unwrap_or(false),
            load_points,
        })
    }

    /// A node reference by `at` (an interface, else a node set) or `node_at`.
    fn node_ref(
        &mut self,
        path: &KeyPath,
        part: &Part,
        at: &Option<String>,
        node_at: &Option<Vec3>,
    ) -> Option<NodeRef> {
        match (at, node_at) {
            (Some(name), None) => {
                if let Some(k) = part.interfaces.iter().position(|i| i.name == *name) {
                    return Some(NodeRef::Interface(k));
                }
                if let Some(nodes) = part.base.mesh.node_set(name) {
                    if nodes.is_empty() {
                        self.err(&path.key("at"), format!("node set '{name}' is empty"));
                        return None;
                    }
                    return Some(NodeRef::Nodes(nodes.to_vec()));
                }
                let mut known: Vec<String> = part.interfaces.iter().map(|i| i.name.clone()).collect();
                known.extend(part.base.mesh.node_sets.keys().cloned());
                self.err(
                    &path.key("at"),
                    format!(
                        "part '{}' has no interface or node set '{name}'{}",
                        part.name,
                        suggestions(name, &known, "interface or node set")
                    ),
                );
                None
            }
            (None, Some(x)) => self
                .node_at(&path.key("node_at"), &part.base, x)
                .map(|n| NodeRef::Nodes(vec![n])),
            _ => {
                self.err(
                    path,
                    "give the node by `at` (an interface or node set name) or by `node_at` = [x, y, z], one of them",
                );
                None
            }
        }
    }

    fn dofs(&mut self, path: &KeyPath, d: &Option<DofsFile>) -> Option<DofMask> {
        let names = ["all", "translations", "rotations"];
        match d {
            None => Some(DofMask::ALL),
            Some(DofsFile::Named(n)) => match n.as_str() {
                "all" => Some(DofMask::ALL),
                "translations" => Some(DofMask::TRANSLATIONS),
                "rotations" => Some(DofMask::ROTATIONS),
                other => {
                    let mut all: Vec<String> = names.iter().map(|s| s.to_string()).collect();
                    all.extend(DOF_NAMES.iter().map(|s| s.to_string()));
                    let hint = if DOF_NAMES.contains(&other) {
                        format!("; a single dof is a list: dofs = [\"{other}\"]")
                    } else {
                        let close = close_matches(other, all.iter().map(String::as_str));
                        if close.is_empty() {
                            String::new()
                        } else {
                            format!("; did you mean {}?", quote_list(&close, "or"))
                        }
                    };
                    self.err(
                        path,
                        format!("unknown dofs '{other}'{hint} (use \"all\", \"translations\", \"rotations\" or a list of ux, uy, uz, rx, ry, rz)"),
                    );
                    None
                }
            },
            Some(DofsFile::List(list)) => {
                let mut mask = [false; 6];
                let mut ok = true;
                for (i, n) in list.iter().enumerate() {
                    match DOF_NAMES.iter().position(|d| d == n) {
                        Some(k) => mask[k] = true,
                        None => {
                            self.err(
                                &path.index(i),
                                unknown_reference("dof", n, &DOF_NAMES.map(String::from)),
                            );
                            ok = false;
                        }
                    }
                }
                if list.is_empty() {
                    self.err(path, "the dof list is empty");
                    ok = false;
                }
                ok.then_some(DofMask(mask))
            }
        }
    }

    fn supports(&mut self, path: &KeyPath, part: &Part, list: &Option<Vec<SupportFile>>) -> Option<Vec<SupportSpec>> {
        let mut out = Vec::new();
        let mut ok = true;
        for (i, s) in list.iter().flatten().enumerate() {
            let sp = path.key("supports").index(i);
            let at = self.node_ref(&sp, part, &s.at, &s.node_at);
            let dofs = self.dofs(&sp.key("dofs"), &s.dofs);
            match (at, dofs) {
                (Some(at), Some(dofs)) => out.push(SupportSpec { at, dofs }),
                _ => ok = false,
            }
        }
        ok.then_some(out)
    }

    fn loads(&mut self, path: &KeyPath, part: &Part, list: &Option<Vec<NodalLoadFile>>) -> Option<Vec<LoadSpec>> {
        // Missing: the registry's check reported it.
        let list = list.as_ref()?;
        if list.is_empty() {
            self.err(
                &path.key("loads"),
                "no loads: a static analysis needs at least one load",
            );
            return None;
        }
        let mut out = Vec::new();
        let mut ok = true;
        for (i, l) in list.iter().enumerate() {
            let lp = path.key("loads").index(i);
            let Some(at) = self.node_ref(&lp, part, &l.at, &l.node_at) else {
                ok = false;
                continue;
            };
            if let NodeRef::Nodes(nodes) = &at {
                if nodes.len() != 1 {
                    self.err(
                        &lp.key("at"),
                        format!(
                            "node set '{}' has {} nodes; a load acts at one node (to spread a load over a surface, define an RBE3 interface on it and load the interface)",
                            l.at.as_deref().unwrap_or(""),
                            nodes.len()
                        ),
                    );
                    ok = false;
                    continue;
                }
            }
            let zero = [0.0; 3];
            let force = self.finite3(&lp.key("force"), l.force.as_ref().unwrap_or(&zero), "the force [N]");
            let moment = self.finite3(
                &lp.key("moment"),
                l.moment.as_ref().unwrap_or(&zero),
                "the moment [N m]",
            );
            let (Some(force), Some(moment)) = (force, moment) else {
                ok = false;
                continue;
            };
            if l.force.is_none() && l.moment.is_none() {
                self.err(&lp, "missing key `force` [N] or `moment` [N m]");
                ok = false;
                continue;
            }
            if part.kind == PartKind::Solid && moment != Vector3::zeros() && matches!(at, NodeRef::Nodes(_)) {
                self.err(
                    &lp.key("moment"),
                    "a solid's mesh nodes have no rotations: put the moment on an interface",
                );
                ok = false;
                continue;
            }
            out.push(LoadSpec { at, force, moment });
        }
        ok.then_some(out)
    }

    /// The analysis's name (`default` without `name`), checked as a file name and unique.
    fn analysis_name(&mut self, path: &KeyPath, a: &AnalysisFile, default: String) -> Option<String> {
        let name = a.name.clone().unwrap_or(default);
        if let Err(e) = check_name(&name) {
            self.err(&path.key("name"), e);
            return None;
        }
        if self.lookup("analysis", &name).is_some() {
            let at = if a.name.is_some() {
                path.key("name")
            } else {
                path.clone()
            };
            self.err(
                &at,
                format!("an analysis named '{name}' is already defined (analyses name their results folders: give each a unique `name`)"),
            );
            return None;
        }
        Some(name)
    }

    fn analyses(
        &mut self,
        list: &[AnalysisFile],
        parts: &mut [(String, Option<Part>)],
        mechanism: &Mechanism,
    ) -> Vec<Analysis> {
        let mut out: Vec<Analysis> = Vec::new();
        let part_names: Vec<String> = parts.iter().map(|(n, _)| n.clone()).collect();
        for (i, a) in list.iter().enumerate() {
            let path = KeyPath::root().key("analyses").index(i);
            let analysis = match a.kind {
                AnalysisKind::Static | AnalysisKind::Modal | AnalysisKind::Reduce => {
                    self.part_analysis(path, a, parts, &part_names)
                }
                AnalysisKind::Equilibrium
                | AnalysisKind::Dynamic
                | AnalysisKind::Linearized
                | AnalysisKind::Buckling => self.mechanism_analysis(path, a, mechanism, &out),
            };
            match analysis {
                Some(analysis) => {
                    self.register("analysis", &analysis.name, out.len());
                    out.push(analysis);
                }
                // A later `start` naming it is not reported again as unknown.
                None => {
                    if let Some(name) = &a.name {
                        self.mark_failed("analysis", name);
                    }
                }
            }
        }
        out
    }

    /// An analysis of the mechanism; `done`: the analyses before it, which `start` may name.
    fn mechanism_analysis(
        &mut self,
        path: KeyPath,
        a: &AnalysisFile,
        mechanism: &Mechanism,
        done: &[Analysis],
    ) -> Option<Analysis> {
        let kind = a.kind.name();
        // Bodies and point masses that failed their own checks are reported there: the
        // mechanism is not missing, only invalid.
        let invalid_only = self
            .failed
            .iter()
            .any(|f| f.starts_with("body:") || f.starts_with("point_mass:"));
        if mechanism.is_empty() && invalid_only {
            return None;
        }
        if mechanism.is_empty() {
            self.err(
                &path.key("type"),
                format!("a '{kind}' analysis runs on the mechanism, and the study defines none ([[bodies]], [[rigid_bodies]] or [[point_masses]])"),
            );
            return None;
        }
        let spec = self.mbs_analysis(&path, a)?;
        let name = self.analysis_name(&path, a, kind.to_string())?;
        let start = match &a.start {
            None => None,
            Some(from) => match self.lookup("analysis", from) {
                Some(k)
                    if matches!(
                        done[k].spec,
                        AnalysisSpec::Mbs(MbsAnalysis::Equilibrium { .. } | MbsAnalysis::Dynamic { .. })
                    ) =>
                {
                    Some(k)
                }
                Some(_) => {
                    self.err(
                        &path.key("start"),
                        format!("analysis '{from}' ends in no state of the mechanism: `start` names an earlier 'equilibrium' or 'dynamic' analysis"),
                    );
                    return None;
                }
                None if self.has_failed("analysis", from) => return None,
                None => {
                    let names: Vec<String> = done
                        .iter()
                        .filter(|b| {
                            matches!(
                                b.spec,
                                AnalysisSpec::Mbs(MbsAnalysis::Equilibrium { .. } | MbsAnalysis::Dynamic { .. })
                            )
                        })
                        .map(|b| b.name.clone())
                        .collect();
                    self.err(
                        &path.key("start"),
                        format!(
                            "{}; `start` names an earlier 'equilibrium' or 'dynamic' analysis",
                            unknown_reference("analysis", from, &names)
                        ),
                    );
                    return None;
                }
            },
        };
        Some(Analysis {
            name,
            path,
            part: None,
            spec: AnalysisSpec::Mbs(spec),
            start,
        })
    }

    /// A `static`, `modal` or `reduce` analysis of a part.
    fn part_analysis(
        &mut self,
        path: KeyPath,
        a: &AnalysisFile,
        parts: &mut [(String, Option<Part>)],
        part_names: &[String],
    ) -> Option<Analysis> {
        let kind = a.kind.name();
        self.only_keys(&path, "analyses", kind, &format!("a '{kind}' analysis"));
        // Missing: the registry's check reported it.
        let part_name = a.part.as_ref()?;
        let Some(listed) = self.lookup("part", part_name) else {
            self.err(&path.key("part"), unknown_reference("part", part_name, part_names));
            return None;
        };
        // A part that failed validation has its own errors already.
        let part = parts[listed].1.as_ref()?;
        let index = parts[..listed].iter().filter(|(_, p)| p.is_some()).count();
        let name = self.analysis_name(&path, a, format!("{kind}-{part_name}"))?;
        let spec = match a.kind {
            AnalysisKind::Static => {
                let supports = self.supports(&path, part, &a.supports);
                let loads = self.loads(&path, part, &a.loads);
                match (supports, loads) {
                    (Some(supports), Some(loads)) => AnalysisSpec::Static { supports, loads },
                    _ => return None,
                }
            }
            AnalysisKind::Modal => {
                let supports = self.supports(&path, part, &a.supports);
                let modes = self.require(&path, a.modes, "modes", "number of modes")?;
                keys::in_range("analyses", "modes", modes as f64).then_some(())?;
                let solver = match a.solver {
                    Some(SolverFile::Dense) => Solver::Dense,
                    Some(SolverFile::Sparse) => Solver::Sparse,
                    _ => Solver::Auto,
                };
                let supports = supports?;
                AnalysisSpec::Modal {
                    modes,
                    solver,
                    supports,
                }
            }
            AnalysisKind::Reduce => {
                if part.reduction.is_none() {
                    self.err(
                        &path.key("part"),
                        format!(
                            "part '{part_name}' has no [parts.reduction] (modes or cut-off frequency) to reduce with"
                        ),
                    );
                    return None;
                }
                AnalysisSpec::Reduce
            }
            _ => return None,
        };
        // The supports change the spiders (an RBE3 avoids supported dofs, an RBE2 cannot
        // take them): build once to report a conflict here rather than mid-run (on the
        // part's own model, restored after: no copy).
        if let AnalysisSpec::Static { supports, .. } | AnalysisSpec::Modal { supports, .. } = &spec {
            let part = parts[listed].1.as_mut()?;
            let free = part
                .check_build(supports, |b| fe_model::DofMap::new(&b.model).map(|d| d.n_free()))
                .and_then(|free| free);
            match free {
                Err(e) => {
                    self.err(
                        &path.key("supports"),
                        format!("with these supports, part '{part_name}': {e}"),
                    );
                    return None;
                }
                Ok(free) => {
                    // A model has as many modes as free dofs.
                    if let AnalysisSpec::Modal { modes, .. } = &spec {
                        if *modes > free {
                            self.err(
                                &path.key("modes"),
                                format!("{modes} modes asked, but part '{part_name}' on these supports has {free} free dofs, so at most {free} modes"),
                            );
                            return None;
                        }
                    }
                }
            }
        }
        Some(Analysis {
            name,
            path,
            part: Some(index),
            spec,
            start: None,
        })
    }
}
