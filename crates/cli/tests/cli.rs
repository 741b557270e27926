//! Tests of the `flexmbs` program. Most run the binary itself (`CARGO_BIN_EXE_flexmbs`) the
//! way a user does and check its output files, messages and exit codes; the VTU node-order
//! tests call the library. What the validation says about a study file is tested in
//! crates/study.
//!
//! Index:

/// Helpers shared by every module: running the binary, scratch folders, reading CSV.
#[path = "cli/support.rs"]
mod support;

/// Every example of `examples/` runs and prints the numbers it demonstrates; the built-in
/// example of `flexmbs run` without a file; `flexmbs example`, `check`, `inspect`, usage errors.
#[path = "cli/examples.rs"]
mod examples;

/// `inspect` on an MBDyn file whose record 12 is compared with its nodal masses, and on Matrix
/// Market matrices with a node table (a table in millimetres refused).
#[path = "cli/inspect.rs"]
mod inspect;

/// Reduced bodies are cached: a second run does not reduce again; a change that matters does.
#[path = "cli/cache.rs"]
mod cache;

/// Invalid study files (the study crate's corpus and generator): exit code 2 and the study
/// crate's report on stderr, never a panic; binary and deeply nested files.
#[path = "cli/invalid.rs"]
mod invalid;

/// The mechanism: B1 and B3 against their references, streamed results of a dynamic run, a
/// solver failure with partial results, errors of the assembled mechanism, `validate`, the
/// modified-Newton option.
#[path = "cli/mechanism.rs"]
mod mechanism;

/// Values that are not finite stop static analyses: an equilibrium whose sensor reads 0/0
/// fails with exit code 2 and the sensor named.
#[path = "cli/non_finite.rs"]
mod non_finite;

/// `--help` of every command, `validate`'s ids (or, without the `validate` feature, how to
/// get the suite), an empty study, a closed pipe, progress.
#[path = "cli/command_line.rs"]
mod command_line;

/// The documents stand on their own: links, anchors and named files exist; nothing points
/// outside the repository.
#[path = "cli/docs.rs"]
mod docs;

/// Results folders: a user's file under one of our names kept (`--foreign-files keep`, a
/// recreated analysis folder), a symbolic link refused, a full disk mid-run, SIGTERM, the
/// lock of a running run.
#[path = "cli/results_folder.rs"]
mod results_folder;
