//! # validation: flexmbs against published results
//!
//! Each problem of `shared/brief/benchmarks.md` is a function that runs the pipeline and
//! returns a [`Table`] of quantity, reference, ours and relative error, with the tolerance
//! the method can honestly reach and the reason for it. `cargo run --release -p validation`
//! prints every table (and `--report` writes `validation/report/REPORT.md`);
//! `tests/quick.rs` runs the quick subset in CI and asserts the tolerances.
//!
//! Today: the linear references A1-A4 (beam and membrane frequencies, cantilever statics,
//! Craig-Bampton convergence). The nonlinear statics (B) and dynamics (C) arrive with the
//! multibody solver.

#![allow(non_snake_case)]

pub mod benchmarks;

use std::fmt::Write;

/// One compared quantity.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub quantity: String,
    pub reference: f64,
    pub ours: f64,
    /// Largest relative error the test subset accepts for this row.
    pub tolerance: f64,
}

impl Row {
    pub fn new(quantity: impl Into<String>, reference: f64, ours: f64, tolerance: f64) -> Self {
        Self {
            quantity: quantity.into(),
            reference,
            ours,
            tolerance,
        }
    }

    /// $|ours - reference| / |reference|$.
    pub fn relative_error(&self) -> f64 {
        ((self.ours - self.reference) / self.reference).abs()
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
                    format!("{:.0e}{}", r.tolerance, if r.passes() { "" } else { " **FAIL**" })
                } else {
                    "—".to_string()
                }
            );
        }
        s
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

/// Every benchmark that exists today, in report order.
pub fn run_all(extent: Extent) -> Result<Vec<Table>, Box<dyn std::error::Error>> {
    let mut tables = Vec::new();
    tables.extend(benchmarks::linear::a1_cantilever_frequencies(extent)?);
    tables.push(benchmarks::linear::a1_timoshenko_pinned_pinned(extent)?);
    tables.push(benchmarks::linear::a2_cantilever_statics()?);
    tables.push(benchmarks::linear::a3_craig_bampton_convergence(extent)?);
    tables.push(benchmarks::linear::a4_fv32(extent)?);
    Ok(tables)
}
