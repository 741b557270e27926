//! # study: from a study file to results
//!
//! The layer between the solver crates (`fe_model`, `reduction`, `superelement`, `mbs`) and
//! the programs that use them (the `flexmbs` command line, the Python package, the
//! validation suite). It owns the path
//!
//! ```text
//! STUDY.toml --serde--> StudyFile --validate--> Study --build--> BuiltMechanism --run--> Observer
//!  (input/schema)       raw, unchecked (input/validate) (build/)  mbs::Model with   (run/)   (output/)
//!                                  every reference resolved,     names, sensors,            CSV/VTU/PNG folder,
//!                                  every value checked           loads                      vectors in memory
//! ```
//!
//! The modules stand in that order: `input <- build <- run -> output`. `input` reads and
//! checks a study file into a [`Study`]; `build` turns a study and its reduced bodies into the
//! mechanism and never runs anything, nor uses anything of `run` or `output`; `run` reduces
//! parts through the cache, asks `build` for the mechanism, runs the analyses and streams
//! every result into an [`Observer`] of `output`, which knows nothing of how results are made
//! (it uses neither `build` nor `run`). The two plain data types that `build` makes and
//! `output` writes, the sensor groups (`sensor_group`) and the VTU mesh of a body (`mesh`,
//! re-exported by `output::vtu`), are leaves below `build` and `output` that use nothing of
//! the crate. [`error`] and [`interrupt`] sit below them all (an error's location uses the key
//! paths of `input::source`, which uses nothing of the crate).
//!
//! Nothing runs until the whole study has been validated: a misspelt material name is
//! reported, with its file, line, column, key and the close matches, before any mesh is
//! reduced. The study-file format is documented in `docs/study-file.md`.
//!
//! | module | what it holds |
//! |---|---|
//! | [`input`] | the study file: schema, sources and spans, validation, parts, documents, examples |
//! | `build` | the mechanism as an `mbs::Model`, concern by concern: points and nodes, bodies, joints, loads, sensors, initial states |
//! | `run` | the [`Runner`] and its start chain, the analyses of parts and of the mechanism, the cached reduction service, the [`Simulation`] stepped by the caller |
//! | [`output`] | the observer, the results folder (CSV, VTU/PVD, PNG, summary) |
//! | [`error`] | the boxed error with context and its report |
//! | [`interrupt`] | Ctrl-C and SIGTERM: a stop requested at the next output step |
//! | [`fmu`] | a dynamic analysis as an FMI 2.0 Co-Simulation FMU: its variables, `modelDescription.xml`, archive and the instance a master steps |
//!
//! The face of the crate is this module: a study loaded ([`load`], [`parse_and_validate`],
//! [`Document`]), run ([`run()`], [`run_with`], [`run_only`], [`run_selected`] with a
//! [`Selection`], a [`Runner`] analysis by analysis) or stepped ([`Simulation`]), its results
//! to an [`Observer`] such as the [`Recorder`]. `build` and `run` are private; the few of their
//! items that the command line, the Python package and the tests use are re-exported here.

pub mod error;
pub mod fmu;
pub mod input;
pub mod interrupt;
pub mod output;

pub(crate) mod build;
pub(crate) mod mesh;
pub(crate) mod run;
pub(crate) mod sensor_group;

pub use error::BoxError;
pub use input::document::Document;
pub use input::validate::{load, parse_and_validate, Study};
pub use output::observer::{Observer, Recorder};
pub use run::{
    run, run_only, run_selected, run_selected_with, run_with, ForceLawSource, Forces, Options, Runner, SavedSimulation,
    Selection, Simulation, UnknownName,
};

// What the command line, the Python package and the tests use beyond the facade.
pub use build::{joint_count, BuiltMechanism};
pub use run::inspect::{inspect, Inspection, Source as InspectSource};
pub use run::mesh::model_page;
pub use run::nothing_to_run;
pub use run::reduce::{build_mechanism, reduce_command, reduce_part, Reduced, ReducedFile};
pub use run::sensors::sensor_columns;
pub use run::simulation::dynamic_settings;
