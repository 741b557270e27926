//! `cargo run --release -p validation [-- --quick] [--no-report] [--report-dir DIR] [--only ID ...]`:
//! the same command as `flexmbs validate` ([`validation::usage`]): runs the problems of the
//! validation guide, prints the report and writes it with its PNG figures.

fn main() -> std::process::ExitCode {
    validation::run_command("validation", std::env::args().skip(1).collect())
}
