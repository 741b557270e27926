//! `flexmbs.Study` (a study file as an editable, validated document: [`study::Document`]) and
//! `flexmbs.Simulation` (a dynamic analysis stepped from Python: [`study::Simulation`]).
//!
//! Runs go through the study crate's one path, the one the `flexmbs` program takes: the same
//! validation and located errors, the same results folder and reduced-body cache. The raw
//! results come back as plain Python data (dicts, lists, numpy arrays) that the pure-Python
//! `flexmbs.results` module wraps.

use crate::errors::{key_err, lookup_err, simulation_err, to_py_err, unknown_name, StudyError};
use crate::rbody::ReducedBody;
use crate::signature::{Class, Member::*};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use std::path::PathBuf;
use study::output::observer::{Cell, Recorded, Recorder};

/// A study: a study file held in memory, read and changed value by value through key paths
/// (`parts.rod.reduction.modes`, `sections[0].d`, `drivers.crank-speed.function.speed`), with
/// the validation of `flexmbs check` after every change.
#[pyclass(module = "flexmbs", name = "Study")]
#[derive(Clone)]
pub struct Study {
    doc: study::Document,
}

/// A Python value as the TOML value text [`study::Document::set`] takes: booleans, integers,
/// floats (shortest text that reads back to the same `f64`; `nan`, `inf`), strings, lists,
/// tuples and numpy arrays (as arrays), dicts (as inline tables).
pub(crate) fn toml_text(value: &Bound<'_, PyAny>) -> PyResult<String> {
    if value.is_instance_of::<PyBool>() {
        return Ok(if value.extract::<bool>()? { "true" } else { "false" }.into());
    }
    if value.is_instance_of::<PyInt>() {
        return Ok(value.extract::<i64>()?.to_string());
    }
    if value.is_instance_of::<PyFloat>() {
        return Ok(float_text(value.extract::<f64>()?));
    }
    if value.is_instance_of::<PyString>() {
        let s: String = value.extract()?;
        // JSON's string escapes (\" \\ \n \t \uXXXX ...) are all valid in a TOML basic string.
        return Ok(serde_json::to_string(&s).expect("a string serialises"));
    }
    if value.is_instance_of::<PyDict>() {
        let d = value.cast::<PyDict>()?;
        let mut items = Vec::new();
        for (k, v) in d.iter() {
            let k: String = k.extract()?;
            let bare = !k.is_empty() && k.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            let key = if bare {
                k
            } else {
                serde_json::to_string(&k).expect("a string serialises")
            };
            items.push(format!("{key} = {}", toml_text(&v)?));
        }
        return Ok(format!("{{ {} }}", items.join(", ")));
    }
    if value.is_instance_of::<PyList>() || value.is_instance_of::<PyTuple>() {
        let items: Vec<String> = value.try_iter()?.map(|v| toml_text(&v?)).collect::<PyResult<_>>()?;
        return Ok(format!("[{}]", items.join(", ")));
    }
    // numpy scalars and arrays, and anything else with `tolist` or an index/float conversion.
    if value.hasattr("tolist")? {
        let list = value.call_method0("tolist")?;
        if !list.is(value) {
            return toml_text(&list);
        }
    }
    if let Ok(i) = value.extract::<i64>() {
        return Ok(i.to_string());
    }
    if let Ok(x) = value.extract::<f64>() {
        return Ok(float_text(x));
    }
    Err(pyo3::exceptions::PyTypeError::new_err(format!(
        "a study value must be a bool, number, string, list or dict, not {}",
        value.get_type().name()?
    )))
}

/// A float as TOML text: Rust's shortest round-trip text, with TOML's `nan` and `inf`.
fn float_text(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        let s = format!("{x:?}");
        // `1e-5` is valid TOML; `5` (from a whole float) would be an integer: keep a `.0`.
        if s.contains(['.', 'e', 'E']) {
            s
        } else {
            format!("{s}.0")
        }
    }
}

/// JSON-like data as Python objects (through the json module: numbers, strings, lists, dicts).
pub(crate) fn json_to_py<'py>(py: Python<'py>, value: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    let json = py.import("json")?;
    json.call_method1("loads", (value.to_string(),))
}

