//! The results folder as an [`Observer`]: tables as CSV, mesh frames as VTU files listed in a
//! PVD collection, sensor streams as CSV files written whenever [`FLUSH_INTERVAL`] has passed,
//! at an interruption and at their end (and a PNG per sensor at the end), reduced bodies copied, and `summary.json`/`summary.md` rewritten after every
//! analysis. Layout in `crate::output`.
//!
//! # What a run owns, and what it never touches
//!
//! - **Manifest** (`.flexmbs-manifest`): every file a run writes is appended to it (one path
//!   per line, relative to the results folder) *before* the file is created, so an interrupted
//!   run's files are known too. A run deletes only files listed there: at the start of an
//!   analysis, the files an earlier run wrote for it (stale plots included); at the start of
//!   the run, the files of analyses no longer in the study, and their folders when that
//!   empties them. Nothing else is ever deleted.
//! - **Foreign files**: a file in an analysis folder, or a `summary.json`/`summary.md`, that
//!   the manifest does not list was not written by flexmbs. The run refuses to start
//!   ([`ForeignFiles::Refuse`], the default) or writes beside them, leaving them alone
//!   ([`ForeignFiles::Keep`], `--foreign-files keep`).
//! - **Lock** (`.flexmbs-lock`, holding the process id): one run per results folder. A second
//!   run stops with a message naming the process; a lock whose process no longer exists (a
//!   run killed hard) is taken over.

use crate::error::{BoxError, ResultExt};
use crate::output::observer::{AnalysisInfo, Cell, Observer, SensorGroup, SensorStream, Series, Table};
use crate::output::summary::{num, Csv, Summary};
use crate::output::vtu::{write_pvd, write_vtu, PointField, VtuMesh};
use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Buffered sensor rows are written to their files at the first row after this much wall time
/// since the last write (and all of them when the stream ends or the run is interrupted): a
/// program reading the files during a run sees the rows with this delay. A flush per row is a
/// system call per sensor and step: with the five sensors of a slider-crank study, 5-10 % of
/// a mechanism step of about 100 µs (BENCHMARKS.md, the slider-crank C2 with a beam rod).
pub const FLUSH_INTERVAL: std::time::Duration = std::time::Duration::from_millis(200);

/// A sensor stream being written: one CSV per sensor, and the values for the plots.
struct Stream {
    x_label: String,
    groups: Vec<SensorGroup>,
    plots: bool,
    files: Vec<(std::io::BufWriter<std::fs::File>, PathBuf)>,
    /// When the files were last flushed ([`FLUSH_INTERVAL`]).
    flushed: std::time::Instant,
    x: Vec<f64>,
    rows: Vec<Vec<Vec<f64>>>,
}

impl Stream {
    /// Writes every buffered row to its file; a failed write names the file.
    fn flush(&mut self) -> Result<(), BoxError> {
        for (w, path) in &mut self.files {
            w.flush().context(|| format!("cannot write {}", path.display()))?;
        }
        self.flushed = std::time::Instant::now();
        Ok(())
    }
}

/// Files in the folder that flexmbs did not write (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ForeignFiles {
    /// Refuse to write into a folder holding them (the default).
    #[default]
    Refuse,
    /// Write beside them; they are never deleted (a file of the same name is replaced).
    Keep,
}

/// The manifest of the files flexmbs wrote into a results folder (module docs).
pub const MANIFEST: &str = ".flexmbs-manifest";
/// The lock file of a results folder (module docs).
pub const LOCK: &str = ".flexmbs-lock";
const MANIFEST_HEADER: &str = "# files written by flexmbs into this results folder; only these are ever deleted by it";

/// The lock of a results folder, released when dropped.
struct FolderLock(PathBuf);

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Whether process `pid` exists (Linux: `/proc/<pid>`; elsewhere assumed alive).
fn process_alive(pid: u32) -> bool {
    let proc_dir = Path::new("/proc");
    !proc_dir.is_dir() || proc_dir.join(pid.to_string()).exists()
}

