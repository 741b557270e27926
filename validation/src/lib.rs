//! # validation: flexmbs against published results
//!
//! Each problem of the validation guide (`docs/validation.md`) is a function that runs the
//! pipeline and returns a [`Table`] of quantity, reference, ours and relative error, with the
//! tolerance the method can honestly reach and the reason for it. `flexmbs validate` (or
//! `cargo run --release -p validation`) prints every table and writes the report
//! (`./validation-report/REPORT.md` unless `--report-dir` says otherwise);
//! `tests/suite/quick.rs` runs the quick subset in CI and asserts the tolerances.
//!
//! The problems: the linear references A1-A5 (beam and membrane frequencies, cantilever
//! statics, Craig-Bampton convergence, the linear transient), the geometrically nonlinear
//! statics B1-B3 (elastica, roll-up, 45-degree bend) and the dynamics C1-C4 (spin-up,
//! planar and spatial slider-cranks, free-floating body), each with its convergence study,
//! and the AIC-FFR papers' comparison of the frame choices and inertia variants ([`benchmarks::variants`]).
//! Models are built by library calls in [`models`]; the report's figures are drawn by the
//! `plot` crate.
//!
//! [`run_command`] is the command line ([`usage`]); `flexmbs validate` forwards to it through
//! [`run_from_args`].

#![allow(non_snake_case)]

pub mod benchmarks;
pub use ::models;

use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

/// Whether tables and [`sci`] print numbers to round-trip precision (`--full-precision`), so
/// two versions of flexmbs can be compared beyond the report's printed digits
/// (`validation/scripts/compare_reports.py`).
static FULL_PRECISION: AtomicBool = AtomicBool::new(false);

/// Print every table value and [`sci`] number with 17 significant digits from now on.
pub fn set_full_precision(on: bool) {
    FULL_PRECISION.store(on, Ordering::Relaxed);
}

fn full_precision() -> bool {
    FULL_PRECISION.load(Ordering::Relaxed)
}

/// One compared quantity.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub quantity: String,
    pub reference: f64,
    pub ours: f64,
    /// Largest relative error the test subset accepts for this row.
    pub tolerance: f64,
    /// The error is $|ours - reference| / scale$; `scale` is $|reference|$ unless the
    /// reference is zero or the quantity is normalised by something else (a length, a peak).
    pub scale: f64,
}

impl Row {
    pub fn new(quantity: impl Into<String>, reference: f64, ours: f64, tolerance: f64) -> Self {
        Self {
            quantity: quantity.into(),
            reference,
            ours,
            tolerance,
            scale: reference.abs(),
        }
    }

    /// A row whose error is measured against `scale` instead of the reference itself.
    pub fn scaled(quantity: impl Into<String>, reference: f64, ours: f64, scale: f64, tolerance: f64) -> Self {
        Self {
            scale,
            ..Self::new(quantity, reference, ours, tolerance)
        }
    }

    /// $|ours - reference| / scale$ (the relative error unless [`Row::scaled`]).
    pub fn relative_error(&self) -> f64 {
        ((self.ours - self.reference) / self.scale).abs()
    }

    pub fn passes(&self) -> bool {
        self.relative_error() <= self.tolerance
    }
}

/// A table of one problem (or one refinement study of it).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// Problem id and name, e.g. "A1 cantilever bending frequencies".
    pub title: String,
    /// The model and why the tolerance is what it is.
    pub note: String,
    pub rows: Vec<Row>,
}

impl Table {
    /// The table as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "### {}\n\n{}\n", self.title, self.note);
        let _ = writeln!(
            s,
            "| quantity | reference | flexmbs | rel. error | tolerance |\n|---|---:|---:|---:|---:|"
        );
        let digits = if full_precision() { 16 } else { 6 };
        for r in &self.rows {
            let _ = writeln!(
                s,
                "| {} | {:.digits$e} | {:.digits$e} | {:.2e} | {} |",
                r.quantity,
                r.reference,
                r.ours,
                r.relative_error(),
                if r.tolerance.is_finite() {
                    // 1e-3 as "1e-3", 1.1 as "1.1e0".
                    let tol = if r.tolerance.log10().fract() == 0.0 {
                        format!("{:.0e}", r.tolerance)
                    } else {
                        format!("{:.1e}", r.tolerance)
                    };
                    format!("{tol}{}", if r.passes() { "" } else { " **FAIL**" })
                } else {
                    "—".to_string()
                }
            );
        }
        s
    }
}