/// The columns of a result table: numbers as a float array, text columns as lists.
fn table_dict<'py>(py: Python<'py>, t: &study::output::observer::Table) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &t.name)?;
    d.set_item("columns", &t.columns)?;
    let data = PyDict::new(py);
    for (k, c) in t.columns.iter().enumerate() {
        let cells: Vec<&Cell> = t.rows.iter().filter_map(|r| r.get(k)).collect();
        let numeric = cells
            .iter()
            .all(|c| matches!(c, Cell::Int(_) | Cell::Num(_) | Cell::Empty));
        if numeric {
            let v: Vec<f64> = cells.iter().map(|c| c.as_f64().unwrap_or(f64::NAN)).collect();
            data.set_item(c, PyArray1::from_vec(py, v))?;
        } else {
            let v: Vec<Option<String>> = cells
                .iter()
                .map(|c| match c {
                    Cell::Text(s) => Some(s.clone()),
                    Cell::Int(i) => Some(i.to_string()),
                    Cell::Num(x) => Some(x.to_string()),
                    Cell::Empty => None,
                })
                .collect();
            data.set_item(c, v)?;
        }
    }
    d.set_item("data", data)?;
    Ok(d)
}

/// One analysis as recorded: name, kind, tables, sensors (abscissa and a 2-D array of columns
/// per sensor) and its summary.
fn recorded_dict<'py>(py: Python<'py>, r: &Recorded) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("name", &r.name)?;
    d.set_item("kind", &r.kind)?;
    let tables = PyList::empty(py);
    for t in &r.tables {
        tables.append(table_dict(py, t)?)?;
    }
    d.set_item("tables", tables)?;
    match &r.sensors {
        Some(h) => {
            let s = PyDict::new(py);
            s.set_item("x_label", &h.x_label)?;
            s.set_item("x", PyArray1::from_slice(py, &h.x))?;
            let groups = PyList::empty(py);
            for (g, rows) in h.groups.iter().zip(&h.rows) {
                let width = g.columns.len();
                let values = Array2::from_shape_fn((rows.len(), width), |(i, j)| {
                    rows[i].get(j).copied().unwrap_or(f64::NAN)
                });
                let gd = PyDict::new(py);
                gd.set_item("name", &g.name)?;
                gd.set_item("columns", &g.columns)?;
                gd.set_item("values", values.into_pyarray(py))?;
                groups.append(gd)?;
            }
            s.set_item("groups", groups)?;
            d.set_item("sensors", s)?;
        }
        None => d.set_item("sensors", py.None())?,
    }
    match &r.summary {
        Some(s) => d.set_item(
            "summary",
            json_to_py(py, &serde_json::to_value(s).map_err(to_json_err)?)?,
        )?,
        None => d.set_item("summary", py.None())?,
    }
    Ok(d)
}

fn to_json_err(e: serde_json::Error) -> PyErr {
    crate::errors::FlexmbsError::new_err(format!("cannot convert the summary: {e}"))
}

fn options(results_dir: Option<PathBuf>, cache: Option<PathBuf>, t_end: Option<f64>) -> study::Options {
    study::Options {
        out: results_dir,
        cache,
        t_end,
        foreign: Default::default(),
    }
}

/// `Study` as the type stubs declare it.
pub(crate) const STUB: Class = Class {
    name: "Study",
    bases: "",
    members: &[
        Static("load", "(path: _Path) -> \"Study\""),
        Static(
            "from_toml",
            "(text: str, base_dir: Optional[_Path] = None, name: Optional[str] = None) -> \"Study\"",
        ),
        Property("path", "str"),
        Property("base_dir", "str"),
        Property("text", "str"),
        Property("analyses", "List[str]"),
        Property("parts", "List[str]"),
        Method("validate", "(self) -> None"),
        BySection("get", "(self, key: str) -> Any"),
        Method("set", "(self, key: str, value: Any) -> None"),
        Method("update", "(self, values: Dict[str, Any]) -> None"),
        Method("remove", "(self, key: str) -> None"),
        BySection("__getitem__", "(self, key: str) -> Any"),
        Method("__setitem__", "(self, key: str, value: Any) -> None"),
        Method("__delitem__", "(self, key: str) -> None"),
        Method(
            "run",
            "(self, analysis: Optional[str] = None, results_dir: Optional[_Path] = None, cache: Optional[_Path] = None, t_end: Optional[float] = None, forces: Optional[ForceLaw] = None) -> Results",
        ),
        Method(
            "reduce",
            "(self, part: Optional[str] = None, cache: Optional[_Path] = None) -> List[Tuple[str, ReducedBody]]",
        ),
        Method("show", "(self, cache: Optional[_Path] = None, height: int = 560) -> Page"),
        Method(
            "simulation",
            "(self, analysis: Optional[str] = None, cache: Optional[_Path] = None, results_dir: Optional[_Path] = None, forces: Optional[ForceLaw] = None) -> \"Simulation\"",
        ),
        Method(
            "export_fmu",
            "(self, path: _Path, analysis: Optional[str] = None, library: Optional[_Path] = None, fmi_version: int = 2) -> Dict[str, Any]",
        ),
    ],
};

