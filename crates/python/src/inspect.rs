//! `flexmbs.inspect(path)`: what a reduced body holds and its physical checks, as
//! `flexmbs inspect` prints them (`study::inspect`), for a person checking a body before a
//! study uses it; matrices from another code (Matrix Market) are reduced first, with the
//! keys of a study's `[bodies.matrices]` as keyword arguments.

use crate::errors::{chain, with_attributes, ReducedBodyFileError};
use crate::signature::{Class, Function, Member::*};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// `inspect` as the type stubs declare it.
pub(crate) const STUB: Function = Function(
    "inspect",
    "(path: _Path, excitation_hz: Optional[float] = None, *, mass: Optional[_Path] = None, nodes: Optional[_Path] = None, dofs: Optional[_Path] = None, dofs_per_node: Optional[int] = None, interfaces: Optional[Dict[str, int]] = None, modes: Optional[int] = None, cutoff_hz: Optional[float] = None) -> \"Inspection\"",
);

/// `Inspection` as the type stubs declare it.
pub(crate) const INSPECTION_STUB: Class = Class {
    name: "Inspection",
    bases: "",
    members: &[
        Property("report", "str"),
        Property("failed_checks", "int"),
        Property("passed", "bool"),
        Method("__str__", "(self) -> str"),
    ],
};

/// What `inspect` found: the report `flexmbs inspect` prints, and how many of the physical
/// checks every body passes before use failed (a study refuses a body that fails one).
/// `str(inspection)` is the report.
#[pyclass(module = "flexmbs", name = "Inspection", frozen)]
pub struct Inspection {
    report: String,
    failed_checks: usize,
}

#[pymethods]
impl Inspection {
    /// The report: size, interfaces, mass data, fixed-interface frequencies and modal effective
    /// masses, and the physical checks with what they measured.
    #[getter]
    fn report(&self) -> &str {
        &self.report
    }

    /// The number of physical checks the body fails (0: studies accept it).
    #[getter]
    fn failed_checks(&self) -> usize {
        self.failed_checks
    }

    /// Whether the body passes every physical check.
    #[getter]
    fn passed(&self) -> bool {
        self.failed_checks == 0
    }

    fn __str__(&self) -> &str {
        &self.report
    }

    fn __repr__(&self) -> String {
        let first = self.report.lines().next().unwrap_or_default();
        format!("<Inspection of {first}: {} failed checks>", self.failed_checks)
    }
}

/// What the reduced body at `path` holds, as `flexmbs inspect` reports it: a reduced-body
/// file (`.rbody`), an MBDyn modal element file (`.fem`), or a Matrix Market stiffness
/// (`.mtx`) with `mass`, `nodes`, `dofs` or `dofs_per_node`, `interfaces` ({name: node}) and
/// `modes` or `cutoff_hz` [Hz], the keys of a study's `[bodies.matrices]`, reduced first.
/// `excitation_hz` [Hz]: the highest frequency a study will excite; the report then says
/// whether the kept modes reach three times it. A body that fails its physical checks is
/// still reported (`Inspection.failed_checks`); a file that cannot be read or reduced raises
/// `ReducedBodyFileError` (with `.path`), a keyword that does not apply `ValueError`.
#[pyfunction]
#[pyo3(signature = (path, excitation_hz = None, *, mass = None, nodes = None, dofs = None, dofs_per_node = None, interfaces = None, modes = None, cutoff_hz = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn inspect(
    py: Python<'_>,
    path: PathBuf,
    excitation_hz: Option<f64>,
    mass: Option<PathBuf>,
    nodes: Option<PathBuf>,
    dofs: Option<PathBuf>,
    dofs_per_node: Option<usize>,
    interfaces: Option<BTreeMap<String, usize>>,
    modes: Option<usize>,
    cutoff_hz: Option<f64>,
) -> PyResult<Inspection> {
    for (name, f) in [("excitation_hz", excitation_hz), ("cutoff_hz", cutoff_hz)] {
        if f.is_some_and(|f| !(f > 0.0 && f.is_finite())) {
            return Err(PyValueError::new_err(format!(
                "{name} needs a positive frequency in Hz, got {}",
                f.unwrap_or_default()
            )));
        }
    }
    let text = |p: PathBuf| p.display().to_string();
    let given = [
        ("mass", mass.is_some()),
        ("nodes", nodes.is_some()),
        ("dofs", dofs.is_some()),
        ("dofs_per_node", dofs_per_node.is_some()),
        ("interfaces", interfaces.is_some()),
        ("modes", modes.is_some()),
        ("cutoff_hz", cutoff_hz.is_some()),
    ];
    let matrices = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("mtx")) {
        let (Some(mass), Some(nodes)) = (mass, nodes) else {
            return Err(PyValueError::new_err(format!(
                "{}: a Matrix Market stiffness needs mass= (M.mtx) and nodes= (x y z per line, m)",
                path.display()
            )));
        };
        Some(study::input::schema::MatricesFile {
            stiffness: text(path.clone()),
            mass: text(mass),
            nodes: text(nodes),
            dofs: dofs.map(text),
            dofs_per_node,
            interfaces: interfaces.unwrap_or_default(),
            modes,
            cutoff_hz,
        })
    } else if let Some((name, _)) = given.iter().find(|(_, g)| *g) {
        return Err(PyValueError::new_err(format!(
            "{name}= is for a Matrix Market stiffness (K.mtx); {} is not one",
            path.display()
        )));
    } else {
        None
    };
    let source = match &matrices {
        Some(m) => study::InspectSource::Matrices(m),
        None => study::InspectSource::File(&path),
    };
    let found =
        py.detach(|| study::inspect(&source, excitation_hz, 3.0).map_err(|e| chain(&*e as &dyn std::error::Error)));
    match found {
        Ok(i) => Ok(Inspection {
            report: i.report,
            failed_checks: i.failed_checks,
        }),
        Err(message) => {
            let at = PyString::new(py, &path.display().to_string()).into_any().unbind();
            Err(with_attributes::<ReducedBodyFileError>(py, message, &[("path", at)]))
        }
    }
}