/// A table of strings (convergence studies, variant comparisons): no pass/fail.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub title: String,
    pub note: String,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl Grid {
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "### {}\n\n{}\n", self.title, self.note);
        let _ = writeln!(s, "| {} |", self.header.join(" | "));
        let _ = writeln!(s, "|{}", "---|".repeat(self.header.len()));
        for r in &self.rows {
            let _ = writeln!(s, "| {} |", r.join(" | "));
        }
        s
    }
}

/// One piece of the report, in order.
#[derive(Clone, Debug)]
pub enum Block {
    /// A section heading (`## ...`).
    Heading(String),
    /// Markdown text: what the figures show.
    Text(String),
    /// Quantities against references with tolerances (asserted by the quick tests).
    Table(Table),
    /// A convergence or comparison table.
    Grid(Grid),
    /// A plot written to `report/<file>` and shown in the report.
    Figure { file: String, figure: plot::Figure },
}

/// The tables with tolerances among `blocks`.
pub fn tables(blocks: &[Block]) -> impl Iterator<Item = &Table> {
    blocks.iter().filter_map(|b| match b {
        Block::Table(t) => Some(t),
        _ => None,
    })
}

/// Rows of `blocks` outside their tolerance, one line each.
pub fn failures(blocks: &[Block]) -> Vec<String> {
    tables(blocks)
        .flat_map(|t| {
            t.rows.iter().filter(|r| !r.passes()).map(move |r| {
                format!(
                    "{}: {}: {} vs {} (error {:.2e} > {:.0e})",
                    t.title,
                    r.quantity,
                    r.ours,
                    r.reference,
                    r.relative_error(),
                    r.tolerance
                )
            })
        })
        .collect()
}

/// Least-squares slope of $\log e$ against $\log x$: the observed convergence rate.
pub fn slope(x: &[f64], err: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = x.iter().zip(err).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum::<f64>()
        / lx.iter().map(|a| (a - mx) * (a - mx)).sum::<f64>()
}

/// Number formatting for grids: 3 significant digits in scientific notation (17 with
/// `--full-precision`).
pub fn sci(v: f64) -> String {
    if full_precision() {
        format!("{v:.16e}")
    } else {
        format!("{v:.2e}")
    }
}

/// How much of each study to run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Extent {
    /// The coarse levels only: seconds in a debug build, for CI.
    Quick,
    /// Every refinement level.
    Full,
}

/// A benchmark: its id (for `--only`) and the function that runs it.
pub type Benchmark = (
    &'static str,
    fn(Extent) -> Result<Vec<Block>, Box<dyn std::error::Error>>,
);

/// Every benchmark, in report order.
pub fn benchmarks() -> Vec<Benchmark> {
    vec![
        ("A1-A4", benchmarks::linear::a1_to_a4),
        ("A5", benchmarks::transient::a5_linear_transient),
        ("B1", benchmarks::nonlinear_statics::b1_elastica),
        ("B2", benchmarks::nonlinear_statics::b2_roll_up),
        ("B3", benchmarks::nonlinear_statics::b3_bend),
        ("C1", benchmarks::dynamics::c1_spin_up),
        ("C2", benchmarks::dynamics::c2_slider_crank),
        ("C3", benchmarks::dynamics::c3_spatial_slider_crank),
        ("C4", benchmarks::dynamics::c4_free_body),
        ("S1", benchmarks::stress::s1_transient_stress),
        ("V", benchmarks::variants::variants),
        ("F1", benchmarks::frame_buckling::f1_portal_frame),
    ]
}

/// Whether the user's `id` selects the benchmark `benchmark`: the same id in any case, or
/// one of the problems a grouped id such as `A1-A4` runs together.
pub fn selects(id: &str, benchmark: &str) -> bool {
    let id = id.trim().to_ascii_uppercase();
    let benchmark = benchmark.to_ascii_uppercase();
    if id == benchmark {
        return true;
    }
    let Some((first, last)) = benchmark.split_once('-') else {
        return false;
    };
    let split = |s: &str| -> Option<(char, u32)> {
        let mut c = s.chars();
        let letter = c.next()?;
        Some((letter, c.as_str().parse().ok()?))
    };
    match (split(&id), split(first), split(last)) {
        (Some((l, n)), Some((l0, n0)), Some((l1, n1))) => l == l0 && l == l1 && (n0..=n1).contains(&n),
        _ => false,
    }
}