impl Study {
    /// [`Study::run`]'s raw results (dicts and numpy arrays), which `flexmbs.results.Results`
    /// wraps; on a failure, the exception with them as `partial`.
    fn raw_results<'py>(
        &self,
        py: Python<'py>,
        analysis: Option<&str>,
        opts: &study::Options,
        forces: &study::Forces,
    ) -> PyResult<Bound<'py, PyDict>> {
        let st = self.doc.study().map_err(|e| to_py_err(py, &e))?;
        let selection =
            study::Selection::of(&st, analysis).map_err(|e| unknown_name(py, e.what, &e.name, &e.defined))?;
        let dir = opts.results_dir(&st);
        let mut recorder = Recorder::default();
        let outcome = py.detach(|| study::run_selected_with(&st, opts, selection, forces, &mut recorder));
        let d = PyDict::new(py);
        d.set_item("results_dir", dir.display().to_string())?;
        let analyses = PyList::empty(py);
        for r in &recorder.analyses {
            analyses.append(recorded_dict(py, r)?)?;
        }
        d.set_item("analyses", analyses)?;
        d.set_item("messages", &recorder.progress)?;
        match outcome {
            Ok(summary) => {
                d.set_item(
                    "summary",
                    json_to_py(py, &serde_json::to_value(&summary).map_err(to_json_err)?)?,
                )?;
                Ok(d)
            }
            Err(e) => {
                let err = to_py_err(py, &*e);
                // The partial results ride on the exception.
                err.value(py).setattr("partial", d)?;
                Err(err)
            }
        }
    }
}

