//! The results folder as an [`Observer`]: tables as CSV, mesh frames as VTU files listed in a
//! PVD collection, sensor streams as CSV files written whenever [`FLUSH_INTERVAL`] has passed,
//! at an interruption and at their end (and a PNG per sensor at the end), reduced bodies
//! copied, and `summary.json`/`summary.md` rewritten after every analysis. Layout in
//! `crate::output`.
//!
//! # What a run owns, and what it never touches
//!
//! - **Manifest** (`.flexmbs-manifest`): every content a run writes is recorded there, as the
//!   length and SHA-256 of the bytes and the path relative to the results folder, *before*
//!   the bytes reach the file (so an interrupted run's files are known too); one line each,
//!   `sha256 length path`, the manifest read as a log (a name keeps every content recorded
//!   for it until the manifest is rewritten whole, at the start of a run and when it grows).
//!   A file is the run's own when its name is listed and its bytes are one of the contents
//!   recorded for it; a line with a path alone (a manifest of an older flexmbs) trusts the
//!   name. Anything else under a name a run writes is the user's: a file the user put in
//!   its place, a file in an analysis folder that was deleted and made again, a symbolic
//!   link, a folder.
//! - **Deleting**: only the run's own files, as just defined: at the start of an analysis,
//!   the files an earlier run wrote for it (stale plots included); at the start of the run,
//!   the files of analyses no longer in the study, and their folders when that empties them.
//! - **Foreign files**: the user's files where a run writes (in an analysis folder, or a
//!   `summary.json`/`summary.md`). The run refuses to start ([`ForeignFiles::Refuse`], the
//!   default) or writes beside them ([`ForeignFiles::Keep`], `--foreign-files keep`). Either
//!   way a user's file is never overwritten nor deleted: a run that would write under its
//!   name stops there with a message naming it (the summary says `failed` and why).
//! - **Symbolic links**: flexmbs creates none; an analysis folder or a file that is one is
//!   the user's, and nothing is written through it (the results folder itself may be one).
//! - **Whole files**: tables, meshes, plots, reduced bodies and the summary are written to a
//!   temporary name beside the file and renamed, so a file is complete or absent. Sensor
//!   rows are appended whole: a batch of rows goes to every sensor file, and when one write
//!   fails (a full disk) every file of the stream is cut back to its last whole row, so they
//!   end at the same row, and nothing more is appended. A file is listed in the summary once
//!   it is written.
//! - **Lock** (`.flexmbs-lock`): an operating-system lock on this file (`File::try_lock`)
//!   held for the whole run, with the process id written in it for the message: a second
//!   run stops with a message naming the process. The system releases the lock when the
//!   process ends, however it ends, so a killed run's folder is free at once; the file stays
//!   (deleting it would let a run waiting on the old file and a new one both lock).

use crate::error::{BoxError, ResultExt};
use crate::output::observer::{AnalysisInfo, Cell, Observer, SensorGroup, SensorStream, Series, Table};
use crate::output::summary::{num, Csv, Summary};
use crate::output::vtu::{pvd_text, vtu_text, PointField, VtuMesh};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Buffered sensor rows are written to their files at the first row after this much wall time
/// since the last write (and all of them when the stream ends or the run is interrupted): a
/// program reading the files during a run sees the rows with this delay. A flush per row is a
/// system call per sensor and step: with the five sensors of a slider-crank study, 5-10 % of
/// a mechanism step of about 100 µs (BENCHMARKS.md, the slider-crank C2 with a beam rod).
pub const FLUSH_INTERVAL: std::time::Duration = std::time::Duration::from_millis(200);

/// Buffered sensor rows are also written when one file has this many bytes waiting: the
/// memory a fast run holds stays bounded, and where a full disk cuts the files does not depend
/// on the machine's speed.
pub const FLUSH_BYTES: usize = 16 * 1024;

/// Where sensor rows are appended: a file, or in a test one that fails.
trait Sink: Write + Send {
    /// Cuts the file back to `len` bytes (its last whole row).
    fn truncate(&mut self, len: u64) -> std::io::Result<()>;
}

impl Sink for std::fs::File {
    fn truncate(&mut self, len: u64) -> std::io::Result<()> {
        self.set_len(len)
    }
}

/// One sensor's CSV file: the bytes on disk (`written`, hashed by `sha256`) and the rows
/// waiting for the next write (`pending`, whole rows only).
struct SensorFile {
    sink: Box<dyn Sink>,
    path: PathBuf,
    rel: String,
    written: u64,
    sha256: Sha256,
    pending: Vec<u8>,
}