/// Every benchmark selected by an id in `only` (all when empty), in report order. An id that
/// selects no benchmark is an error naming the ids there are, before anything runs.
pub fn run_all(extent: Extent, only: &[String]) -> Result<Vec<Block>, Box<dyn std::error::Error>> {
    check_ids(only)?;
    let mut blocks = Vec::new();
    for (id, run) in benchmarks() {
        if only.is_empty() || only.iter().any(|o| selects(o, id)) {
            let t0 = std::time::Instant::now();
            blocks.extend(run(extent).map_err(|e| format!("{id}: {e}"))?);
            eprintln!("validation: {id} done in {:.1} s", t0.elapsed().as_secs_f64());
        }
    }
    Ok(blocks)
}

/// The ids there are, for messages: `A1 A2 A3 A4 A5 B1 ... V`.
pub fn benchmark_ids() -> String {
    benchmarks().iter().map(|b| b.0).collect::<Vec<_>>().join(" ")
}

/// An error naming every id of `only` that selects no benchmark.
pub fn check_ids(only: &[String]) -> Result<(), String> {
    let unknown: Vec<&str> = only
        .iter()
        .filter(|o| !benchmarks().iter().any(|(id, _)| selects(o, id)))
        .map(|o| o.as_str())
        .collect();
    if unknown.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "unknown benchmark id{} {}: the ids are {} (A1 to A4 also one by one)",
            if unknown.len() > 1 { "s" } else { "" },
            unknown.iter().map(|u| format!("'{u}'")).collect::<Vec<_>>().join(", "),
            benchmark_ids()
        ))
    }
}

/// The report as Markdown, with the figures written beside it in `dir`.
pub fn write_report(blocks: &[Block], dir: &Path, command: &str) -> Result<String, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut report = format!(
        "# flexmbs validation report\n\nGenerated by `{command}`. The problems are defined in the validation guide, \
         `docs/validation.md`; every table states its model and why its tolerance is what it is. Timings are wall-clock on \
         a shared 2-core machine and are indicative only.\n\n"
    );
    for b in blocks {
        match b {
            Block::Heading(h) => {
                let _ = writeln!(report, "## {h}\n");
            }
            Block::Text(t) => {
                let _ = writeln!(report, "{t}\n");
            }
            Block::Table(t) => {
                let _ = writeln!(report, "{}", t.markdown());
            }
            Block::Grid(g) => {
                let _ = writeln!(report, "{}", g.markdown());
            }
            Block::Figure { file, figure } => {
                plot::write_png(figure, &dir.join(file))?;
                let _ = writeln!(report, "![{}]({file})\n", figure.title);
            }
        }
    }
    Ok(report)
}

/// The report folder when none is given: `validation-report` in the current folder, never the
/// source tree (the repository's `validation/report/` is written only when asked for with
/// `--report-dir validation/report`).
pub const DEFAULT_REPORT_DIR: &str = "validation-report";

/// What the command line asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub extent: Extent,
    /// Write the report and its figures (default), or only print it.
    pub write: bool,
    pub dir: PathBuf,
    /// Benchmark ids to run; all when empty.
    pub only: Vec<String>,
    /// Tables and grid numbers to 17 significant digits (for comparing two versions).
    pub full_precision: bool,
    pub help: bool,
}

/// The usage text of `program` (`flexmbs validate` or `validation`).
pub fn usage(program: &str) -> String {
    format!(
        "usage: {program} [--quick] [--no-report] [--report-dir DIR] [--full-precision] [--only ID...]\n\n\
         Runs the benchmark problems of docs/validation.md through the whole pipeline, prints the\n\
         report and writes it with its figures to DIR/REPORT.md (default: ./{DEFAULT_REPORT_DIR}).\n\n\
         --quick           the coarse refinement levels only (seconds instead of minutes)\n\
         --no-report       print the report without writing it\n\
         --report-dir DIR  where REPORT.md and its PNG figures go\n\
         --full-precision  table values and convergence numbers to 17 significant digits, to\n\
         \x20                 compare two versions (validation/scripts/compare_reports.py)\n\
         --only ID...      the problems to run, separated by spaces or commas: {}\n\n\
         Exit status: 0 when every quantity is within its tolerance, 1 when one is not, 2 on an error.\n",
        benchmark_ids()
    )
}

