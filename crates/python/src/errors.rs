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
//! | `SolveError` | a solver stopped (Newton did not converge, a singular matrix, ...) | `time` (of the step that failed in a dynamic analysis), `load_factor` (of the load step that failed in an equilibrium), `step` (its number), `residual` (the last relative residual when Newton failed), `analysis` (its name), `file`, `line`, `column`, `key` (where the study describes the entity the solver failed at: the body whose floating frame failed); `None` when not known; `partial` (from `Study.run`: the results computed before, also in the results folder) |

use pyo3::create_exception;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};
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

/// Adds the exception classes to the module.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
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
    match convert(py, error) {
        Ok(e) | Err(e) => e,
    }
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
