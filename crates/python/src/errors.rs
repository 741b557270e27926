//! The package's exceptions: `FlexmbsError` and its subclasses. Each carries, besides its
//! message (the library error's chain, outermost first), the entity it is about as attributes,
//! so a script can react without parsing text.
//!
//! | class | raised when | attributes |
//! |---|---|---|
//! | `FlexmbsError` | base of all below | |
//! | `ReducedBodyFileError` | a `.rbody` file cannot be read or written | `path` |
//! | `StudyError` | a study is not valid (as `flexmbs check` reports it) | `file`, `line`, `column`, `key` of the first error; `errors`: every error as a dict of these and `message` |
//! | `KeyPathError` | a key path leads to no value of the study | `path` |
//! | `SolveError` | a solver stopped (Newton did not converge, a singular matrix, ...) | `time`, `step`, `residual` (when known); `partial` (results computed before, from `Study.run`) |

use pyo3::create_exception;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

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
    "A key path that leads to no value of the study; `path` is the path."
);
create_exception!(
    flexmbs,
    SolveError,
    FlexmbsError,
    "A solver stopped: `time`, `step` and `residual` say where (None when not known)."
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

/// The message of an error and of every source below it, joined by ": " (the CLI prints the
/// same chain).
pub(crate) fn chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(s) = source {
        let more = s.to_string();
        if !text.contains(&more) {
            text.push_str(": ");
            text.push_str(&more);
        }
        source = s.source();
    }
    text
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
fn study_error_dicts<'py>(py: Python<'py>, e: &study::source::StudyErrors) -> PyResult<Vec<Bound<'py, PyDict>>> {
    use study::source::{line_column, Anchor};
    let src = &e.source;
    e.errors
        .iter()
        .map(|err| {
            let span = match &err.anchor {
                Anchor::Value(p) => src.locate(p, false),
                Anchor::Key(p) => src.locate(p, true),
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
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(error);
    while let Some(e) = cause {
        if let Some(s) = e.downcast_ref::<study::source::StudyErrors>() {
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
        if let Some(p) = e.downcast_ref::<study::document::PathError>() {
            let path = match p {
                study::document::PathError::Malformed { path, .. }
                | study::document::PathError::Missing { path, .. }
                | study::document::PathError::Index { path, .. }
                | study::document::PathError::NotTable { path, .. }
                | study::document::PathError::Value { path, .. } => path.clone(),
            };
            let path = PyString::new(py, &path).into_any().unbind();
            return Ok(with_attributes::<KeyPathError>(py, message, &[("path", path)]));
        }
        if let Some(s) = e.downcast_ref::<mbs::SolveError>() {
            let (t, step, residual) = match s {
                mbs::SolveError::NotConverged { t, step, residual, .. } => (Some(*t), Some(*step), Some(*residual)),
                mbs::SolveError::Singular { t, step, .. } => (Some(*t), Some(*step), None),
                mbs::SolveError::Body { t, .. } | mbs::SolveError::UserForce { t, .. } => (Some(*t), None, None),
                _ => (None, None, None),
            };
            let attrs = [
                ("time", t.into_pyobject(py)?.into_any().unbind()),
                ("step", step.into_pyobject(py)?.into_any().unbind()),
                ("residual", residual.into_pyobject(py)?.into_any().unbind()),
            ];
            return Ok(with_attributes::<SolveError>(py, message, &attrs));
        }
        if let Some(r) = e.downcast_ref::<reduction::ReductionError>() {
            if let reduction::ReductionError::BodyFile { path, .. } = r {
                let path = PyString::new(py, &path.display().to_string()).into_any().unbind();
                return Ok(with_attributes::<ReducedBodyFileError>(py, message, &[("path", path)]));
            }
        }
        cause = e.source();
    }
    Ok(FlexmbsError::new_err(message))
}
