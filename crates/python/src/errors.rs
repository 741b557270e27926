//! The package's exceptions: `FlexmbsError` and its subclasses. Each carries, besides its
//! message (the library error's chain, outermost first), the entity it is about as attributes,
//! so a script can react without parsing text.
//!
//! | class | raised when | attributes |
//! |---|---|---|
//! | `FlexmbsError` | base of all below | |
//! | `ReducedBodyFileError` | a `.rbody` file cannot be read or written | `path` |
//! | `StudyError` | a study is not valid (as `flexmbs check` reports it) | `file`, `line`, `column`, `key` of the first error; `errors`: every error as a dict of these and `message` |
//! | `KeyPathError` | a key path leads to no value of the study | `path` (the path asked for), `at` (its part that leads nowhere) |
//! | `UnknownNameError` (also a `KeyError`) | a name the study or the results do not have: an analysis (`Study.run`, `Study.simulation`), a sensor (`Simulation.sensor`, `Results.sensor`) | `name`, `what` (`"analysis"`, `"sensor"`), `matches` (the close names: the message's "did you mean"), `defined` (every name there is) |
//! | `SolveError` | a solver stopped (Newton did not converge, a singular matrix, ...) | `time` (of the step that failed in a dynamic analysis), `load_factor` (of the load step that failed in an equilibrium), `step` (its number), `residual` (the last relative residual when Newton failed), `analysis` (its name), `file`, `line`, `column`, `key` (where the study describes the entity the solver failed at: the body whose floating frame failed); `None` when not known; `partial` (from `Study.run`: the results computed before, also in the results folder) |

use crate::signature::{Class, Function, Member::Attribute};
use pyo3::create_exception;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyList, PyString, PyType};
pub(crate) use study::error::chain;

create_exception!(
    flexmbs,
    FlexmbsError,
    pyo3::exceptions::PyException,
    "Base class of every error raised by flexmbs."
);
create_exception!(
    flexmbs,
    ReducedBodyFileError,
    FlexmbsError,
    "A reduced-body file (.rbody) could not be read or written; `path` names it."
);

create_exception!(
    flexmbs,
    StudyError,
    FlexmbsError,
    "A study is not valid; `file`, `line`, `column` and `key` locate the first error, `errors` lists all."
);
create_exception!(
    flexmbs,
    KeyPathError,
    FlexmbsError,
    "A key path that leads to no value of the study; `path` is the path, `at` its part that leads nowhere."
);
create_exception!(
    flexmbs,
    SolveError,
    FlexmbsError,
    "A solver stopped: `time` (dynamic) or `load_factor` (equilibrium), `step`, `residual` and `analysis` say where, `file`, `line`, `column` and `key` the study's entity it failed at (None when not known); `partial` holds what `Study.run` computed before."
);

/// The exception classes as the type stubs declare them (their attributes are set on each
/// raised instance).
pub(crate) const STUBS: &[Class] = &[
    Class {
        name: "FlexmbsError",
        bases: "Exception",
        members: &[],
    },
    Class {
        name: "ReducedBodyFileError",
        bases: "FlexmbsError",
        members: &[Attribute("path", "str")],
    },
    Class {
        name: "StudyError",
        bases: "FlexmbsError",
        members: &[
            Attribute("file", "Optional[str]"),
            Attribute("line", "Optional[int]"),
            Attribute("column", "Optional[int]"),
            Attribute("key", "Optional[str]"),
            Attribute("errors", "List[Dict[str, Any]]"),
        ],
    },
    Class {
        name: "KeyPathError",
        bases: "FlexmbsError",
        members: &[Attribute("path", "str"), Attribute("at", "str")],
    },
    Class {
        name: "SolveError",
        bases: "FlexmbsError",
        members: &[
            Attribute("time", "Optional[float]"),
            Attribute("load_factor", "Optional[float]"),
            Attribute("step", "Optional[int]"),
            Attribute("residual", "Optional[float]"),
            Attribute("analysis", "Optional[str]"),
            Attribute("file", "Optional[str]"),
            Attribute("line", "Optional[int]"),
            Attribute("column", "Optional[int]"),
            Attribute("key", "Optional[str]"),
            Attribute("partial", "Optional[Results]"),
        ],
    },
    Class {
        name: "UnknownNameError",
        bases: "FlexmbsError, KeyError",
        members: &[
            Attribute("name", "str"),
            Attribute("what", "str"),
            Attribute("matches", "List[str]"),
            Attribute("defined", "List[str]"),
        ],
    },
];