/// A sensor stream being written: one CSV per sensor, and the values for the plots.
struct Stream {
    x_label: String,
    groups: Vec<SensorGroup>,
    plots: bool,
    files: Vec<SensorFile>,
    /// When the files were last flushed ([`FLUSH_INTERVAL`]).
    flushed: std::time::Instant,
    /// The abscissa of the row waiting last, and of the last row written.
    x_pending: Option<f64>,
    x_written: Option<f64>,
    /// The write that failed: nothing more is appended.
    failed: Option<String>,
    x: Vec<f64>,
    rows: Vec<Vec<Vec<f64>>>,
}

impl Stream {
    /// Appends the waiting rows of every file, recording each file's new content in the
    /// manifest first. A write that fails cuts every file back to its last whole row (they
    /// end at the same row), stops the stream and is the error, naming the file.
    fn flush(&mut self, manifest: &mut Manifest) -> Result<(), BoxError> {
        if let Some(e) = &self.failed {
            return Err(e.clone().into());
        }
        let mut hashes = Vec::with_capacity(self.files.len());
        for f in &self.files {
            let mut h = f.sha256.clone();
            h.update(&f.pending);
            let len = f.written + f.pending.len() as u64;
            if !f.pending.is_empty() {
                manifest.record(&f.rel, Content::of(len, h.clone()))?;
            }
            hashes.push(h);
        }
        for k in 0..self.files.len() {
            let f = &mut self.files[k];
            if f.pending.is_empty() {
                continue;
            }
            if let Err(e) = f.sink.write_all(&f.pending).and_then(|()| f.sink.flush()) {
                let message = self.cut_back(k, e);
                self.failed = Some(message.clone());
                return Err(message.into());
            }
        }
        for (f, h) in self.files.iter_mut().zip(hashes) {
            f.written += f.pending.len() as u64;
            f.sha256 = h;
            f.pending.clear();
        }
        self.x_written = self.x_pending.or(self.x_written);
        self.flushed = std::time::Instant::now();
        Ok(())
    }

    /// After the write of file `k` failed with `e`: every file cut back to its last whole
    /// row; the message names the file and the last row the files keep.
    fn cut_back(&mut self, k: usize, e: std::io::Error) -> String {
        let mut message = format!("cannot write {}: {e}", self.files[k].path.display());
        for f in &mut self.files {
            if let Err(e) = f.sink.truncate(f.written) {
                message.push_str(&format!(
                    "; and cannot cut {} back to its last whole row: {e}",
                    f.path.display()
                ));
            }
        }
        match self.x_written {
            Some(x) => message.push_str(&format!(
                "; the sensor files end at their last whole row, {} = {}",
                self.x_label,
                num(x)
            )),
            None => message.push_str("; the sensor files hold their header only"),
        }
        message
    }
}

/// Files in the folder that flexmbs did not write (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ForeignFiles {
    /// Refuse to write into a folder holding them (the default).
    #[default]
    Refuse,
    /// Write beside them; they are never overwritten nor deleted (a run that would write
    /// under the name of one stops there, naming it).
    Keep,
}

/// The manifest of the files flexmbs wrote into a results folder (module docs).
pub const MANIFEST: &str = ".flexmbs-manifest";
/// The lock file of a results folder (module docs).
pub const LOCK: &str = ".flexmbs-lock";
const MANIFEST_HEADER: &str = "# files written by flexmbs into this results folder (sha256, length, path); only these are ever deleted or replaced by it";

/// A content flexmbs wrote: its length and SHA-256 (hex).
#[derive(Clone, Debug, PartialEq, Eq)]
struct Content {
    len: u64,
    sha256: String,
}

impl Content {
    fn of(len: u64, h: Sha256) -> Self {
        Self {
            len,
            sha256: h.finalize().iter().map(|b| format!("{b:02x}")).collect(),
        }
    }

    fn of_bytes(bytes: &[u8]) -> Self {
        Self::of(bytes.len() as u64, Sha256::new_with_prefix(bytes))
    }

    /// The content of the file at `path`.
    fn of_file(path: &Path) -> std::io::Result<Self> {
        let mut h = Sha256::new();
        let len = std::io::copy(&mut std::fs::File::open(path)?, &mut h)?;
        Ok(Self::of(len, h))
    }
}

