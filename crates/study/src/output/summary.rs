//! The results folder: CSV files (one per result group, with units in the header),
//! `summary.json` and `summary.md`, written as the analyses finish so that an interrupted
//! run keeps what it computed. Every file is written to a temporary name and renamed, so a
//! file that exists is complete.
//!
//! ```text
//! <results>/
//!   summary.json, summary.md      rewritten after every analysis
//!   view.html                     the results page, rewritten after every analysis (crate::output::view)
//!   .flexmbs-manifest             the files flexmbs wrote here, with their SHA-256 (crate::output::folder)
//!   .flexmbs-lock                 locked by the operating system while a run writes here (crate::output::folder)
//!   <analysis>/                   one folder per analysis, named by it
//!     *.csv                       result groups, header "name (unit)"
//!     *.vtu, *.pvd                ParaView: mesh and displacement fields (crate::output::vtu)
//!     <part>.rbody                reduce: the reduced body
//! ```

use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A temporary name beside `path`, unique per process and per call (concurrent writers never
/// share one); it ends with the file's own name, so a writer that picks a format by the
/// extension picks the same one.
pub fn temporary_beside(path: &Path) -> PathBuf {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .unwrap_or_default();
    static COUNTER: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    dir.join(format!(".{}-{n}.tmp.{name}", std::process::id()))
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temporary_beside(path);
    // On any failure (a full disk: the write; a vanished folder: the rename) no temporary
    // stays behind, and the error names the file that was being written.
    let named = |e: std::io::Error| std::io::Error::new(e.kind(), format!("{}: {e}", path.display()));
    std::fs::write(&tmp, bytes)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            named(e)
        })
}

/// A CSV table built in memory and written at once.
pub struct Csv {
    text: String,
    columns: usize,
}

impl Csv {
    /// A table with a header line; each column name carries its unit, `"ux [m]"`.
    pub fn new(header: &[&str]) -> Self {
        Self {
            text: header.join(",") + "\n",
            columns: header.len(),
        }
    }

    /// Appends a row; text cells with a comma or quote are quoted.
    pub fn row(&mut self, cells: &[String]) {
        debug_assert_eq!(cells.len(), self.columns);
        let quoted: Vec<String> = cells
            .iter()
            .map(|c| {
                if c.contains([',', '"', '\n']) {
                    format!("\"{}\"", c.replace('"', "\"\""))
                } else {
                    c.clone()
                }
            })
            .collect();
        self.text.push_str(&quoted.join(","));
        self.text.push('\n');
    }

    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        write_atomic(path, self.text.as_bytes())
    }

    /// The text of the table, header first.
    pub fn text(&self) -> &str {
        &self.text
    }
}

/// A number for a CSV cell: the shortest decimal that reads back to the same `f64`.
pub fn num(x: f64) -> String {
    format!("{x:e}")
}

/// One part, for the summary.
#[derive(Clone, Debug, Serialize)]
pub struct PartSummary {
    pub name: String,
    pub description: String,
    pub nodes: usize,
    pub elements: usize,
    pub interfaces: Vec<String>,
}

/// Status of an analysis in the summary.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    Pending,
    Done,
    Failed,
}

impl std::fmt::Display for Status {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Status::Pending => "pending",
            Status::Done => "done",
            Status::Failed => "failed",
        })
    }
}

/// One analysis, for the summary.
#[derive(Clone, Debug, Serialize)]
pub struct AnalysisSummary {
    pub name: String,
    #[serde(rename = "type")]
    pub kind: String,
    pub part: String,
    pub status: Status,
    pub seconds: Option<f64>,
    /// Independent dofs of the FE model it ran on.
    pub free_dofs: Option<usize>,
    /// Lines of text: what it found (also printed on stdout).
    pub report: Vec<String>,
    /// Analysis-specific numbers (frequencies, modes kept, maximum displacement, ...).
    pub results: serde_json::Value,
    /// Files written, relative to the results folder.
    pub files: Vec<String>,
    pub error: Option<String>,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub flexmbs_version: String,
    pub study: String,
    pub title: Option<String>,
    /// `running`, `complete`, `failed` or `interrupted` (Ctrl-C or SIGTERM; what was written
    /// is kept).
    pub status: String,
    /// Why a run that is `failed` or `interrupted` stopped: the analysis, the cause and, for a
    /// time integration, the last time reached (absent while running and when complete).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    pub parts: Vec<PartSummary>,
    pub analyses: Vec<AnalysisSummary>,
    pub total_seconds: f64,
}

