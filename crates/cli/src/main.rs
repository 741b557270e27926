//! `flexmbs`: from a mesh to the motion of a flexible mechanism. See `flexmbs --help` and
//! the library docs of this crate.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("validate") {
        return validate(args[1..].to_vec());
    }
    // Ctrl-C: a second one ends the program at once (exit 130), the first asks the run to
    // stop at its next output step (`study::interrupt`).
    let flag = study::interrupt::flag();
    let _ = signal_hook::flag::register_conditional_shutdown(signal_hook::consts::SIGINT, 130, flag.clone());
    let _ = signal_hook::flag::register(signal_hook::consts::SIGINT, flag);
    match flexmbs::cli::main_with(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            flexmbs::tell!("{}", study::error::report(&*e));
            if e.is::<flexmbs::cli::ChecksFailed>() {
                ExitCode::from(1)
            } else {
                ExitCode::from(2)
            }
        }
    }
}

/// `flexmbs validate`: the validation suite, which has its own command line and exit codes
/// (1: out of tolerance).
#[cfg(feature = "validate")]
fn validate(args: Vec<String>) -> ExitCode {
    validation::run_from_args(args)
}

/// `flexmbs validate` in a program built without the suite: how to get it.
#[cfg(not(feature = "validate"))]
fn validate(_args: Vec<String>) -> ExitCode {
    flexmbs::tell!("{}", flexmbs::cli::VALIDATE_NOT_BUILT);
    ExitCode::from(2)
}