/// Whose a path of the results folder is (module docs).
enum Owner {
    Absent,
    /// flexmbs wrote it: its content now.
    Flexmbs(Content),
    /// The user's: why it is not flexmbs's.
    User(&'static str),
}

/// The manifest of a results folder (module docs).
struct Manifest {
    root: PathBuf,
    /// Every content recorded for each name, the latest last; empty: a line of an older
    /// manifest, the name alone.
    files: BTreeMap<String, Vec<Content>>,
    /// Lines appended since the manifest was written whole.
    appended: usize,
}

impl Manifest {
    /// The manifest of `root` (empty when there is none); refused when it is a symbolic link.
    fn load(root: &Path) -> Result<Self, BoxError> {
        let path = root.join(MANIFEST);
        if is_symlink(&path) {
            return Err(format!(
                "{} is a symbolic link, which flexmbs does not create: it is left alone; remove it, or write elsewhere with --out",
                path.display()
            )
            .into());
        }
        let mut files: BTreeMap<String, Vec<Content>> = BTreeMap::new();
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        // A last line without its newline was cut short (a full disk): ignored.
        let whole = text.rfind('\n').map_or("", |end| &text[..end]);
        for line in whole.lines().filter(|l| !l.trim().is_empty() && !l.starts_with('#')) {
            let (content, rel) = match line.splitn(3, ' ').collect::<Vec<_>>()[..] {
                [h, len, rel] if h.len() == 64 && h.bytes().all(|b| b.is_ascii_hexdigit()) => match len.parse() {
                    Ok(len) => (
                        Some(Content {
                            len,
                            sha256: h.to_string(),
                        }),
                        rel,
                    ),
                    Err(_) => continue,
                },
                _ => (None, line.trim()),
            };
            if rel.split('/').any(|c| c == ".." || c.is_empty()) {
                continue;
            }
            let entry = files.entry(rel.to_string()).or_default();
            entry.extend(content.filter(|c| !entry.contains(c)));
        }
        Ok(Self {
            root: root.to_path_buf(),
            files,
            appended: 0,
        })
    }

    /// Whose `rel` is now (module docs).
    fn owner(&self, rel: &str) -> Owner {
        let path = self.root.join(rel);
        // A folder on the way that is a symbolic link: nothing under it is the run's.
        let mut parent = self.root.clone();
        let parts: Vec<&str> = rel.split('/').collect();
        for p in &parts[..parts.len() - 1] {
            parent.push(p);
            if is_symlink(&parent) {
                return Owner::User("it is in a folder that is a symbolic link, which flexmbs does not create");
            }
        }
        let meta = match std::fs::symlink_metadata(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Owner::Absent,
            Err(_) => return Owner::User("it cannot be read"),
            Ok(m) => m,
        };
        if meta.file_type().is_symlink() {
            return Owner::User("it is a symbolic link, which flexmbs does not create");
        }
        if !meta.is_file() {
            return Owner::User("it is not a file");
        }
        let Some(recorded) = self.files.get(rel) else {
            return Owner::User("flexmbs did not write it (it is not in the manifest)");
        };
        let candidates = || recorded.iter().filter(|c| c.len == meta.len());
        if !recorded.is_empty() && candidates().next().is_none() {
            return Owner::User("its content is not what flexmbs wrote there");
        }
        match Content::of_file(&path) {
            Ok(now) if recorded.is_empty() || candidates().any(|c| *c == now) => Owner::Flexmbs(now),
            Ok(_) => Owner::User("its content is not what flexmbs wrote there"),
            Err(_) => Owner::User("it cannot be read"),
        }
    }

    /// Records `content` for `rel` (appended to the manifest file, which is rewritten whole
    /// first when it has grown long).
    fn record(&mut self, rel: &str, content: Content) -> Result<(), BoxError> {
        if self.appended > 2 * self.files.len() + 256 {
            self.rewrite()?;
        }
        let entry = self.files.entry(rel.to_string()).or_default();
        if entry.last() == Some(&content) {
            return Ok(());
        }
        entry.retain(|c| *c != content);
        let line = format!("{} {} {rel}\n", content.sha256, content.len);
        entry.push(content);
        let path = self.root.join(MANIFEST);
        let new = !path.exists();
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .context(|| format!("cannot write {}", path.display()))?;
        let text = if new {
            format!("{MANIFEST_HEADER}\n{line}")
        } else {
            line
        };
        f.write_all(text.as_bytes())
            .context(|| format!("cannot write {}", path.display()))?;
        self.appended += 1;
        Ok(())
    }

