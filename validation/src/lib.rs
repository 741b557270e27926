//! # validation: flexmbs against published results
//!
//! Each problem of `shared/brief/benchmarks.md` is a function that runs the pipeline and
//! returns a [`Table`] of quantity, reference, ours and relative error, with the tolerance
//! the method can honestly reach and the reason for it. `cargo run --release -p validation`
//! prints every table (and `--report` writes `validation/report/REPORT.md`);
//! `tests/quick.rs` runs the quick subset in CI and asserts the tolerances.
//!
//! The problems: the linear references A1-A5 (beam and membrane frequencies, cantilever
//! statics, Craig-Bampton convergence, the linear transient), the geometrically nonlinear
//! statics B1-B3 (elastica, roll-up, 45-degree bend) and the dynamics C1-C4 (spin-up,
//! planar and spatial slider-cranks, free-floating body), each with its convergence study,
//! and the seed's comparison of the frame choices and inertia variants ([`benchmarks::variants`]).
//! Models are built by library calls in [`models`]; the report's figures are drawn by the
//! `plot` crate.
//!
//! [`run_from_args`] is the command line (`cargo run --release -p validation -- [--quick]
//! [--no-report] [--only ID...]`); `flexmbs validate` forwards to it.

#![allow(non_snake_case)]

pub mod benchmarks;
pub mod models;

use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

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
        for r in &self.rows {
            let _ = writeln!(
                s,
                "| {} | {:.6e} | {:.6e} | {:.2e} | {} |",
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

/// Number formatting for grids: 3 significant digits in scientific notation.
pub fn sci(v: f64) -> String {
    format!("{v:.2e}")
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
    ]
}

/// Every benchmark whose id is in `only` (all when empty), in report order.
pub fn run_all(extent: Extent, only: &[String]) -> Result<Vec<Block>, Box<dyn std::error::Error>> {
    let mut blocks = Vec::new();
    for (id, run) in benchmarks() {
        if only.is_empty() || only.iter().any(|o| o == id) {
            let t0 = std::time::Instant::now();
            blocks.extend(run(extent).map_err(|e| format!("{id}: {e}"))?);
            eprintln!("validation: {id} done in {:.1} s", t0.elapsed().as_secs_f64());
        }
    }
    Ok(blocks)
}

/// The report as Markdown, with the figures written beside it in `dir`.
pub fn write_report(blocks: &[Block], dir: &Path, command: &str) -> Result<String, Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    let mut report = format!(
        "# flexmbs validation report\n\nGenerated by `{command}`. Problems: `shared/brief/benchmarks.md`; \
         every table states its model and why its tolerance is what it is. Timings are wall-clock on \
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

/// The command line: `[--quick] [--no-report] [--report-dir DIR] [--only ID ...]`. Prints the
/// report, writes `validation/report/REPORT.md` and the PNGs (unless `--no-report`), and
/// exits with 1 if a quantity is outside its tolerance, 2 on an error.
pub fn run_from_args(args: Vec<String>) -> ExitCode {
    let mut extent = Extent::Full;
    let mut write = true;
    let mut dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("report");
    let mut only = Vec::new();
    let mut it = args.into_iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => extent = Extent::Quick,
            "--full" => extent = Extent::Full,
            // Kept for the old command line: the report is written by default now.
            "--report" => write = true,
            "--no-report" => write = false,
            "--report-dir" => match it.next() {
                Some(d) => dir = PathBuf::from(d),
                None => {
                    eprintln!("validation: --report-dir needs a directory");
                    return ExitCode::from(2);
                }
            },
            "--only" => only.extend(it.by_ref()),
            "-h" | "--help" => {
                println!(
                    "validation [--quick] [--no-report] [--report-dir DIR] [--only ID ...]\nids: {}",
                    benchmarks().iter().map(|b| b.0).collect::<Vec<_>>().join(" ")
                );
                return ExitCode::SUCCESS;
            }
            other => {
                eprintln!("validation: unknown argument '{other}' (try --help)");
                return ExitCode::from(2);
            }
        }
    }
    let blocks = match run_all(extent, &only) {
        Ok(b) => b,
        Err(e) => {
            eprintln!("validation: error: {e}");
            return ExitCode::from(2);
        }
    };
    let command = match extent {
        Extent::Quick => "cargo run --release -p validation -- --quick",
        Extent::Full => "cargo run --release -p validation",
    };
    let scratch = std::env::temp_dir().join(format!("validation-figures-{}", std::process::id()));
    let target = if write { dir.clone() } else { scratch };
    let report = match write_report(&blocks, &target, command) {
        Ok(r) => r,
        Err(e) => {
            eprintln!("validation: error: {e}");
            return ExitCode::from(2);
        }
    };
    print!("{report}");
    if write {
        if let Err(e) = std::fs::write(dir.join("REPORT.md"), &report) {
            eprintln!("validation: cannot write {}: {e}", dir.join("REPORT.md").display());
            return ExitCode::from(2);
        }
        eprintln!("validation: wrote {}", dir.join("REPORT.md").display());
    }
    let failures = failures(&blocks);
    if !failures.is_empty() {
        eprintln!(
            "validation: {} quantities outside their tolerance:\n{}",
            failures.len(),
            failures.join("\n")
        );
        return ExitCode::from(1);
    }
    ExitCode::SUCCESS
}