#[pymethods]
impl Study {
    /// Reads and validates the study file at `path`. Raises `StudyError` (with `file`, `line`,
    /// `column`, `key` and `errors`) when it is not valid.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let doc = study::Document::open(&path).map_err(|e| to_py_err(py, &*e))?;
        let s = Self { doc };
        s.validate(py)?;
        Ok(s)
    }

    /// A study from TOML `text`. `base_dir` (default: the current folder) anchors the study's
    /// relative paths (meshes, tables, `.rbody` files, the results folder and the cache);
    /// `name` is the file name errors and the results folder use (default `study.toml`).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None, name=None))]
    fn from_toml(py: Python<'_>, text: &str, base_dir: Option<PathBuf>, name: Option<String>) -> PyResult<Self> {
        let dir = match base_dir {
            Some(d) => d,
            None => std::env::current_dir()?,
        };
        let file = name.unwrap_or_else(|| "study.toml".into());
        let file_name = std::path::Path::new(&file)
            .file_name()
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("study.toml"));
        let doc = study::Document::from_text(text, &dir.join(file_name)).map_err(|e| to_py_err(py, &*e))?;
        let s = Self { doc };
        s.validate(py)?;
        Ok(s)
    }

    /// The study file this study came from (or the name it was given).
    #[getter]
    fn path(&self) -> String {
        self.doc.path.display().to_string()
    }

    /// The folder relative paths of the study are taken from.
    #[getter]
    fn base_dir(&self) -> String {
        self.doc
            .path
            .parent()
            .map(|p| p.display().to_string())
            .unwrap_or_else(|| ".".into())
    }

    /// The study as TOML text now (comments and layout of the original kept).
    #[getter]
    fn text(&self) -> String {
        self.doc.text()
    }

    /// Checks the study as `flexmbs check` does; raises `StudyError` when it is not valid.
    fn validate(&self, py: Python<'_>) -> PyResult<()> {
        self.doc.study().map(|_| ()).map_err(|e| to_py_err(py, &e))
    }

    /// The value at key path `key` (numbers, strings, lists; tables as dicts). Raises
    /// `KeyPathError` for a path that leads nowhere.
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let v = self.doc.get(key).map_err(|e| key_err(py, &*e, key))?;
        json_to_py(py, &v)
    }

    /// Sets the value at `key` and validates the study. A value the study refuses raises
    /// `StudyError` located at the value (file, line, column, key) and is not kept. A dict
    /// given to a table (`study["sections.rod"] = {"name": "rod", "shape": "values", ...}`)
    /// replaces the whole table, so keys that exclude each other can be switched.
    fn set(&mut self, py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let text = toml_text(value)?;
        self.doc.set(key, &text).map_err(|e| key_err(py, &*e, key))
    }

    /// Sets several values (a dict of key path to value), then validates once: for changes that
    /// are only valid together. On an error, none of them is kept.
    fn update(&mut self, py: Python<'_>, values: &Bound<'_, PyDict>) -> PyResult<()> {
        let mut doc = self.doc.clone();
        for (k, v) in values.iter() {
            let key: String = k.extract()?;
            doc.set_unchecked(&key, &toml_text(&v)?)
                .map_err(|e| key_err(py, &*e, &key))?;
        }
        doc.study().map_err(|e| to_py_err(py, &e))?;
        self.doc = doc;
        Ok(())
    }

    /// Removes the value or table at `key` (`del study[key]`) and validates the study. A removal
    /// the study refuses (a required key, a name still referred to) raises `StudyError` located
    /// as for `set`, and is not kept; a path that leads nowhere raises `KeyPathError`.
    fn remove(&mut self, py: Python<'_>, key: &str) -> PyResult<()> {
        self.doc.remove(key).map_err(|e| key_err(py, &*e, key))
    }

    fn __delitem__(&mut self, py: Python<'_>, key: &str) -> PyResult<()> {
        self.remove(py, key)
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.get(py, key)
    }

    fn __setitem__(&mut self, py: Python<'_>, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set(py, key, value)
    }

    /// Names of the analyses, in the order they run.
    #[getter]
    fn analyses(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let s = self.doc.study().map_err(|e| to_py_err(py, &e))?;
        Ok(s.analyses.iter().map(|a| a.name.clone()).collect())
    }

    /// Names of the parts.
    #[getter]
    fn parts(&self, py: Python<'_>) -> PyResult<Vec<String>> {
        let s = self.doc.study().map_err(|e| to_py_err(py, &e))?;
        Ok(s.parts.iter().map(|p| p.name.clone()).collect())
    }

    /// Writes the dynamic analysis `analysis` (default: the study's only one) as an FMI 2.0
    /// (`fmi_version=2`, the default) or FMI 3.0 (`fmi_version=3`) Co-Simulation FMU at `path`, as `flexmbs export-fmu` does (docs/fmu.md): inputs the
    /// actuators and point loads, outputs the sensors, parameters the study's `[fmu]` table.
    /// `library`: the FMU's binary, the shared library of `flexmbs-fmu` (default: the
    /// environment variable `FLEXMBS_FMU_LIBRARY`; build it with
    /// `cargo build --release -p flexmbs-fmu`). Returns a dict: `path`, `analysis`,
    /// `model_identifier`, `fmi_version` (`"2.0"` or `"3.0"`), `inputs`, `outputs`, `parameters` (variable
    /// names).
    #[pyo3(signature = (path, analysis=None, library=None, fmi_version=2))]
    fn export_fmu<'py>(
        &self,
        py: Python<'py>,
        path: PathBuf,
        analysis: Option<String>,
        library: Option<PathBuf>,
        fmi_version: u8,
    ) -> PyResult<Bound<'py, PyDict>> {
        let version = study::fmu::FmiVersion::parse(&fmi_version.to_string()).map_err(|e| to_py_err(py, &*e))?;
        let library = match library {
            Some(l) => l,
            None => study::fmu::library_path().map_err(|e| to_py_err(py, &*e))?,
        };
        let doc = &self.doc;
        let exported = py
            .detach(|| study::fmu::export_document(doc, analysis.as_deref(), version, &library, &path))
            .map_err(|e| to_py_err(py, &*e))?;
        let d = PyDict::new(py);
        d.set_item("path", exported.path.display().to_string())?;
        d.set_item("analysis", &exported.analysis)?;
        d.set_item("model_identifier", &exported.model_identifier)?;
        d.set_item("fmi_version", exported.version.name())?;
        for (key, causality) in [("inputs", "input"), ("outputs", "output"), ("parameters", "parameter")] {
            let names: Vec<&str> = exported
                .variables
                .iter()
                .filter(|v| v.causality() == causality)
                .map(|v| v.name.as_str())
                .collect();
            d.set_item(key, names)?;
        }
        Ok(d)
    }

    /// Runs the analyses (all, or the one named `analysis`) as `flexmbs run` does and returns a
    /// `flexmbs.Results` (sensors, tables and the summary as numpy arrays and dicts): results go
    /// into the results folder (`results_dir`, default `<study>-results` beside the study file),
    /// reduced bodies through the cache (`cache`, default `.flexmbs-cache` beside it); `t_end`
    /// ends every dynamic analysis earlier. `forces`: a `ForceLaw` evaluated in every Newton
    /// iteration of the analyses of the mechanism. A solver failure raises `SolveError` whose
    /// `partial` holds the `Results` computed before it (also written to the folder).
    #[pyo3(signature = (analysis=None, results_dir=None, cache=None, t_end=None, forces=None))]
    fn run<'py>(
        &self,
        py: Python<'py>,
        analysis: Option<String>,
        results_dir: Option<PathBuf>,
        cache: Option<PathBuf>,
        t_end: Option<f64>,
        forces: Option<PyRef<'_, crate::force_law::ForceLaw>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let forces = forces.and_then(|f| f.forces());
        let wrap = |raw: Bound<'py, PyAny>| -> PyResult<Bound<'py, PyAny>> {
            py.import("flexmbs.results")?.getattr("Results")?.call1((raw,))
        };
        let opts = options(results_dir, cache, t_end);
        match self.raw_results(py, analysis.as_deref(), &opts, &forces) {
            Ok(raw) => wrap(raw.into_any()),
            Err(e) => {
                let value = e.value(py);
                if let Ok(partial) = value.getattr("partial") {
                    if !partial.is_none() {
                        value.setattr("partial", wrap(partial)?)?;
                    }
                }
                Err(e)
            }
        }
    }

    /// The model before it runs, on a results page (`view.html`'s viewer): the mechanism's
    /// bodies, interfaces, joints, supports, point masses and loads at the initial state, the
    /// parts reduced through the cache (`cache`, default `.flexmbs-cache` beside the study file).
    /// Displayed inline in Jupyter when there is a notebook kernel; returns the page's HTML
    /// (a `flexmbs.Page`, a `str`).
    #[pyo3(signature = (cache=None, height=560))]
    fn show<'py>(&self, py: Python<'py>, cache: Option<PathBuf>, height: usize) -> PyResult<Bound<'py, PyAny>> {
        let st = self.doc.study().map_err(|e| to_py_err(py, &e))?;
        let opts = options(None, cache, None);
        let html = py
            .detach(|| study::model_page(&st, &opts, &mut ()))
            .map_err(|e| to_py_err(py, &*e))?;
        let results = py.import("flexmbs.results")?;
        let page = results.getattr("Page")?.call1((html,))?;
        page.call_method1("show", (height,))?;
        Ok(page)
    }

    /// Reduces the parts that have a `[parts.reduction]` (or the one named `part`) through the
    /// cache, as `flexmbs reduce` does without writing a results folder; returns
    /// `{part name: ReducedBody}`.
    #[pyo3(signature = (part=None, cache=None))]
    fn reduce(
        &self,
        py: Python<'_>,
        part: Option<String>,
        cache: Option<PathBuf>,
    ) -> PyResult<Vec<(String, ReducedBody)>> {
        let st = self.doc.study().map_err(|e| to_py_err(py, &e))?;
        let opts = options(None, cache, None);
        let cache_dir = opts.cache_dir(&st);
        let targets: Vec<usize> = match &part {
            Some(name) => vec![st.part(name).map_err(StudyError::new_err)?],
            None => (0..st.parts.len())
                .filter(|&i| st.parts[i].reduction.is_some())
                .collect(),
        };
        let mut out = Vec::new();
        for i in targets {
            let p = &st.parts[i];
            let reduced = py
                .detach(|| study::reduce_part(&st, p, &cache_dir, &mut ()))
                .map_err(|e| to_py_err(py, &*e))?;
            out.push((
                p.name.clone(),
                ReducedBody {
                    body: std::sync::Arc::unwrap_or_clone(reduced.body),
                },
            ));
        }
        Ok(out)
    }

    /// Starts the dynamic analysis `analysis` (default: the study's only dynamic analysis) for
    /// stepping from Python; reduced bodies come through the cache as in a run. With
    /// `results_dir`, the simulation writes the results folder of the analysis as it steps
    /// (the files `run(analysis)` writes), until `finish_results()`. `forces`: a `ForceLaw`
    /// evaluated in every Newton iteration of its steps.
    #[pyo3(signature = (analysis=None, cache=None, results_dir=None, forces=None))]
    fn simulation(
        &self,
        py: Python<'_>,
        analysis: Option<String>,
        cache: Option<PathBuf>,
        results_dir: Option<PathBuf>,
        forces: Option<PyRef<'_, crate::force_law::ForceLaw>>,
    ) -> PyResult<Simulation> {
        let forces = forces.and_then(|f| f.forces());
        let st = self.doc.study().map_err(|e| to_py_err(py, &e))?;
        let name = match analysis {
            Some(n) => n,
            None => st
                .dynamic_analysis(None)
                .map_err(|e| StudyError::new_err(e.to_string()))?,
        };
        let writing = results_dir.is_some();
        let opts = options(results_dir, cache, None);
        let sim = py.detach(|| match writing {
            true => study::Simulation::writing_results_with(&st, &name, &opts, &forces),
            false => study::Simulation::new_with(&st, &name, &opts, &forces),
        });
        let sim = sim.map_err(|e| {
            let names: Vec<String> = st.analyses.iter().map(|a| a.name.clone()).collect();
            lookup_err(py, &*e, "analysis", &name, &names)
        })?;
        let end_time = sim.end_time();
        Ok(Simulation {
            sim,
            analysis: name,
            end_time,
        })
    }

    fn __repr__(&self) -> String {
        format!("Study({:?})", self.doc.path.display().to_string())
    }
}

