//! # study: from a study file to results
//!
//! The layer between the solver crates (`fe_model`, `reduction`, `superelement`, `mbs`) and
//! the programs that use them (the `flexmbs` command line, the Python package, the
//! validation suite). It owns the path
//!
//! ```text
//! STUDY.toml --serde--> StudyFile --validate--> Study --build--> mbs::Model --run--> Observer
//!  (input/schema)        raw, unchecked  (input/validate)     (mechanism.rs)   (run, output)
//!                                     every reference resolved,                  CSV/VTU/PNG folder
//!                                     every value checked                        (output/folder), vectors
//! ```
//!
//! Nothing runs until the whole study has been validated: a misspelt material name is
//! reported, with its file, line, column, key and the close matches, before any mesh is
//! reduced. The study-file format is documented in `docs/study-file.md`.
//!
//! | module | what it holds |
//! |---|---|
//! | [`input`] | the study file: schema, sources and spans, validation, parts, documents, examples |
//! | [`mod@run`] | the analyses of parts (static, modal, reduce), the run loop, `flexmbs reduce` |
//! | [`mechanism`] | the mechanism as an `mbs::Model`; equilibrium, dynamic, linearized |
//! | [`simulation`] | a dynamic analysis stepped by the caller: sensors, state, named loads |
//! | [`cache`] | reduced bodies cached by a hash of what produced them |
//! | [`output`] | the observer, the results folder (CSV, VTU/PVD, PNG, summary) |
//! | [`error`] | the boxed error with context and its report |
//! | [`interrupt`] | Ctrl-C: a stop requested at the next output step |

pub mod error;
pub mod input;
pub mod interrupt;
pub mod output;

pub(crate) mod build;
pub(crate) mod run;

pub use error::BoxError;
pub use input::document::Document;
pub use input::validate::{load, parse_and_validate, Study};
pub use output::observer::{Observer, Recorder};
pub use run::{run, run_only, run_selected, run_with, Options, Runner, Selection, Simulation};

// What the command line, the Python package and the tests use beyond the facade.
pub use build::{joint_count, BuiltMechanism};
pub use run::nothing_to_run;
pub use run::reduce::{build_mechanism, reduce_command, reduce_part, Reduced, ReducedFile};
pub use run::sensors::sensor_columns;
pub use run::simulation::dynamic_settings;
