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
//! | [`builtin`] | `flexmbs run` without a file: the flexible slider-crank (benchmark C2) |

/// `println!` that cannot panic: when stdout is closed (`flexmbs check STUDY.toml | head`
/// stops reading), the text is dropped instead of aborting the program with a broken pipe.
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// `print!` that cannot panic (see [`say!`]).
#[macro_export]
macro_rules! say_raw {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout(), $($arg)*);
    }};
}

/// `eprintln!` that cannot panic when stderr is closed (`flexmbs ... 2>&1 | head`).
#[macro_export]
macro_rules! tell {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

pub mod builtin;
pub mod cli;
pub mod console;
