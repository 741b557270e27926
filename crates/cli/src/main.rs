//! `flexmbs`: from a mesh to the motion of a flexible mechanism. See `flexmbs --help` and
//! the library docs of this crate.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    // The validation suite has its own command line and exit codes (1: out of tolerance).
    if args.first().map(String::as_str) == Some("validate") {
        return validation::run_from_args(args[1..].to_vec());
    }
    match flexmbs::cli::main_with(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{}", study::error::report(&*e));
            ExitCode::from(2)
        }
    }
}