impl Summary {
    /// Writes `summary.json` and `summary.md` into `dir`.
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        write_atomic(&dir.join("summary.json"), self.json().as_bytes())?;
        write_atomic(&dir.join("summary.md"), self.markdown().as_bytes())
    }

    /// The text of `summary.json`.
    pub fn json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// The short human summary: model sizes, analyses with timings, and what each found.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "# {}\n", self.title.as_deref().unwrap_or("flexmbs results"));
        let _ = writeln!(
            s,
            "Study `{}`, flexmbs {}, status **{}**, {:.2} s in all.\n",
            self.study, self.flexmbs_version, self.status, self.total_seconds
        );
        if let Some(reason) = &self.reason {
            let _ = writeln!(s, "Stopped: {reason}\n");
        }
        let _ = writeln!(
            s,
            "## Parts\n\n| part | model | nodes | elements | interfaces |\n|---|---|---|---|---|"
        );
        for p in &self.parts {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} |",
                p.name,
                p.description,
                p.nodes,
                p.elements,
                if p.interfaces.is_empty() {
                    "-".to_string()
                } else {
                    p.interfaces.join(", ")
                }
            );
        }
        let _ = writeln!(
            s,
            "\n## Analyses\n\n| analysis | type | part | free dofs | status | time [s] |\n|---|---|---|---|---|---|"
        );
        for a in &self.analyses {
            let _ = writeln!(
                s,
                "| {} | {} | {} | {} | {} | {} |",
                a.name,
                a.kind,
                a.part,
                a.free_dofs.map_or("-".to_string(), |n| n.to_string()),
                a.status,
                a.seconds.map_or("-".to_string(), |t| format!("{t:.3}"))
            );
        }
        for a in &self.analyses {
            if a.report.is_empty() && a.error.is_none() {
                continue;
            }
            let _ = writeln!(s, "\n### {}\n", a.name);
            for line in &a.report {
                let _ = writeln!(s, "- {line}");
            }
            if let Some(e) = &a.error {
                let _ = writeln!(s, "- **failed**: {e}");
            }
        }
        s
    }
}

/// The default results folder of a study: `<study dir>/<study stem>-results`.
pub fn default_results_dir(study: &Path) -> PathBuf {
    let stem = study
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "study".into());
    study
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default()
        .join(format!("{stem}-results"))
}

/// The start section of a dynamic analysis that starts at t = 0: how each coordinate got its
/// position and rate (`mbs::System::start_report`), or the choice to start at rest. Lines for
/// the report, and the same as JSON for `summary.json`.
pub(crate) fn start_section(report: &mbs::StartReport, at_rest: bool) -> (Vec<String>, serde_json::Value) {
    let mut lines = Vec::new();
    // The report lists the values above round-off of the largest (the start's solve leaves
    // components of about 1e-14 of it where the motion has none); summary.json keeps them all.
    let list = |items: &[(String, f64)], unit: &str| {
        let big = items.iter().map(|(_, x)| x.abs()).fold(0.0, f64::max);
        let shown: Vec<String> = items
            .iter()
            .filter(|(_, x)| x.abs() > 1e-12 * big)
            .map(|(l, x)| format!("{l} {x:.6e}{unit}"))
            .collect();
        match items.len() - shown.len() {
            0 => shown.join(", "),
            n => format!("{} ({n} more at round-off)", shown.join(", ")),
        }
    };
    let moving: Vec<&(String, f64, f64)> = report.drivers.iter().filter(|d| d.1 != 0.0 || d.2 != 0.0).collect();
    if at_rest {
        lines.push("start: at rest (`[[initial]] start = \"at-rest\"`): every coordinate's rate zero at t = 0 but the drivers', which keep their own".into());
    } else {
        lines.push("start: consistent (initial position and velocity analysis at t = 0)".into());
    }
    if !moving.is_empty() {
        let d: Vec<String> = moving
            .iter()
            .map(|(n, x, v)| format!("'{n}' value {x:.6e}, rate {v:.6e}"))
            .collect();
        lines.push(format!("start: set by drivers: {}", d.join("; ")));
    }
    if !report.initial.is_empty() {
        lines.push(format!("start: set by [[initial]]: {}", report.initial.join("; ")));
    }
    if !report.assembled.is_empty() {
        lines.push(format!(
            "start: positions assembled (closed loops): {}",
            list(&report.assembled, "")
        ));
    }
    if !at_rest && !report.solved.is_empty() {
        lines.push(format!(
            "start: rates solved (loops closed, flexible bodies moving rigidly): {}",
            list(&report.solved, "")
        ));
    }
    if report.modal > 0 {
        lines.push(format!(
            "start: {} modal coordinates at zero with zero rate (bodies undeformed, no strain rate)",
            report.modal
        ));
    }
    let json = serde_json::json!({
        "choice": if at_rest { "at-rest" } else { "consistent" },
        "drivers": report.drivers.iter().map(|(n, x, v)| serde_json::json!({"name": n, "value": x, "rate": v})).collect::<Vec<_>>(),
        "initial": report.initial,
        "assembled": report.assembled.iter().map(|(l, x)| serde_json::json!({"coordinate": l, "change": x})).collect::<Vec<_>>(),
        "solved": if at_rest { Vec::new() } else { report.solved.iter().map(|(l, x)| serde_json::json!({"coordinate": l, "rate": x})).collect::<Vec<_>>() },
        "unset": report.unset,
        "modal_at_rest": report.modal,
    });
    (lines, json)
}
