//! The validation crate's tests, one binary (each test binary links the whole dependency tree).

/// The quick subset of the suite: every benchmark at its quick levels, within its tolerances.
#[path = "suite/quick.rs"]
mod quick;

/// The command line of `flexmbs validate` and of the `validation` binary.
#[path = "suite/command_line.rs"]
mod command_line;