    /// Writes the manifest whole: the latest content of every name.
    fn rewrite(&mut self) -> Result<(), BoxError> {
        let mut text = format!("{MANIFEST_HEADER}\n");
        for (rel, contents) in &mut self.files {
            match contents.last() {
                Some(c) => {
                    text.push_str(&format!("{} {} {rel}\n", c.sha256, c.len));
                    contents.drain(..contents.len() - 1);
                }
                None => text.push_str(&format!("{rel}\n")),
            }
        }
        let path = self.root.join(MANIFEST);
        crate::output::summary::write_atomic(&path, text.as_bytes())
            .context(|| format!("cannot write {}", path.display()))?;
        self.appended = 0;
        Ok(())
    }

    /// Keeps only the names whose files are flexmbs's now, each with its content now (an
    /// older manifest's names get theirs), and writes the manifest whole.
    fn settle(&mut self) -> Result<(), BoxError> {
        let names: Vec<String> = self.files.keys().cloned().collect();
        for rel in names {
            match self.owner(&rel) {
                Owner::Flexmbs(now) => {
                    self.files.insert(rel, vec![now]);
                }
                Owner::Absent | Owner::User(_) => {
                    self.files.remove(&rel);
                }
            }
        }
        self.rewrite()
    }

    /// Deletes the files `rels` that are flexmbs's, and forgets all of them (a user's file
    /// under such a name is left as it is).
    fn forget(&mut self, rels: &[String]) -> Result<(), BoxError> {
        if rels.is_empty() {
            return Ok(());
        }
        for rel in rels {
            if let Owner::Flexmbs(_) = self.owner(rel) {
                let path = self.root.join(rel);
                match std::fs::remove_file(&path) {
                    Ok(()) => {}
                    Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                    Err(e) => return Err(Box::new(e)).context(|| format!("cannot delete {}", path.display())),
                }
            }
            self.files.remove(rel);
        }
        self.rewrite()
    }