/// `_unknown_name_error` as the type stubs declare it.
pub(crate) const FUNCTION_STUB: Function = Function(
    "_unknown_name_error",
    "(what: str, name: str, defined: List[str]) -> UnknownNameError",
);

/// `UnknownNameError`, made once: an exception class of PyO3 has one base, and this one has
/// two, so it is made as Python makes it, by `type(name, bases, namespace)`.
static UNKNOWN_NAME_ERROR: PyOnceLock<Py<PyType>> = PyOnceLock::new();

/// The class `UnknownNameError(FlexmbsError, KeyError)`: a `KeyError` to code that looks names
/// up, the package's error to code that catches those. Its message reads as written (a
/// `KeyError` would show it quoted, as a key).
pub(crate) fn unknown_name_error(py: Python<'_>) -> PyResult<&Bound<'_, PyType>> {
    let ty = UNKNOWN_NAME_ERROR.get_or_try_init(py, || -> PyResult<Py<PyType>> {
        let namespace = PyDict::new(py);
        namespace.set_item("__module__", "flexmbs")?;
        namespace.set_item(
            "__doc__",
            "A name the study or the results do not have (an analysis, a sensor); the message says \
             which names are close. `name`, `what`, `matches` (the close names) and `defined` (every \
             name there is).",
        )?;
        let exception = py.get_type::<pyo3::exceptions::PyException>();
        namespace.set_item("__str__", exception.getattr("__str__")?)?;
        let bases = (
            py.get_type::<FlexmbsError>(),
            py.get_type::<pyo3::exceptions::PyKeyError>(),
        );
        let ty = py.get_type::<PyType>().call1(("UnknownNameError", bases, namespace))?;
        Ok(ty.cast_into::<PyType>()?.unbind())
    })?;
    Ok(ty.bind(py))
}

/// An `UnknownNameError` for `name`, which is not among the `defined` names of a `what`
/// (`"analysis"`, `"sensor"`): the library's message for an unknown name, with its "did you
/// mean", and the names as attributes.
pub(crate) fn unknown_name(py: Python<'_>, what: &str, name: &str, defined: &[String]) -> PyErr {
    let message = study::input::source::unknown_reference(what, name, defined);
    let matches = study::input::source::close_matches(name, defined.iter().map(String::as_str));
    let ty = match unknown_name_error(py) {
        Ok(ty) => ty.clone(),
        Err(e) => return e,
    };
    let err = PyErr::from_type(ty, message);
    let value = err.value(py);
    let set = value
        .setattr("name", name)
        .and_then(|()| value.setattr("what", what))
        .and_then(|()| value.setattr("matches", matches))
        .and_then(|()| value.setattr("defined", defined.to_vec()));
    match set {
        Ok(()) => err,
        Err(e) => e,
    }
}

/// `unknown_name` for the pure-Python part of the package (`Results.sensor`): the exception
/// object, for Python to raise.
#[pyfunction]
pub(crate) fn _unknown_name_error(py: Python<'_>, what: &str, name: &str, defined: Vec<String>) -> Py<PyAny> {
    unknown_name(py, what, name, &defined).into_value(py).into_any()
}

/// `error` from a library call that looked `name` up among the `defined` names of a `what`:
/// the library reports a name it does not have as a [`study::UnknownName`] (an analysis) or as
/// its message for an unknown name ([`study::input::source::unknown_reference`], an error
/// without a cause: a sensor), which becomes an `UnknownNameError`; any other error is
/// [`to_py_err`]'s.
pub(crate) fn lookup_err(
    py: Python<'_>,
    error: &(dyn std::error::Error + 'static),
    what: &str,
    name: &str,
    defined: &[String],
) -> PyErr {
    if let Some(u) = error.downcast_ref::<study::UnknownName>() {
        return unknown_name(py, u.what, &u.name, &u.defined);
    }
    let unknown = study::input::source::unknown_reference(what, name, defined);
    if error.source().is_none() && error.to_string() == unknown {
        unknown_name(py, what, name, defined)
    } else {
        to_py_err(py, error)
    }
}

/// Adds the exception classes to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("UnknownNameError", unknown_name_error(py)?)?;
    m.add_function(wrap_pyfunction!(_unknown_name_error, m)?)?;
    m.add("FlexmbsError", py.get_type::<FlexmbsError>())?;
    m.add("ReducedBodyFileError", py.get_type::<ReducedBodyFileError>())?;
    m.add("StudyError", py.get_type::<StudyError>())?;
    m.add("KeyPathError", py.get_type::<KeyPathError>())?;
    m.add("SolveError", py.get_type::<SolveError>())?;
    Ok(())
}

/// A Python exception of class `T` with `message` and the attributes `attrs` set on it.
pub(crate) fn with_attributes<T: pyo3::PyTypeInfo>(
    py: Python<'_>,
    message: String,
    attrs: &[(&str, Py<PyAny>)],
) -> PyErr {
    let err = PyErr::new::<T, _>(message);
    let value = err.value(py);
    for (name, v) in attrs {
        if let Err(e) = value.setattr(*name, v.bind(py)) {
            return e;
        }
    }
    err
}

/// The errors of a study's validation as dicts (`file`, `line`, `column`, `key`, `message`);
/// `line` and `column` are 1-based, `None` when the error is about the file as a whole.
fn study_error_dicts<'py>(py: Python<'py>, e: &study::input::source::StudyErrors) -> PyResult<Vec<Bound<'py, PyDict>>> {
    use study::input::source::{line_column, Anchor};
    let src = &e.source;
    e.errors
        .iter()
        .map(|err| {
            let span = match &err.anchor {
                Anchor::Value(p) => src.locate(p),
                Anchor::Key(p) => src.locate_key(p),
                Anchor::Span(s) => Some(s.clone()),
                Anchor::File => None,
            };
            let (line, column) = match span {
                Some(s) => {
                    let (l, c) = line_column(&src.text, s.start);
                    (Some(l), Some(c))
                }
                None => (None, None),
            };
            let d = PyDict::new(py);
            d.set_item("file", src.path.display().to_string())?;
            d.set_item("line", line)?;
            d.set_item("column", column)?;
            d.set_item("key", err.path.to_string())?;
            d.set_item("message", &err.message)?;
            Ok(d)
        })
        .collect()
}