/// How long a run waits for the process id in a lock file another run has just created: the
/// file is created empty (atomically, so that only one run gets it) and its id written right
/// after, so a run starting at the same moment can find it empty for a few microseconds.
const LOCK_PID_WAIT: std::time::Duration = std::time::Duration::from_millis(1000);

/// What a run found in a lock file another run holds.
enum LockHolder {
    /// The process id written in it.
    Process(u32),
    /// The file was removed while being read: the other run has ended.
    Released,
    /// No process id appeared within [`LOCK_PID_WAIT`].
    Unnamed,
}

/// Reads the lock file at `path` until it holds a process id, is removed, or
/// [`LOCK_PID_WAIT`] has passed.
fn read_lock_holder(path: &Path) -> LockHolder {
    let start = std::time::Instant::now();
    loop {
        match std::fs::read_to_string(path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return LockHolder::Released,
            Ok(text) => {
                if let Ok(pid) = text.trim().parse::<u32>() {
                    return LockHolder::Process(pid);
                }
            }
            Err(_) => {}
        }
        if start.elapsed() >= LOCK_PID_WAIT {
            return LockHolder::Unnamed;
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
}

impl FolderLock {
    /// Creates the lock file with this process's id; a lock held by a live process (or one
    /// that never names its process) is refused, a dead process's lock or a lock released
    /// meanwhile is taken (a few attempts, as other runs may be taking it at the same time).
    fn acquire(root: &Path) -> Result<Self, BoxError> {
        let path = root.join(LOCK);
        for _ in 0..4 {
            match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(mut f) => {
                    let _ = writeln!(f, "{}", std::process::id());
                    return Ok(Self(path));
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => match read_lock_holder(&path) {
                    LockHolder::Released => {}
                    LockHolder::Process(pid) if !process_alive(pid) => {
                        // A run killed hard left it: take it over.
                        let _ = std::fs::remove_file(&path);
                    }
                    LockHolder::Process(pid) => {
                        return Err(format!(
                            "the results folder {} is in use by another flexmbs run (process {pid}): wait for it to finish or write elsewhere with --out; if no run is active, delete {}",
                            root.display(),
                            path.display()
                        )
                        .into())
                    }
                    LockHolder::Unnamed => {
                        return Err(format!(
                            "the results folder {} is in use by another flexmbs run that has not written its process id into {} within {} ms; if no run is active, delete it",
                            root.display(),
                            path.display(),
                            LOCK_PID_WAIT.as_millis()
                        )
                        .into())
                    }
                },
                Err(e) => {
                    return Err(Box::new(e)).context(|| format!("cannot lock the results folder {}", root.display()))
                }
            }
        }
        Err(format!("cannot lock the results folder {}", root.display()).into())
    }
}

/// Writes a study's results into a folder (module docs).
pub struct ResultsFolder {
    root: PathBuf,
    /// Every file of the manifest (relative paths).
    manifest: BTreeSet<String>,
    _lock: FolderLock,
    /// The current analysis: its folder and name.
    dir: PathBuf,
    prefix: String,
    files: Vec<String>,
    /// PVD entries of the current analysis, per series.
    series: Vec<(Series, Vec<(f64, String)>)>,
    stream: Option<Stream>,
}

/// The VTU file stem, number width, first number and PVD name of each series.
fn series_names(s: Series) -> (&'static str, usize, usize, &'static str) {
    match s {
        Series::Static => ("static", 0, 0, "static.pvd"),
        Series::Modes => ("mode_", 3, 1, "modes.pvd"),
        Series::Shapes => ("shape_", 3, 1, "shapes.pvd"),
        Series::Mechanism => ("mechanism_", 5, 0, "mechanism.pvd"),
    }
}

impl ResultsFolder {
    /// A results folder at `root` for a study with the analyses `analyses`, created and
    /// locked now; refuses foreign files unless `foreign` keeps them, and deletes the files of
    /// analyses no longer in the study (module docs).
    pub fn open(root: &Path, analyses: &[String], foreign: ForeignFiles) -> Result<Self, BoxError> {
        if root.as_os_str().is_empty() {
            return Err("the results folder is '' (an empty path): name a folder, e.g. --out results, or --out . for the current one".into());
        }
        std::fs::create_dir_all(root).context(|| format!("cannot create the results folder {}", root.display()))?;
        let lock = FolderLock::acquire(root)?;
        let manifest = read_manifest(root);
        if foreign == ForeignFiles::Refuse {
            let found = foreign_files(root, analyses, &manifest);
            if !found.is_empty() {
                let shown: Vec<String> = found.iter().take(5).map(|p| p.display().to_string()).collect();
                return Err(format!(
                    "the results folder {} holds {} file(s) that flexmbs did not write: {}{}; they are left alone: write elsewhere with --out, or beside them with --foreign-files keep",
                    root.display(),
                    found.len(),
                    shown.join(", "),
                    if found.len() > 5 { ", ..." } else { "" }
                )
                .into());
            }
        }
        let mut folder = Self {
            root: root.to_path_buf(),
            manifest,
            _lock: lock,
            dir: root.to_path_buf(),
            prefix: String::new(),
            files: Vec::new(),
            series: Vec::new(),
            stream: None,
        };
        // Analyses removed from the study: their files go, and their folders if that empties them.
        let current: BTreeSet<&str> = analyses.iter().map(String::as_str).collect();
        let stale: Vec<String> = folder
            .manifest
            .iter()
            .filter(|f| f.split_once('/').is_some_and(|(a, _)| !current.contains(a)))
            .cloned()
            .collect();
        folder.forget(&stale)?;
        for dir in stale
            .iter()
            .filter_map(|f| f.split_once('/').map(|(a, _)| a))
            .collect::<BTreeSet<_>>()
        {
            let _ = std::fs::remove_dir(root.join(dir));
        }
        Ok(folder)
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The path of `name` in the current analysis folder, listed for the summary and
    /// recorded in the manifest before the file is created.
    fn path(&mut self, name: &str) -> Result<PathBuf, BoxError> {
        let rel = format!("{}/{name}", self.prefix);
        self.record(&rel)?;
        self.files.push(rel);
        Ok(self.dir.join(name))
    }

    /// Appends `rel` to the manifest (once).
    fn record(&mut self, rel: &str) -> Result<(), BoxError> {
        if self.manifest.insert(rel.to_string()) {
            let path = self.root.join(MANIFEST);
            let new = !path.exists();
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&path)
                .context(|| format!("cannot write {}", path.display()))?;
            let line = if new {
                format!("{MANIFEST_HEADER}\n{rel}\n")
            } else {
                format!("{rel}\n")
            };
            f.write_all(line.as_bytes())
                .context(|| format!("cannot write {}", path.display()))?;
        }
        Ok(())
    }

    /// Deletes the listed files of the manifest and drops them from it.
    fn forget(&mut self, files: &[String]) -> Result<(), BoxError> {
        if files.is_empty() {
            return Ok(());
        }
        for f in files {
            match std::fs::remove_file(self.root.join(f)) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(Box::new(e)).context(|| format!("cannot delete {}", self.root.join(f).display())),
            }
            self.manifest.remove(f);
        }
        let mut text = format!("{MANIFEST_HEADER}\n");
        for f in &self.manifest {
            text.push_str(f);
            text.push('\n');
        }
        let path = self.root.join(MANIFEST);
        crate::output::summary::write_atomic(&path, text.as_bytes())
            .context(|| format!("cannot write {}", path.display()))
    }
}

/// The manifest of `root` (empty when there is none).
fn read_manifest(root: &Path) -> BTreeSet<String> {
    std::fs::read_to_string(root.join(MANIFEST))
        .unwrap_or_default()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#') && !l.split('/').any(|c| c == ".." || c.is_empty()))
        .map(str::to_string)
        .collect()
}

/// Files where a run of `analyses` writes that the manifest does not list: anything in the
/// analysis folders, and the summary files.
fn foreign_files(root: &Path, analyses: &[String], manifest: &BTreeSet<String>) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for name in ["summary.json", "summary.md"] {
        if root.join(name).exists() && !manifest.contains(name) {
            found.push(root.join(name));
        }
    }
    for a in analyses {
        let Ok(entries) = std::fs::read_dir(root.join(a)) else {
            continue;
        };
        for e in entries.flatten() {
            let rel = format!("{a}/{}", e.file_name().to_string_lossy());
            if !manifest.contains(&rel) {
                found.push(e.path());
            }
        }
    }
    found
}

