//! Tests of the `flexmbs` program. Most run the binary itself (`CARGO_BIN_EXE_flexmbs`) the
//! way a user does and check its output files, messages and exit codes; the VTU node-order
//! tests and the bulk of the property test call the library.
//!
//! Index:

/// Helpers shared by every module: running the binary, scratch folders, reading CSV.
#[path = "cli/support.rs"]
mod support;

/// Every example of `examples/` runs and prints the numbers it demonstrates; the built-in
/// example of `flexmbs run` without a file; `flexmbs example`, `check`, `inspect`, usage errors.
#[path = "cli/examples.rs"]
mod examples;

/// The corpus `tests/broken/*.toml`: each file lists the messages `flexmbs check` must print
/// (`# expect:` lines: file:line:col, key, close matches); exit code 2.
#[path = "cli/broken.rs"]
mod broken;

/// Reduced bodies are cached: a second run does not reduce again; a change that matters does.
#[path = "cli/cache.rs"]
mod cache;

/// Random and mutated study files (fixed seeds): no panic, exit code 2 with a message.
#[path = "cli/property.rs"]
mod property;

/// The mechanism: B1 and B3 against their references, streamed results of a dynamic run, a
/// solver failure with partial results, errors of the assembled mechanism, `validate`, the
/// modified-Newton option.
#[path = "cli/mechanism.rs"]
mod mechanism;

/// `--help` of every command, `validate`'s ids (or, without the `validate` feature, how to
/// get the suite), an empty study, a closed pipe, progress.
#[path = "cli/command_line.rs"]
mod command_line;

/// The documents stand on their own: links, anchors and named files exist; nothing points
/// outside the repository.
#[path = "cli/docs.rs"]
mod docs;