/// A library error as the package's exception: the first error of the chain that the package
/// has a class for decides the class and its attributes; the message is the whole chain.
pub(crate) fn to_py_err(py: Python<'_>, error: &(dyn std::error::Error + 'static)) -> PyErr {
    let err = match convert(py, error) {
        Ok(e) | Err(e) => e,
    };
    // A Python exception that a force law raised is the cause of the solver's error.
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(error);
    while let Some(e) = cause {
        // The solver's error holds it boxed.
        let law = e
            .downcast_ref::<mbs::force_law::LawError>()
            .or_else(|| e.downcast_ref::<Box<mbs::force_law::LawError>>().map(|b| &**b));
        if let Some(law) = law {
            if let Some(raised) = law.source.as_ref().and_then(|c| c.0.downcast_ref::<PyErr>()) {
                err.set_cause(py, Some(raised.clone_ref(py)));
                break;
            }
        }
        cause = e.source();
    }
    err
}

fn convert(py: Python<'_>, error: &(dyn std::error::Error + 'static)) -> PyResult<PyErr> {
    let message = chain(error);
    // Where a solver stopped, from the errors around its own: the analysis of a run and the
    // step number the analysis counts.
    let mut analysis: Option<String> = None;
    let mut analysis_step: Option<usize> = None;
    let mut location: Option<&study::error::Location> = None;
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(error);
    while let Some(e) = cause {
        if let Some(a) = e.downcast_ref::<study::error::AnalysisFailed>() {
            analysis.get_or_insert_with(|| a.analysis.clone());
        }
        if let Some(s) = e.downcast_ref::<study::error::SolverStopped>() {
            analysis_step = analysis_step.or(s.step);
            location = location.or(s.location.as_ref());
        }
        if let Some(s) = e.downcast_ref::<study::input::source::StudyErrors>() {
            let errors = study_error_dicts(py, s)?;
            let first = errors.first().cloned();
            let get = |k: &str| -> PyResult<Py<PyAny>> {
                Ok(match &first {
                    Some(d) => d.get_item(k)?.map_or_else(|| py.None(), |v| v.unbind()),
                    None => py.None(),
                })
            };
            let attrs = [
                ("file", get("file")?),
                ("line", get("line")?),
                ("column", get("column")?),
                ("key", get("key")?),
                ("errors", PyList::new(py, errors)?.into_any().unbind()),
            ];
            return Ok(with_attributes::<StudyError>(py, s.to_string(), &attrs));
        }
        if let Some(p) = e.downcast_ref::<study::input::document::PathError>() {
            let path = match p {
                study::input::document::PathError::Malformed { path, .. }
                | study::input::document::PathError::Missing { path, .. }
                | study::input::document::PathError::Index { path, .. }
                | study::input::document::PathError::NotTable { path, .. }
                | study::input::document::PathError::Value { path, .. } => path.clone(),
            };
            let at = PyString::new(py, &path).into_any().unbind();
            return Ok(with_attributes::<KeyPathError>(
                py,
                message,
                &[("path", at.clone_ref(py)), ("at", at)],
            ));
        }
        if let Some(s) = e.downcast_ref::<mbs::SolveError>() {
            let residual = match s {
                mbs::SolveError::NotConverged { residual, .. } => Some(*residual),
                _ => None,
            };
            let at = s.at();
            let step = s.step().or(analysis_step);
            let attrs = [
                (
                    "time",
                    at.and_then(mbs::At::time).into_pyobject(py)?.into_any().unbind(),
                ),
                (
                    "load_factor",
                    at.and_then(mbs::At::load_factor).into_pyobject(py)?.into_any().unbind(),
                ),
                ("step", step.into_pyobject(py)?.into_any().unbind()),
                ("residual", residual.into_pyobject(py)?.into_any().unbind()),
                ("analysis", analysis.clone().into_pyobject(py)?.into_any().unbind()),
                ("partial", py.None()),
            ];
            let err = with_attributes::<SolveError>(py, message, &attrs);
            return Ok(with_location(py, err, location));
        }
        if let Some(reduction::ReductionError::BodyFile { path, .. }) = e.downcast_ref::<reduction::ReductionError>() {
            let path = PyString::new(py, &path.display().to_string()).into_any().unbind();
            return Ok(with_attributes::<ReducedBodyFileError>(py, message, &[("path", path)]));
        }
        cause = e.source();
    }
    Ok(FlexmbsError::new_err(message))
}