/// A table cell as CSV text: integers as they are, numbers as the shortest decimal that
/// reads back to the same `f64`.
fn cell_text(c: &Cell) -> String {
    match c {
        Cell::Int(i) => i.to_string(),
        Cell::Num(x) => num(*x),
        Cell::Text(s) => s.clone(),
        Cell::Empty => String::new(),
    }
}

impl Observer for ResultsFolder {
    fn begin(&mut self, a: &AnalysisInfo) -> Result<(), BoxError> {
        self.dir = self.root.join(&a.name);
        self.prefix = a.name.clone();
        self.files.clear();
        self.series.clear();
        self.stream = None;
        // The files an earlier run wrote for this analysis (stale plots included), and only those.
        let prefix = format!("{}/", a.name);
        let old: Vec<String> = self
            .manifest
            .iter()
            .filter(|f| f.starts_with(&prefix))
            .cloned()
            .collect();
        self.forget(&old)?;
        crate::interrupt::check()?;
        std::fs::create_dir_all(&self.dir)
            .context(|| format!("cannot create the results folder {}", self.dir.display()))
    }

    fn table(&mut self, t: &Table) -> Result<(), BoxError> {
        let header: Vec<&str> = t.columns.iter().map(String::as_str).collect();
        let mut csv = Csv::new(&header);
        for r in &t.rows {
            csv.row(&r.iter().map(cell_text).collect::<Vec<_>>());
        }
        let p = self.path(&format!("{}.csv", t.name))?;
        csv.write(&p).context(|| format!("cannot write {}", p.display()))
    }

