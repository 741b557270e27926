//! # study: from a study file to results
//!
//! The layer between the solver crates (`fe_model`, `reduction`, `superelement`, `mbs`) and
//! the programs that use them (the `flexmbs` command line, the Python package, the
//! validation suite). It owns the path
//!
//! ```text
//! STUDY.toml --serde--> StudyFile --validate--> Study --build--> mbs::Model --run--> Observer
//!  (schema.rs)        raw, unchecked  (validate*, part.rs)     (mechanism.rs)   (run.rs, observer.rs)
//!                                     every reference resolved,                  CSV/VTU/PNG folder
//!                                     every value checked                        (folder.rs), vectors
//! ```
//!
//! Nothing runs until the whole study has been validated: a misspelt material name is
//! reported, with its file, line, column, key and the close matches, before any mesh is
//! reduced. The study-file format is documented in `docs/study-file.md`.
//!
//! | module | what it holds |
//! |---|---|
//! | [`schema`] | the serde schema of a study file, raw: every key |
//! | [`source`] | spans, key paths, error rendering, close matches |
//! | [`validate`] | validation `StudyFile` → `Study` (parts, analyses; `validate::mechanism`: the mechanism) |
//! | [`part`] | a validated part and the FE model an analysis runs on |
//! | [`document`] | a study as an editable document: load from a file or text, get and set values by key path |
//! | [`run`] | the analyses of parts (static, modal, reduce), the run loop, `flexmbs reduce` |
//! | [`mechanism`] | the mechanism as an `mbs::Model`; equilibrium, dynamic, linearized |
//! | [`simulation`] | a dynamic analysis stepped by the caller: sensors, state, named loads |
//! | [`observer`] | the output observer trait, result tables, the in-memory [`observer::Recorder`] |
//! | [`folder`] | the results folder observer: CSV, VTU/PVD, PNG, summary |
//! | [`cache`] | reduced bodies cached by a hash of what produced them |
//! | [`output`] | CSV text, summary types, results-folder layout |
//! | [`vtu`] | VTK XML unstructured grids and `.pvd` collections |
//! | [`examples`] | the built-in example studies of `examples/` |
//! | [`error`] | the boxed error with context and its report |

pub mod cache;
pub mod document;
pub mod error;
pub mod examples;
pub mod folder;
pub mod interrupt;
pub mod mechanism;
pub mod observer;
pub mod output;
pub mod part;
pub mod run;
pub mod schema;
pub mod simulation;
pub mod source;
pub mod validate;
pub mod vtu;

pub use document::Document;
pub use error::BoxError;
pub use observer::{Observer, Recorder};
pub use run::{run, run_with, Options, Runner};
pub use simulation::Simulation;
pub use validate::{load, parse_and_validate, Study};