/// A dynamic analysis stepped from Python (`Study.simulation`): `step()`, `advance_to(t)`,
/// every sensor and the full state between steps, and the values of named loads set by a
/// controller.
#[pyclass(module = "flexmbs", name = "Simulation", unsendable)]
pub struct Simulation {
    sim: study::Simulation,
    /// The analysis being stepped.
    #[pyo3(get)]
    analysis: String,
    /// The analysis' end time [s] (stepping past it is allowed).
    #[pyo3(get)]
    end_time: f64,
}

impl Simulation {
    /// A failure to read the sensors as the package's exception: a sensor that is not finite
    /// is a `SolveError` located at the sensor in the study, as a failed step is.
    fn sensor_err(&self, py: Python<'_>, e: &(dyn std::error::Error + 'static)) -> PyErr {
        match e.downcast_ref::<mbs::SolveError>() {
            Some(s) => simulation_err(py, s, &self.analysis, self.sim.steps(), self.sim.locate(s)),
            None => to_py_err(py, e),
        }
    }
}

/// `Simulation` as the type stubs declare it.
pub(crate) const SIMULATION_STUB: Class = Class {
    name: "Simulation",
    bases: "",
    members: &[
        Property("analysis", "str"),
        Property("time", "float"),
        Property("dt", "float"),
        Property("end_time", "float"),
        Property("steps", "int"),
        Property("sensor_names", "List[str]"),
        Property("load_names", "List[str]"),
        Property("actuator_names", "List[str]"),
        Method("step", "(self, dt: Optional[float] = None) -> int"),
        Method("advance_to", "(self, t: float) -> int"),
        Method("finish_results", "(self) -> Optional[Dict[str, Any]]"),
        Method("sensor_columns", "(self, name: str) -> List[str]"),
        Method("sensor", "(self, name: str) -> _Array"),
        Method("sensors", "(self) -> Dict[str, _Array]"),
        Method("state", "(self) -> Dict[str, Any]"),
        Method("node_motions", "(self) -> Dict[str, Any]"),
        Method(
            "set_load",
            "(self, name: str, force: Optional[_Vec3] = None, moment: Optional[_Vec3] = None) -> None",
        ),
        Method("set_actuator", "(self, name: str, effort: Optional[float]) -> None"),
        Method("release_actuator", "(self, name: str) -> None"),
        Method("actuator_effort", "(self, name: str) -> float"),
        Method("held_actuator", "(self, name: str) -> Optional[float]"),
    ],
};