    fn sensors(&mut self, s: &SensorStream<'_>) -> Result<(), BoxError> {
        let mut files = Vec::new();
        for g in s.groups {
            let path = self.path(&format!("{}.csv", g.name))?;
            let f = std::fs::File::create(&path).context(|| format!("cannot create {}", path.display()))?;
            let mut w = std::io::BufWriter::new(f);
            let mut header = vec![s.x_label.to_string()];
            header.extend(g.columns.iter().cloned());
            writeln!(w, "{}", header.join(",")).context(|| format!("cannot write {}", path.display()))?;
            files.push((w, path));
        }
        self.stream = Some(Stream {
            x_label: s.x_label.to_string(),
            groups: s.groups.to_vec(),
            plots: s.plots,
            files,
            flushed: std::time::Instant::now(),
            x: Vec::new(),
            rows: vec![Vec::new(); s.groups.len()],
        });
        Ok(())
    }

    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        let Some(s) = &mut self.stream else {
            return crate::interrupt::check();
        };
        for (k, ((w, path), v)) in s.files.iter_mut().zip(values).enumerate() {
            // The cells as `output::num` writes them, straight into the buffer.
            let mut row = || -> std::io::Result<()> {
                write!(w, "{x:e}")?;
                for v in v {
                    write!(w, ",{v:e}")?;
                }
                writeln!(w)
            };
            row().context(|| format!("cannot write {}", path.display()))?;
            if s.plots {
                s.rows[k].push(v.clone());
            }
        }
        if s.plots {
            s.x.push(x);
        }
        if let Err(stop) = crate::interrupt::check() {
            // What was computed before the interruption is kept, this row included.
            s.flush()?;
            return Err(stop);
        }
        if s.flushed.elapsed() >= FLUSH_INTERVAL {
            s.flush()?;
        }
        Ok(())
    }

    /// A PNG per sensor: every column against the abscissa, on one axis when the columns
    /// share a unit and a size, else in panels ([`plot_panels`]).
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        let Some(mut s) = self.stream.take() else {
            return Ok(());
        };
        s.flush()?;
        if !s.plots || s.x.len() < 2 {
            return Ok(());
        }
        for (g, rows) in s.groups.iter().zip(&s.rows) {
            let columns: Vec<Vec<f64>> = (0..g.columns.len())
                .map(|k| rows.iter().map(|r| r[k]).collect())
                .collect();
            let panels = plot_panels(&g.columns, &columns);
            let figures: Vec<plot::Figure> = panels
                .iter()
                .map(|panel| {
                    let unit = column_unit(&g.columns[panel[0]]);
                    let (title, y_label) = if panels.len() == 1 {
                        (format!("sensor {}", g.name), format!("{} [{unit}]", g.name))
                    } else {
                        let names: Vec<&str> = panel.iter().map(|&k| column_name(&g.columns[k])).collect();
                        (names.join(", "), format!("[{unit}]"))
                    };
                    let mut fig = plot::Figure::new(title, &s.x_label, y_label);
                    for &k in panel {
                        fig.series.push(plot::Series::line(
                            g.columns[k].clone(),
                            s.x.clone(),
                            columns[k].clone(),
                        ));
                    }
                    fig
                })
                .collect();
            let path = self.path(&format!("{}.png", g.name))?;
            plot::write_panels_png(&format!("sensor {}", g.name), &figures, &path)
                .context(|| format!("cannot draw {}", path.display()))?;
        }
        Ok(())
    }

    fn frame(&mut self, series: Series, key: f64, mesh: &VtuMesh, fields: &[PointField<'_>]) -> Result<(), BoxError> {
        let (stem, digits, first, pvd) = series_names(series);
        let k = match self.series.iter().position(|(s, _)| *s == series) {
            Some(k) => k,
            None => {
                self.series.push((series, Vec::new()));
                self.series.len() - 1
            }
        };
        let index = self.series[k].1.len() + first;
        let name = if digits == 0 {
            format!("{stem}.vtu")
        } else {
            format!("{stem}{index:0digits$}.vtu")
        };
        crate::interrupt::check()?;
        let p = self.path(&name)?;
        write_vtu(&p, mesh, fields).context(|| format!("cannot write {}", p.display()))?;
        self.series[k].1.push((key, name));
        // The collection is rewritten after every frame, so an interrupted run keeps a
        // readable one; it is listed once.
        let path = self.dir.join(pvd);
        self.record(&format!("{}/{pvd}", self.prefix))?;
        write_pvd(&path, &self.series[k].1).context(|| format!("cannot write {}", path.display()))?;
        if self.series[k].1.len() == 1 {
            self.files.push(format!("{}/{pvd}", self.prefix));
        }
        Ok(())
    }

    fn file(&mut self, name: &str, path: &Path) -> Result<(), BoxError> {
        let target = self.path(name)?;
        std::fs::copy(path, &target)
            .map(|_| ())
            .context(|| format!("cannot copy {} to {}", path.display(), target.display()))
    }

    fn take_files(&mut self) -> Vec<String> {
        std::mem::take(&mut self.files)
    }

    fn summary(&mut self, s: &Summary) -> Result<(), BoxError> {
        self.record("summary.json")?;
        self.record("summary.md")?;
        s.write(&self.root)
            .context(|| format!("cannot write the summary into {}", self.root.display()))
    }
}

