//! `flexmbs`: from a mesh to the motion of a flexible mechanism. See `flexmbs --help` and
//! the library docs of this crate.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match flexmbs::cli::main_with(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{}", flexmbs::error::report(&*e));
            ExitCode::from(2)
        }
    }
}
