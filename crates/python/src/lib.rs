//! # flexmbs-python: the `flexmbs` Python package's extension module
//!
//! `flexmbs._flexmbs`, built by maturin (`pip install ./crates/python`), wraps the library
//! crates for Python: arrays cross as numpy arrays (rust-numpy), errors as exceptions of the
//! [`errors`] module. The pure-Python part of the package (`python/flexmbs/`) re-exports these
//! classes and adds what is better written in Python (the parameter sweep on Dask).
//!
//! - [`rbody`]: `ReducedBody`, a reduced-body file (`.rbody`) read, written and inspected.
//! - [`study`]: `Study` (a study file: values by key path, validation with located errors,
//!   runs, reductions) and `Simulation` (a dynamic analysis stepped from Python, with named
//!   loads set between steps).
//! - [`force_law`]: `ForceLaw`, a Python callable giving actuator efforts and point loads
//!   inside the implicit step (`Study.run(forces=...)`, `Study.simulation(forces=...)`).
//! - [`inspect`]: `inspect()`, what a reduced body holds and its physical checks, as
//!   `flexmbs inspect` reports them (`Inspection`).
//! - [`keys`]: `study_keys()`, the study-file keys as the study crate declares them.
//! - [`stubs`]: `_stubs()`, the text of the type stubs `flexmbs/_flexmbs.pyi`.
//!
//! The module keeps no state of its own: every class owns plain data of the library crates.

// The doc comments of the Python classes and methods are their Python docstrings, where
// units are written in brackets (`[m]`, `[Hz]`) as Python users read them; rustdoc would take
// those for intra-doc links.
#![allow(rustdoc::broken_intra_doc_links)]

use pyo3::prelude::*;

pub mod errors;
pub mod force_law;
pub mod inspect;
pub mod keys;
pub mod rbody;
pub mod signature;
pub mod stubs;
pub mod study;

/// The extension module `flexmbs._flexmbs`.
#[pymodule]
fn _flexmbs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    m.add_class::<rbody::ReducedBody>()?;
    m.add_class::<study::Study>()?;
    m.add_class::<study::Simulation>()?;
    m.add_class::<force_law::ForceLaw>()?;
    m.add_class::<inspect::Inspection>()?;
    m.add_function(wrap_pyfunction!(inspect::inspect, m)?)?;
    m.add_function(wrap_pyfunction!(keys::study_keys, m)?)?;
    m.add_function(wrap_pyfunction!(stubs::_stubs, m)?)?;
    Ok(())
}
