//! `flexmbs`: from a mesh to the motion of a flexible mechanism.
//!
//! Today the program runs the built-in beam example (statics and modes of a cantilever,
//! printed against the analytic values); study files, reduction, superelements and the
//! multibody solver are added by the issues that build those stages.

use std::process::ExitCode;

mod beam_example;

const USAGE: &str = "usage: flexmbs run            run the built-in example (a 3D cantilever: statics and modes against beam theory)\n       flexmbs --help         this text";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
        ["run"] => match beam_example::run() {
            Ok(report) => {
                print!("{report}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("flexmbs: error: {e}");
                let mut source = std::error::Error::source(&*e);
                while let Some(s) = source {
                    eprintln!("  caused by: {s}");
                    source = s.source();
                }
                ExitCode::from(2)
            }
        },
        ["--help"] | ["-h"] | ["help"] => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        [] => {
            eprintln!("{USAGE}");
            ExitCode::from(2)
        }
        other => {
            eprintln!("flexmbs: unknown command '{}'\n{USAGE}", other.join(" "));
            ExitCode::from(2)
        }
    }
}