/// The unit of a column header `name [unit]` ("" without one).
fn column_unit(header: &str) -> &str {
    header
        .split_once('[')
        .map_or("", |(_, u)| u.trim_end_matches(']').trim())
}

/// The name of a column header `name [unit]`.
fn column_name(header: &str) -> &str {
    header.split_once('[').map_or(header, |(n, _)| n.trim())
}

/// The columns of a sensor grouped into plot panels: columns share a panel when they have
/// the same unit and sizes within a factor of 10 (largest |value|), so that a millimetre
/// deflection is not flattened beside a 10 m position and newtons are not drawn on an axis
/// of newton metres. Returns the column indices of each panel, in column order.
///
/// A column that is zero to round-off (below 1e-9 of the largest column of its unit, such as
/// the out-of-plane deflection of a planar motion) joins the panel of the smallest other
/// column of its unit instead of a panel of its own.
pub fn plot_panels(headers: &[String], columns: &[Vec<f64>]) -> Vec<Vec<usize>> {
    let size = |c: &[f64]| c.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let largest = |unit: &str| {
        headers
            .iter()
            .zip(columns)
            .filter(|(h, _)| column_unit(h) == unit)
            .fold(0.0f64, |m, (_, c)| m.max(size(c)))
    };
    let mut panels: Vec<(String, f64, Vec<usize>)> = Vec::new();
    let mut zeros = Vec::new();
    for (k, (h, c)) in headers.iter().zip(columns).enumerate() {
        let (unit, s) = (column_unit(h), size(c));
        if s <= 1e-9 * largest(unit) && s < largest(unit) {
            zeros.push((k, unit));
            continue;
        }
        let fits = |ps: f64| {
            let (lo, hi) = if s < ps { (s, ps) } else { (ps, s) };
            hi <= 10.0 * lo || hi == 0.0
        };
        match panels.iter_mut().find(|(u, ps, _)| u == unit && fits(*ps)) {
            Some((_, ps, members)) => {
                *ps = ps.max(s);
                members.push(k);
            }
            None => panels.push((unit.to_string(), s, vec![k])),
        }
    }
    for (k, unit) in zeros {
        let smallest = panels
            .iter_mut()
            .filter(|(u, _, _)| u == unit)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((_, _, members)) = smallest {
            members.push(k);
            members.sort_unstable();
        }
    }
    panels.into_iter().map(|(_, _, m)| m).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A results folder under the system's temporary folder, removed first.
    fn scratch(name: &str) -> PathBuf {
        let root = std::env::temp_dir().join(format!("flexmbs-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        root
    }

    fn rows_in(path: &Path) -> usize {
        std::fs::read_to_string(path).unwrap().lines().count() - 1
    }

    /// Rows are buffered between writes ([`FLUSH_INTERVAL`]): every row is in the file once
    /// the stream ends, and rows sampled after the interval has passed reach the file while
    /// the stream is still open.
    #[test]
    fn sensor_rows_reach_their_files_after_the_interval_and_at_the_end() {
        let root = scratch("flush");
        let mut folder = ResultsFolder::open(&root, &["run".to_string()], ForeignFiles::Refuse).unwrap();
        let info = AnalysisInfo {
            index: 0,
            count: 1,
            name: "run".into(),
            kind: "dynamic".into(),
            of: "the mechanism".into(),
        };
        folder.begin(&info).unwrap();
        let groups = vec![SensorGroup {
            name: "s".into(),
            mbs_names: vec!["s".into()],
            columns: vec!["s [m]".into()],
        }];
        folder
            .sensors(&SensorStream {
                x_label: "t [s]",
                groups: &groups,
                plots: false,
            })
            .unwrap();
        let file = root.join("run").join("s.csv");
        folder.sample(0.0, &[vec![1.0]]).unwrap();
        std::thread::sleep(FLUSH_INTERVAL + std::time::Duration::from_millis(50));
        folder.sample(1.0, &[vec![2.5e-3]]).unwrap();
        assert_eq!(
            rows_in(&file),
            2,
            "the rows up to the first one after the interval are written"
        );
        for k in 2..50 {
            folder.sample(k as f64, &[vec![-0.5]]).unwrap();
        }
        folder.sensors_end().unwrap();
        let text = std::fs::read_to_string(&file).unwrap();
        assert_eq!(text.lines().count(), 51, "{text}");
        assert_eq!(
            text.lines().nth(2),
            Some("1e0,2.5e-3"),
            "cells as output::num writes them"
        );
        assert_eq!(num(2.5e-3), "2.5e-3");
        drop(folder);
        let _ = std::fs::remove_dir_all(&root);
    }
}
