//! # flexmbs: the program
//!
//! From a mesh to the motion of a flexible mechanism. This crate is the `flexmbs` command
//! line tool and the only place that reads study files, writes results and turns errors into
//! a report and an exit code (2 on error). The numerical stages are the other crates:
//! `fe_model` (FE models, statics, dense modes), `reduction` (Craig-Bampton, reduced-body
//! files, sparse modes), and later `superelement` and `mbs`.
//!
//! ```text
//! STUDY.toml --serde--> StudyFile --validate--> Study --run--> results folder
//!   (study_file.rs)       raw, unchecked     (study.rs, part.rs)   (run.rs, output.rs, vtu.rs)
//!                                            every reference        CSV + summary.json/.md
//!                                            resolved, every        + VTU/PVD for ParaView
//!                                            value checked          + .rbody (cache.rs)
//! ```
//!
//! Nothing runs until the whole study has been validated (style R12): a misspelt material
//! name is reported, with its file, line, column, key and the close matches, before any
//! mesh is reduced. The study-file format is documented in `docs/study-file.md`.
//!
//! | module | what it holds |
//! |---|---|
//! | [`study_file`] | the serde schema of a study file, raw |
//! | [`source`] | spans, key paths, error rendering, close matches |
//! | [`study`] | validation `StudyFile` → `Study` |
//! | [`part`] | a validated part and the FE model an analysis runs on |
//! | [`run`] | the analyses: static, modal, reduce; `flexmbs reduce` |
//! | [`mechanism_run`] | the mechanism as an `mbs::Model`; equilibrium, dynamic, linearized; streamed sensors and meshes |
//! | [`cache`] | reduced bodies cached by a hash of what produced them |
//! | [`output`] | results folder, CSV, summary |
//! | [`vtu`] | VTK XML unstructured grids and `.pvd` collections |
//! | [`inspect`] | `flexmbs inspect FILE.rbody` |
//! | [`examples`] | the built-in example studies of `examples/` |
//! | [`builtin`] | `flexmbs run` without a file: the flexible slider-crank (benchmarks.md C2) |

pub mod builtin;
pub mod cache;
pub mod cli;
pub mod error;
pub mod examples;
pub mod inspect;
pub mod mechanism_run;
pub mod output;
pub mod part;
pub mod run;
pub mod source;
pub mod study;
pub mod study_file;
pub mod vtu;
