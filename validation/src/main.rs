//! `cargo run --release -p validation [-- --quick] [--no-report] [--only ID ...]`: runs the
//! benchmarks of `benchmarks.md`, prints the report, and writes `validation/report/REPORT.md`
//! with its PNG figures (see [`validation::run_from_args`]).

fn main() -> std::process::ExitCode {
    validation::run_from_args(std::env::args().skip(1).collect())
}