    /// Files where a run of `analyses` writes that are not flexmbs's, after [`Self::settle`]:
    /// the summary files, analysis folders that are not folders, and anything in them that
    /// the manifest does not list.
    fn foreign(&self, analyses: &[String]) -> Vec<PathBuf> {
        let mut found = Vec::new();
        for name in ["summary.json", "summary.md", VIEW] {
            if let Owner::User(_) = self.owner(name) {
                found.push(self.root.join(name));
            }
        }
        for a in analyses {
            let dir = self.root.join(a);
            if is_symlink(&dir) || dir.exists() && !dir.is_dir() {
                found.push(dir);
                continue;
            }
            let Ok(entries) = std::fs::read_dir(&dir) else {
                continue;
            };
            for e in entries.flatten() {
                let name = e.file_name().to_string_lossy().to_string();
                let rel = format!("{a}/{name}");
                // A temporary of a run killed while it wrote (`summary::temporary_beside`)
                // is neither refused nor deleted.
                if is_temporary(&name) {
                    continue;
                }
                if !self.files.contains_key(&rel) || is_symlink(&e.path()) {
                    found.push(e.path());
                }
            }
        }
        found
    }
}

/// Whether `name` is a temporary name of `summary::temporary_beside`: `.<pid>-<n>.tmp.<name>`.
fn is_temporary(name: &str) -> bool {
    name.strip_prefix('.')
        .and_then(|rest| rest.split_once(".tmp."))
        .and_then(|(id, _)| id.split_once('-'))
        .is_some_and(|(pid, n)| {
            [pid, n]
                .iter()
                .all(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
        })
}

/// Whether `path` is a symbolic link (not followed).
fn is_symlink(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink())
}

/// Locks the results folder `root` for this process (module docs): the open lock file,
/// unlocked by the system when it is closed or the process ends.
fn lock_folder(root: &Path) -> Result<std::fs::File, BoxError> {
    let path = root.join(LOCK);
    if is_symlink(&path) {
        return Err(format!(
            "{} is a symbolic link, which flexmbs does not create: it is left alone; remove it, or write elsewhere with --out",
            path.display()
        )
        .into());
    }
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .context(|| format!("cannot lock the results folder {}", root.display()))?;
    match f.try_lock() {
        Ok(()) => {
            // The process id, for the message of a run that finds the folder locked.
            let _ = f.set_len(0).and_then(|()| writeln!(f, "{}", std::process::id()));
            Ok(f)
        }
        Err(std::fs::TryLockError::WouldBlock) => {
            let holder = std::fs::read_to_string(&path)
                .ok()
                .and_then(|t| t.trim().parse::<u32>().ok())
                .map_or(String::new(), |pid| format!(" (process {pid})"));
            Err(format!(
                "the results folder {} is in use by another flexmbs run{holder}, which holds the lock on {}: wait for it to finish or write elsewhere with --out",
                root.display(),
                path.display()
            )
            .into())
        }
        Err(std::fs::TryLockError::Error(e)) => Err(Box::new(e))
            .context(|| format!("cannot lock the results folder {} ({})", root.display(), path.display())),
    }
}

/// Writes a study's results into a folder (module docs).
pub struct ResultsFolder {
    root: PathBuf,
    manifest: Manifest,
    /// The locked lock file, unlocked when dropped.
    _lock: std::fs::File,
    /// The current analysis: its folder and name.
    dir: PathBuf,
    prefix: String,
    files: Vec<String>,
    /// PVD entries of the current analysis, per series.
    series: Vec<(Series, Vec<(f64, String)>)>,
    stream: Option<Stream>,
    /// The data of the results page, over the run.
    view: crate::output::view::SceneBuilder,
}

/// The results page of a results folder (`crate::output::view`): the analyses that have
/// something to show, with three.js inlined; its data are read back from it to write it again
/// ([`rewrite_view`]).
pub const VIEW: &str = "view.html";

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
        let lock = lock_folder(root)?;
        let mut manifest = Manifest::load(root)?;
        manifest.settle()?;
        if foreign == ForeignFiles::Refuse {
            let found = manifest.foreign(analyses);
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
            view: Default::default(),
        };
        // Analyses removed from the study: their files go, and their folders if that empties them.
        let current: std::collections::BTreeSet<&str> = analyses.iter().map(String::as_str).collect();
        let stale: Vec<String> = folder
            .manifest
            .files
            .keys()
            .filter(|f| f.split_once('/').is_some_and(|(a, _)| !current.contains(a)))
            .cloned()
            .collect();
        folder.manifest.forget(&stale)?;
        // The page's analyses that this run does not run again stay on it.
        if let Owner::Flexmbs(_) = folder.manifest.owner(VIEW) {
            if let Some(earlier) = std::fs::read_to_string(root.join(VIEW))
                .ok()
                .and_then(|html| viewer::data_of_page(&html).ok())
            {
                folder.view.keep(earlier, analyses);
            }
        }
        for dir in stale
            .iter()
            .filter_map(|f| f.split_once('/').map(|(a, _)| a))
            .collect::<std::collections::BTreeSet<_>>()
        {
            if !is_symlink(&root.join(dir)) {
                let _ = std::fs::remove_dir(root.join(dir));
            }
        }
        Ok(folder)
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The path of `rel` (relative to the results folder), refused when a user's file is
    /// there (module docs).
    fn claim(&self, rel: &str) -> Result<PathBuf, BoxError> {
        let path = self.root.join(rel);
        match self.manifest.owner(rel) {
            Owner::User(why) => Err(format!(
                "refusing to write {}: {why}; the file is left as it is: move it away, or write the results elsewhere with --out",
                path.display()
            )
            .into()),
            Owner::Absent | Owner::Flexmbs(_) => Ok(path),
        }
    }

    /// Writes `bytes` to `rel` whole (a temporary file and a rename), recorded in the
    /// manifest first.
    fn write_whole(&mut self, rel: &str, bytes: &[u8]) -> Result<(), BoxError> {
        let path = self.claim(rel)?;
        self.manifest.record(rel, Content::of_bytes(bytes))?;
        crate::output::summary::write_atomic(&path, bytes).context(|| format!("cannot write {}", path.display()))
    }

