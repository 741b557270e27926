//! `flexmbs`: from a mesh to the motion of a flexible mechanism. See `flexmbs --help` and
//! the library docs of this crate.

use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("validate") {
        return validate(args[1..].to_vec());
    }
    // Ctrl-C (SIGINT) and SIGTERM (what batch schedulers and `kill` send): the first asks
    // the run to stop at its next output step with a truthful summary (`study::interrupt`,
    // which also learns which signal it was), a second ends the program at once (exit 130
    // and 143, the shells' 128 + signal). The handlers only set atomics.
    let flag = study::interrupt::flag();
    let signal = study::interrupt::signal();
    for (sig, tag, code) in [
        (signal_hook::consts::SIGINT, study::interrupt::SIGINT, 130),
        (signal_hook::consts::SIGTERM, study::interrupt::SIGTERM, 143),
    ] {
        let _ = signal_hook::flag::register_conditional_shutdown(sig, code, flag.clone());
        let _ = signal_hook::flag::register_usize(sig, signal.clone(), tag);
        let _ = signal_hook::flag::register(sig, flag.clone());
    }
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