#[pymethods]
impl Simulation {
    /// The time reached [s].
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// The analysis' step size [s].
    #[getter]
    fn dt(&self) -> f64 {
        self.sim.step_size()
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> usize {
        self.sim.steps()
    }

    /// One time step under the analysis' step control, as `run()` takes it: a fixed step of
    /// `dt` whose failure is retried with halved steps down to `dt_min`, or one adaptive
    /// step; with `dt`, one step of that size (retried likewise), after which the analysis'
    /// steps go on. Returns the Newton iterations it took (of every substep). A step that
    /// fails even at the smallest step raises `SolveError` (`time`, `step`, `residual`,
    /// `analysis`; `file`, `line`, `key` of the body it failed at) and leaves the state at the
    /// last converged step: the simulation can go on (with a changed load or actuator, say).
    #[pyo3(signature = (dt=None))]
    fn step(&mut self, py: Python<'_>, dt: Option<f64>) -> PyResult<usize> {
        if let Some(h) = dt {
            if !(h > 0.0 && h.is_finite()) {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "step(dt={h}): the step must be a positive number of seconds"
                )));
            }
        }
        let steps = self.sim.steps();
        let sim = &mut self.sim;
        let taken = py.detach(|| match dt {
            Some(h) => sim.step_by(h),
            None => sim.step(),
        });
        let taken =
            taken.map_err(|f| simulation_err(py, &f.error, &self.analysis, steps, self.sim.locate(&f.error)))?;
        // The residuals before each correction and at convergence, of every substep.
        Ok(taken.reports.iter().map(|r| r.residuals.len().saturating_sub(1)).sum())
    }

    /// Steps (as `step()` does) until the time reaches `t`; returns the number of steps taken.
    fn advance_to(&mut self, py: Python<'_>, t: f64) -> PyResult<usize> {
        let sim = &mut self.sim;
        let result = py.detach(|| sim.advance_to(t));
        result.map_err(|f| {
            simulation_err(
                py,
                &f.error,
                &self.analysis,
                self.sim.steps(),
                self.sim.locate(&f.error),
            )
        })
    }

    /// Ends the results folder of a simulation started with `results_dir`: writes the rows
    /// still waiting, the report and the summary (what `run()` writes for the analysis) and
    /// returns the summary (a dict); `None` when the simulation writes no folder or its
    /// results have ended. The simulation can step on. A file that could not be written, or
    /// a sensor that is no longer finite, raises (the summary says `failed`). A simulation
    /// that is dropped ends its results the same way.
    fn finish_results<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let summary = self.sim.finish_results().map_err(|e| to_py_err(py, &*e))?;
        match summary {
            None => Ok(None),
            Some(s) => Ok(Some(json_to_py(py, &serde_json::to_value(&s).map_err(to_json_err)?)?)),
        }
    }

    /// The names of the study's sensors.
    #[getter]
    fn sensor_names(&self) -> Vec<String> {
        self.sim.sensors().iter().map(|g| g.name.clone()).collect()
    }

    /// Column names (with units) of sensor `name`.
    fn sensor_columns(&self, py: Python<'_>, name: &str) -> PyResult<Vec<String>> {
        match self.sim.sensors().iter().find(|g| g.name == name) {
            Some(g) => Ok(g.columns.clone()),
            None => self
                .sim
                .sensor(name)
                .map(|_| Vec::new())
                .map_err(|e| to_py_err(py, &*e)),
        }
    }

    /// The values of sensor `name` now (numpy array of its columns); only this sensor is
    /// evaluated.
    fn sensor<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let v = self
            .sim
            .sensor(name)
            .map_err(|e| match e.downcast_ref::<mbs::SolveError>() {
                Some(_) => self.sensor_err(py, &*e),
                None => lookup_err(py, &*e, "sensor", name, &self.sensor_names()),
            })?;
        Ok(PyArray1::from_vec(py, v))
    }

    /// Every sensor now: `{name: numpy array of its columns}`.
    fn sensors<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let values = self.sim.read().map_err(|e| self.sensor_err(py, &*e))?;
        let d = PyDict::new(py);
        for (g, v) in self.sim.sensors().iter().zip(values) {
            d.set_item(&g.name, PyArray1::from_vec(py, v))?;
        }
        Ok(d)
    }

    /// The full state: `time`, the unknowns' `labels`, `velocity` and `acceleration`, every
    /// scalar coordinate (`scalars`: joint and modal coordinates, unknown and prescribed) and the
    /// free rotations as unit quaternions (`rotations`, n x 4, [w, x, y, z]).
    fn state<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.sim.state();
        let d = PyDict::new(py);
        d.set_item("time", s.time())?;
        d.set_item("labels", self.sim.system().dof_labels().to_vec())?;
        d.set_item("velocity", PyArray1::from_slice(py, s.velocity()))?;
        d.set_item("acceleration", PyArray1::from_slice(py, s.acceleration()))?;
        let (scalars, rotations) = s.coordinates();
        d.set_item("scalars", PyArray1::from_slice(py, scalars))?;
        let q = Array2::from_shape_fn((rotations.len(), 4), |(i, k)| {
            let r = rotations[i];
            [r.w, r.i, r.j, r.k][k]
        });
        d.set_item("rotations", q.into_pyarray(py))?;
        Ok(d)
    }

    /// Every node's motion: `names`, `position` (n x 3) [m], `orientation` (n x 4 unit
    /// quaternions [w, x, y, z], node axes to global), `velocity`, `angular_velocity` (spatial),
    /// `acceleration`, `angular_acceleration` (n x 3).
    fn node_motions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = self.sim.node_motions();
        let names: Vec<String> = self.sim.system().model().nodes.iter().map(|n| n.name.clone()).collect();
        let n = m.len();
        let d = PyDict::new(py);
        d.set_item("names", names)?;
        let v3 = |f: &dyn Fn(&mbs::NodeMotion) -> nalgebra::Vector3<f64>| {
            Array2::from_shape_fn((n, 3), |(i, k)| f(&m[i])[k])
        };
        d.set_item("position", v3(&|x| x.r).into_pyarray(py))?;
        d.set_item(
            "orientation",
            Array2::from_shape_fn((n, 4), |(i, k)| {
                let q = m[i].R;
                [q.w, q.i, q.j, q.k][k]
            })
            .into_pyarray(py),
        )?;
        d.set_item("velocity", v3(&|x| x.v).into_pyarray(py))?;
        d.set_item("angular_velocity", v3(&|x| x.omega).into_pyarray(py))?;
        d.set_item("acceleration", v3(&|x| x.a).into_pyarray(py))?;
        d.set_item("angular_acceleration", v3(&|x| x.alpha).into_pyarray(py))?;
        Ok(d)
    }

    /// The names of the study's point loads (those `set_load` can change).
    #[getter]
    fn load_names(&self) -> Vec<String> {
        self.sim.load_names().into_iter().map(String::from).collect()
    }

    /// Sets the force [N] and/or moment [N m] of point load `name` (in the load's axes, as in
    /// the study file; the load's time function still multiplies it) from the next step on.
    #[pyo3(signature = (name, force=None, moment=None))]
    fn set_load(
        &mut self,
        py: Python<'_>,
        name: &str,
        force: Option<[f64; 3]>,
        moment: Option<[f64; 3]>,
    ) -> PyResult<()> {
        if force.is_none() && moment.is_none() {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "set_load('{name}'): give force=[fx, fy, fz] and/or moment=[mx, my, mz]"
            )));
        }
        if let Some(f) = force {
            self.sim
                .set_load(name, mbs::LoadKind::Force, f)
                .map_err(|e| to_py_err(py, &*e))?;
        }
        if let Some(m) = moment {
            self.sim
                .set_load(name, mbs::LoadKind::Moment, m)
                .map_err(|e| to_py_err(py, &*e))?;
        }
        Ok(())
    }

    /// The names of the study's actuators (those `set_actuator` can hold).
    #[getter]
    fn actuator_names(&self) -> Vec<String> {
        self.sim.actuator_names().into_iter().map(String::from).collect()
    }

    /// Holds actuator `name` at `effort` [N on a length, N m on an angle] in place of its
    /// `function` or `pid` from the next step on, until `release_actuator(name)` (or
    /// `set_actuator(name, None)`). The `actuator-effort` sensors write the held value.
    fn set_actuator(&mut self, py: Python<'_>, name: &str, effort: Option<f64>) -> PyResult<()> {
        self.sim.set_actuator(name, effort).map_err(|e| to_py_err(py, &*e))
    }

    /// Releases actuator `name` to its `function` or `pid` (a PID resumes from its integral,
    /// frozen while held).
    fn release_actuator(&mut self, py: Python<'_>, name: &str) -> PyResult<()> {
        self.sim.set_actuator(name, None).map_err(|e| to_py_err(py, &*e))
    }

    /// The effort [N or N m] actuator `name` applies now: the held value, or its law's.
    fn actuator_effort(&self, py: Python<'_>, name: &str) -> PyResult<f64> {
        self.sim.actuator_effort(name).map_err(|e| to_py_err(py, &*e))
    }

    /// The effort actuator `name` is held at, `None` while its law acts.
    fn held_actuator(&self, py: Python<'_>, name: &str) -> PyResult<Option<f64>> {
        self.sim.held_actuator(name).map_err(|e| to_py_err(py, &*e))
    }

    fn __repr__(&self) -> String {
        format!(
            "Simulation(analysis={:?}, time={}, steps={})",
            self.analysis,
            self.sim.time(),
            self.sim.steps()
        )
    }
}