    /// Writes `bytes` to the file `name` of the current analysis ([`Self::write_whole`]) and
    /// lists it for the summary once it is written.
    fn put(&mut self, name: &str, bytes: &[u8]) -> Result<(), BoxError> {
        let rel = format!("{}/{name}", self.prefix);
        self.write_whole(&rel, bytes)?;
        self.files.push(rel);
        Ok(())
    }
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
        self.view.begin(&a.name, &a.kind);
        // Nothing is written, nor deleted, through an analysis folder that is not a folder.
        match std::fs::symlink_metadata(&self.dir) {
            Ok(m) if m.file_type().is_symlink() => {
                return Err(format!(
                    "refusing to write into {}: it is a symbolic link, which flexmbs does not create; it is left as it is: remove it, or write the results elsewhere with --out",
                    self.dir.display()
                )
                .into())
            }
            Ok(m) if !m.is_dir() => {
                return Err(format!(
                    "refusing to write into {}: it is not a folder; it is left as it is: move it away, or write the results elsewhere with --out",
                    self.dir.display()
                )
                .into())
            }
            _ => {}
        }
        // The files an earlier run wrote for this analysis (stale plots included), and only those.
        let prefix = format!("{}/", a.name);
        let old: Vec<String> = self
            .manifest
            .files
            .keys()
            .filter(|f| f.starts_with(&prefix))
            .cloned()
            .collect();
        self.manifest.forget(&old)?;
        crate::interrupt::check()?;
        match std::fs::create_dir(&self.dir) {
            Err(e) if e.kind() != std::io::ErrorKind::AlreadyExists => {
                Err(Box::new(e)).context(|| format!("cannot create the results folder {}", self.dir.display()))
            }
            _ => Ok(()),
        }
    }

    fn table(&mut self, t: &Table) -> Result<(), BoxError> {
        self.view.table(t);
        let header: Vec<&str> = t.columns.iter().map(String::as_str).collect();
        let mut csv = Csv::new(&header);
        for r in &t.rows {
            csv.row(&r.iter().map(cell_text).collect::<Vec<_>>());
        }
        self.put(&format!("{}.csv", t.name), csv.text().as_bytes())
    }

    fn sensors(&mut self, s: &SensorStream<'_>) -> Result<(), BoxError> {
        self.view.sensors(s.x_label, s.groups);
        let mut stream = Stream {
            x_label: s.x_label.to_string(),
            groups: s.groups.to_vec(),
            plots: s.plots,
            files: Vec::new(),
            flushed: std::time::Instant::now(),
            x_pending: None,
            x_written: None,
            failed: None,
            x: Vec::new(),
            rows: vec![Vec::new(); s.groups.len()],
        };
        let rels: Vec<String> = s
            .groups
            .iter()
            .map(|g| format!("{}/{}.csv", self.prefix, g.name))
            .collect();
        let paths = rels.iter().map(|rel| self.claim(rel)).collect::<Result<Vec<_>, _>>()?;
        for ((g, rel), path) in s.groups.iter().zip(rels).zip(paths) {
            if let Owner::Flexmbs(_) = self.manifest.owner(&rel) {
                self.manifest.forget(std::slice::from_ref(&rel))?;
            }
            // Recorded empty first: a file created and then not written is still the run's.
            self.manifest.record(&rel, Content::of_bytes(b""))?;
            // A new file: never one that appeared meanwhile, never through a symbolic link.
            let file = std::fs::OpenOptions::new()
                .append(true)
                .create_new(true)
                .open(&path)
                .context(|| format!("cannot create {}", path.display()))?;
            let mut header = vec![s.x_label.to_string()];
            header.extend(g.columns.iter().cloned());
            stream.files.push(SensorFile {
                sink: Box::new(file),
                path,
                rel,
                written: 0,
                sha256: Sha256::new(),
                pending: format!("{}\n", header.join(",")).into_bytes(),
            });
        }
        stream.flush(&mut self.manifest)?;
        self.files.extend(stream.files.iter().map(|f| f.rel.clone()));
        self.stream = Some(stream);
        Ok(())
    }

    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        if self.stream.as_ref().is_some_and(|s| s.failed.is_none()) {
            self.view.sample(x, values);
        }
        let Some(s) = &mut self.stream else {
            return crate::interrupt::check();
        };
        if let Some(e) = &s.failed {
            return Err(e.clone().into());
        }
        for (k, (f, v)) in s.files.iter_mut().zip(values).enumerate() {
            // The cells as `output::num` writes them, a whole row into the waiting bytes.
            let mut row = format!("{x:e}");
            for v in v {
                row.push_str(&format!(",{v:e}"));
            }
            row.push('\n');
            f.pending.extend_from_slice(row.as_bytes());
            if s.plots {
                s.rows[k].push(v.clone());
            }
        }
        s.x_pending = Some(x);
        if s.plots {
            s.x.push(x);
        }
        if let Err(stop) = crate::interrupt::check() {
            // What was computed before the interruption is kept, this row included.
            s.flush(&mut self.manifest)?;
            return Err(stop);
        }
        let waiting = s.files.iter().map(|f| f.pending.len()).max().unwrap_or(0);
        if waiting >= FLUSH_BYTES || s.flushed.elapsed() >= FLUSH_INTERVAL {
            s.flush(&mut self.manifest)?;
        }
        Ok(())
    }

    /// A PNG per sensor: every column against the abscissa, on one axis when the columns
    /// share a unit and a size, else in panels ([`plot_panels`]).
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        self.view.finish_sensors();
        let Some(mut s) = self.stream.take() else {
            return Ok(());
        };
        s.flush(&mut self.manifest)?;
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
            let name = format!("{}.png", g.name);
            // Drawn into a temporary file of its own, then written whole as every file is.
            let tmp = crate::output::summary::temporary_beside(&self.dir.join(&name));
            let drawn = plot::write_panels_png(&format!("sensor {}", g.name), &figures, &tmp)
                .map_err(BoxError::from)
                .and_then(|()| std::fs::read(&tmp).map_err(BoxError::from));
            let _ = std::fs::remove_file(&tmp);
            let bytes = drawn.context(|| format!("cannot draw {}", self.dir.join(&name).display()))?;
            self.put(&name, &bytes)?;
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
        self.put(&name, vtu_text(mesh, fields).as_bytes())?;
        self.series[k].1.push((key, name));
        // The collection is rewritten after every frame, so an interrupted run keeps a
        // readable one; it is listed once.
        let rel = format!("{}/{pvd}", self.prefix);
        self.write_whole(&rel, pvd_text(&self.series[k].1).as_bytes())?;
        if self.series[k].1.len() == 1 {
            self.files.push(rel);
        }
        Ok(())
    }

    fn view(&mut self, event: &crate::output::view::ViewEvent<'_>) {
        self.view.event(event);
    }

    fn file(&mut self, name: &str, path: &Path) -> Result<(), BoxError> {
        let bytes = std::fs::read(path).context(|| format!("cannot read {}", path.display()))?;
        self.put(name, &bytes)
    }

    fn take_files(&mut self) -> Vec<String> {
        std::mem::take(&mut self.files)
    }

    fn summary(&mut self, s: &Summary) -> Result<(), BoxError> {
        // Both or neither: a user's summary.md refuses before summary.json changes.
        self.claim("summary.json")?;
        self.claim("summary.md")?;
        self.write_whole("summary.json", s.json().as_bytes())?;
        self.write_whole("summary.md", s.markdown().as_bytes())?;
        // The page after the summary: a user's view.html stops the run with the summaries
        // written. A page that cannot be written (a full disk) does not stop the analyses,
        // whose files are the results: the run goes on without it (the program says where the
        // page is only when it exists).
        self.view.scene.title = s.title.clone().unwrap_or_else(|| s.study.clone());
        self.claim(VIEW)?;
        let page = viewer::page(&self.view.scene());
        let _ = self.write_whole(VIEW, page.as_bytes());
        Ok(())
    }
}

