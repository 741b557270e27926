//! `study_keys()`: the study-file keys as the study crate declares them once
//! (`study::input::keys`), so Python's help on a key is the program's and the docs' own.

use crate::signature::Function;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// `study_keys` as the type stubs declare it.
pub(crate) const STUB: Function = Function("study_keys", "(table: Optional[str] = None) -> List[Dict[str, Any]]");

/// The keys of a study file, one dict each: ``table`` (dotted table path, ``""`` for the
/// file's root), ``name``, ``kinds`` (the kinds of the table that take it; empty: all),
/// ``type``, ``unit``, ``required``, ``default`` (as the docs write it; ``""`` when none),
/// ``range`` and ``doc``. With ``table``, only that table's keys. The same declarations give
/// the validator's allowed keys and the key tables of docs/study-file.md.
#[pyfunction]
#[pyo3(signature = (table = None))]
pub(crate) fn study_keys<'py>(py: Python<'py>, table: Option<&str>) -> PyResult<Vec<Bound<'py, PyDict>>> {
    study::input::keys::entries()
        .into_iter()
        .filter(|e| table.is_none_or(|t| t == e.table))
        .map(|e| {
            let d = PyDict::new(py);
            d.set_item("table", e.table)?;
            d.set_item("name", e.name)?;
            d.set_item("kinds", e.kinds)?;
            d.set_item("type", e.ty)?;
            d.set_item("unit", e.unit)?;
            d.set_item("required", e.required)?;
            d.set_item("default", e.default)?;
            d.set_item("range", e.range)?;
            d.set_item("doc", e.doc)?;
            Ok(d)
        })
        .collect()
}
