//! # flexmbs: the program
//!
//! From a mesh to the motion of a flexible mechanism. This crate is the `flexmbs` command
//! line tool: argument parsing, progress display and error printing (exit code 2 on error).
//! Everything a study does (reading and validating study files, building the mechanism,
//! running the analyses, writing results folders) is the `study` crate.
//!
//! | module | what it holds |
//! |---|---|
//! | [`cli`] | the command line: arguments and dispatch |
//! | [`console`] | the observer that shows progress on stderr and the report on stdout |
//! | [`inspect`] | `flexmbs inspect FILE.rbody` |
//! | [`builtin`] | `flexmbs run` without a file: the flexible slider-crank (benchmark C2) |

pub mod builtin;
pub mod cli;
pub mod console;
pub mod inspect;

pub use study::{error, examples, source, vtu};