/// `err` with the attributes `file`, `line`, `column` and `key` of `location` (all `None`
/// without one).
fn with_location(py: Python<'_>, err: PyErr, location: Option<&study::error::Location>) -> PyErr {
    let (file, (line, column), key) = match location {
        Some(at) => (
            Some(at.file.display().to_string()),
            at.line_column.unzip(),
            Some(at.key.to_string()),
        ),
        None => (None, (None, None), None),
    };
    let value = err.value(py);
    let set = value
        .setattr("file", file)
        .and_then(|()| value.setattr("line", line))
        .and_then(|()| value.setattr("column", column))
        .and_then(|()| value.setattr("key", key));
    match set {
        Ok(()) => err,
        Err(e) => e,
    }
}

/// A failure of the simulation of analysis `analysis` that has taken `steps` steps, as the
/// package's exception: a `SolveError` names the analysis, the step when the solver did not
/// (the step that failed is the next), and where the study describes the entity it failed at
/// (`location`) when the error itself does not say.
pub(crate) fn simulation_err(
    py: Python<'_>,
    error: &(dyn std::error::Error + 'static),
    analysis: &str,
    steps: usize,
    location: Option<&study::error::Location>,
) -> PyErr {
    let mut err = to_py_err(py, error);
    if err.is_instance_of::<SolveError>(py) && location.is_some() {
        err = with_location(py, err, location);
    }
    if err.is_instance_of::<SolveError>(py) {
        let value = err.value(py);
        let unknown_step = value.getattr("step").map(|s| s.is_none()).unwrap_or(true);
        let set = value.setattr("analysis", analysis).and_then(|()| {
            if unknown_step {
                value.setattr("step", steps + 1)
            } else {
                Ok(())
            }
        });
        if let Err(e) = set {
            return e;
        }
    }
    err
}

/// `error` as the package's exception; a `KeyPathError` gets `path` = `key`, the path the
/// caller asked for (the library names the part of it that leads nowhere, kept as `at`).
pub(crate) fn key_err(py: Python<'_>, error: &(dyn std::error::Error + 'static), key: &str) -> PyErr {
    let err = to_py_err(py, error);
    if err.is_instance_of::<KeyPathError>(py) {
        if let Err(e) = err.value(py).setattr("path", key) {
            return e;
        }
    }
    err
}