/// Writes the results page of the results folder `root` again from the data it holds, with
/// this version of the viewer; returns its path. The folder is locked meanwhile, and a page
/// that flexmbs did not write is refused (module docs).
pub fn rewrite_view(root: &Path) -> Result<PathBuf, BoxError> {
    let path = root.join(VIEW);
    if !path.is_file() {
        return Err(format!(
            "{} not found: {} is not a results folder of `flexmbs run`, or one written before the results page existed: run the study again",
            path.display(),
            root.display()
        )
        .into());
    }
    let _lock = lock_folder(root)?;
    let mut manifest = Manifest::load(root)?;
    if let Owner::User(why) = manifest.owner(VIEW) {
        return Err(format!("refusing to rewrite {}: {why}; it is left as it is", path.display()).into());
    }
    let html = std::fs::read_to_string(&path).context(|| format!("cannot read {}", path.display()))?;
    let scene = viewer::data_of_page(&html).map_err(|e| format!("{}: {e}", path.display()))?;
    let page = viewer::page(&scene);
    if page != html {
        manifest.record(VIEW, Content::of_bytes(page.as_bytes()))?;
        crate::output::summary::write_atomic(&path, page.as_bytes())
            .context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(path)
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

    /// A results folder at `root` in which the one dynamic analysis "run" has begun.
    fn dynamic_run_folder(root: &Path) -> ResultsFolder {
        let mut folder = ResultsFolder::open(root, &["run".to_string()], ForeignFiles::Refuse).unwrap();
        let info = AnalysisInfo {
            index: 0,
            count: 1,
            name: "run".into(),
            kind: "dynamic".into(),
            of: "the mechanism".into(),
        };
        folder.begin(&info).unwrap();
        folder
    }

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
        let mut folder = dynamic_run_folder(&root);
        let groups = vec![SensorGroup {
            name: "s".into(),
            mbs_names: vec!["s".into()],
            columns: vec!["s [m]".into()],
            node_labels: None,
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

    /// A file that takes `budget` more bytes and then fails, having written part of the
    /// bytes it was given: a disk that fills mid-row.
    struct FullDisk {
        file: std::fs::File,
        budget: usize,
    }

    impl Write for FullDisk {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            if self.budget == 0 {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::StorageFull,
                    "no space left on device",
                ));
            }
            let n = self.file.write(&buf[..buf.len().min(self.budget)])?;
            self.budget -= n;
            Ok(n)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.file.flush()
        }
    }

    impl Sink for FullDisk {
        fn truncate(&mut self, len: u64) -> std::io::Result<()> {
            self.file.set_len(len)
        }
    }

    /// A write that fails mid-row (the energy file's disk fills after a few rows): every
    /// sensor file is cut back to the same last whole row, each cell reads back exactly
    /// (no `6.5` where 6.57 was written), nothing more is appended, the error names the file
    /// and the last row kept, the files listed exist, and the next run finds the files its
    /// own (their contents are the ones recorded).
    #[test]
    fn a_failed_sensor_write_leaves_whole_rows_of_one_length() {
        let root = scratch("full-disk");
        let mut folder = dynamic_run_folder(&root);
        let group = |name: &str, columns: &[&str]| SensorGroup {
            name: name.into(),
            mbs_names: vec![name.into()],
            columns: columns.iter().map(|c| c.to_string()).collect(),
            node_labels: None,
        };
        let groups = vec![
            group("angle", &["angle [rad]"]),
            group("energy", &["kinetic [J]", "potential [J]"]),
        ];
        let stream = SensorStream {
            x_label: "t [s]",
            groups: &groups,
            plots: false,
        };
        folder.sensors(&stream).unwrap();
        let row = |k: usize| {
            (
                k as f64 * 1e-3,
                vec![vec![6.57 * k as f64], vec![6.57, -6.57e-3 * k as f64]],
            )
        };
        let (x, v) = row(1);
        folder.sample(x, &v).unwrap();
        folder.stream.as_mut().unwrap().flush(&mut folder.manifest).unwrap();
        // The energy file's disk fills 70 bytes on: inside the third row after the first.
        let energy = root.join("run/energy.csv");
        let file = std::fs::OpenOptions::new().append(true).open(&energy).unwrap();
        folder.stream.as_mut().unwrap().files[1].sink = Box::new(FullDisk { file, budget: 70 });
        for k in 2..12 {
            let (x, v) = row(k);
            folder.sample(x, &v).unwrap();
        }
        let stream = folder.stream.as_mut().unwrap();
        let e = stream.flush(&mut folder.manifest).unwrap_err().to_string();
        assert!(e.contains(&energy.display().to_string()), "{e}");
        assert!(
            e.contains("no space left") && e.contains("last whole row, t [s] = 1e-3"),
            "{e}"
        );
        let read = |name: &str| -> Vec<Vec<f64>> {
            let text = std::fs::read_to_string(root.join("run").join(name)).unwrap();
            assert!(text.ends_with('\n'), "{name}: a cut row: {text:?}");
            text.lines()
                .skip(1)
                .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
                .collect()
        };
        let (angle, energies) = (read("angle.csv"), read("energy.csv"));
        assert_eq!(angle.len(), 1, "{angle:?}");
        assert_eq!(energies.len(), 1, "{energies:?}");
        let (x, v) = row(1);
        assert_eq!(angle[0], [x, v[0][0]]);
        assert_eq!(energies[0], [x, v[1][0], v[1][1]]);
        // Stopped: nothing more is appended.
        let (x, v) = row(12);
        assert!(folder.sample(x, &v).is_err());
        assert!(folder.sensors_end().is_err());
        let files = folder.take_files();
        assert_eq!(files, ["run/angle.csv", "run/energy.csv"]);
        assert!(files.iter().all(|f| root.join(f).is_file()));
        drop(folder);
        // The files are the run's own: a new run refuses nothing and replaces them.
        let again = dynamic_run_folder(&root);
        assert!(!energy.exists());
        drop(again);
        let _ = std::fs::remove_dir_all(&root);
    }
}