/// Parses the arguments after the program name. `--only` takes the ids up to the next
/// option, so `--only B1 --quick` runs B1 quickly.
pub fn parse_args(args: &[String]) -> Result<Options, String> {
    let mut options = Options {
        extent: Extent::Full,
        write: true,
        dir: PathBuf::from(DEFAULT_REPORT_DIR),
        only: Vec::new(),
        full_precision: false,
        help: false,
    };
    let mut it = args.iter().peekable();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => options.extent = Extent::Quick,
            "--full" => options.extent = Extent::Full,
            "--report" => options.write = true,
            "--no-report" => options.write = false,
            "--full-precision" => options.full_precision = true,
            "--report-dir" => match it.next() {
                Some(d) if !d.starts_with("--") => options.dir = PathBuf::from(d),
                _ => return Err("--report-dir needs a folder".into()),
            },
            "--only" => {
                let before = options.only.len();
                while let Some(id) = it.next_if(|s| !s.starts_with('-')) {
                    options.only.extend(
                        id.split(',')
                            .filter(|s| !s.trim().is_empty())
                            .map(|s| s.trim().to_string()),
                    );
                }
                if options.only.len() == before {
                    return Err(format!("--only needs benchmark ids: {}", benchmark_ids()));
                }
            }
            "-h" | "--help" => options.help = true,
            other => return Err(format!("unknown argument '{other}'")),
        }
    }
    check_ids(&options.only)?;
    Ok(options)
}

/// `flexmbs validate`: [`run_command`] under that name.
pub fn run_from_args(args: Vec<String>) -> ExitCode {
    run_command("flexmbs validate", args)
}

/// The command line of `program`: `[--quick] [--no-report] [--report-dir DIR] [--full-precision] [--only ID ...]`
/// ([`usage`]). Prints the report, writes `DIR/REPORT.md` and the PNGs (unless
/// `--no-report`), and exits with 1 if a quantity is outside its tolerance, 2 on an error.
pub fn run_command(program: &str, args: Vec<String>) -> ExitCode {
    let options = match parse_args(&args) {
        Ok(o) => o,
        Err(e) => {
            eprintln!("{program}: {e}\n(try {program} --help)");
            return ExitCode::from(2);
        }
    };
    if options.help {
        let _ = std::io::Write::write_all(&mut std::io::stdout(), usage(program).as_bytes());
        return ExitCode::SUCCESS;
    }
    let Options {
        extent,
        write,
        dir,
        only,
        full_precision,
        ..
    } = options;
    set_full_precision(full_precision);
    let blocks = match run_all(extent, &only) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("{program}: error: {e}");
            return ExitCode::from(2);
        }
    };
    let command = std::iter::once(program.to_string())
        .chain(args)
        .collect::<Vec<_>>()
        .join(" ");
    let scratch = std::env::temp_dir().join(format!("validation-figures-{}", std::process::id()));
    let target = if write { dir.clone() } else { scratch };
    let report = match write_report(&blocks, &target, &command) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("{program}: error: {e}");
            return ExitCode::from(2);
        }
    };
    // A closed stdout (`| head`) drops the text: the report is still written to DIR.
    let _ = std::io::Write::write_all(&mut std::io::stdout(), report.as_bytes());
    if write {
        if let Err(e) = std::fs::write(dir.join("REPORT.md"), &report) {
            eprintln!("{program}: cannot write {}: {e}", dir.join("REPORT.md").display());
            return ExitCode::from(2);
        }
        eprintln!("{program}: wrote {}", dir.join("REPORT.md").display());
    }
    let failures = failures(&blocks);
    if !failures.is_empty() {
        eprintln!(
            "{program}: {} quantities outside their tolerance:\n{}",
            failures.len(),
            failures.join("\n")
        );
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}
