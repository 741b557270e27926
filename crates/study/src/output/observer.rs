//! The output observer: everything an analysis produces goes through [`Observer`] as plain
//! data, as soon as it is computed. The analyses (`crate::run`) never
//! write a file themselves.
//!
//! | observer | where | what it does with the results |
//! |---|---|---|
//! | [`ResultsFolder`](crate::output::folder::ResultsFolder) | this crate | CSV, VTU/PVD, PNG and `summary.json/.md` in a results folder |
//! | [`Recorder`] | this crate | keeps everything in vectors (tests, scripting) |
//! | the console of `flexmbs` | the program | progress bars and the report on stdout |
//!
//! Two observers run together as a pair `(a, b)`: each event goes to `a`, then to `b`.
//!
//! Events of one analysis, in order: [`Observer::begin`], then any number of tables, mesh
//! frames, files and one sensor stream ([`Observer::sensors`], [`Observer::sample`]...,
//! [`Observer::sensors_end`]), then [`Observer::end`]. [`Observer::summary`] follows every
//! analysis with the whole run so far.

use crate::error::BoxError;
use crate::output::summary::{AnalysisSummary, Summary};
use crate::output::vtu::{PointField, VtuMesh};
use std::path::Path;
use viewer::{Body, Frame, Marker};

/// One cell of a result table.
#[derive(Clone, Debug, PartialEq)]
pub enum Cell {
    Int(i64),
    Num(f64),
    Text(String),
    /// No value (a damping ratio of an undamped mode).
    Empty,
}

impl Cell {
    /// The number in the cell (an integer as `f64`), `None` for text and empty cells.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Cell::Int(i) => Some(*i as f64),
            Cell::Num(x) => Some(*x),
            Cell::Text(_) | Cell::Empty => None,
        }
    }
}

impl From<usize> for Cell {
    fn from(i: usize) -> Self {
        Cell::Int(i as i64)
    }
}

impl From<f64> for Cell {
    fn from(x: f64) -> Self {
        Cell::Num(x)
    }
}

impl From<String> for Cell {
    fn from(s: String) -> Self {
        Cell::Text(s)
    }
}

impl From<&str> for Cell {
    fn from(s: &str) -> Self {
        Cell::Text(s.to_string())
    }
}

/// A result table of one analysis: a name (`displacements`), column names with their units
/// (`"ux [m]"`) and rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    pub name: String,
    pub columns: Vec<String>,
    pub rows: Vec<Vec<Cell>>,
}

impl Table {
    pub fn new(name: &str, columns: &[&str]) -> Self {
        Self {
            name: name.to_string(),
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    pub fn row(&mut self, cells: Vec<Cell>) {
        debug_assert_eq!(cells.len(), self.columns.len());
        self.rows.push(cells);
    }

    /// Column `k` as numbers (`NaN` for text and empty cells).
    pub fn column(&self, k: usize) -> Vec<f64> {
        self.rows
            .iter()
            .map(|r| r.get(k).and_then(Cell::as_f64).unwrap_or(f64::NAN))
            .collect()
    }
}

pub use crate::sensor_group::SensorGroup;

/// The name and unit of a column label `"name [unit]"` (unit empty when there is none).
pub fn split_unit(column: &str) -> (&str, &str) {
    match column.rsplit_once(" [") {
        Some((name, unit)) => (name, unit.trim_end_matches(']')),
        None => (column, ""),
    }
}

/// The header of a sensor stream: the abscissa (`"t [s]"` or `"load factor [-]"`) and the
/// sensors; `plots` asks for a figure per sensor (study key `output.plots`).
#[derive(Clone, Copy, Debug)]
pub struct SensorStream<'a> {
    pub x_label: &'a str,
    pub groups: &'a [SensorGroup],
    pub plots: bool,
}

/// A sequence of meshes with point fields: static displacements, mode shapes, reduction
/// shapes, or the deformed mechanism over time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Series {
    /// The displacement of a static analysis (one frame, key 0).
    Static,
    /// Mass-normalised mode shapes, key = mode number.
    Modes,
    /// Craig-Bampton shapes of a reduction, key = shape number.
    Shapes,
    /// The deformed bodies of the mechanism, key = time or load factor.
    Mechanism,
}

/// The analysis an event belongs to.
#[derive(Clone, Debug)]
pub struct AnalysisInfo {
    /// 0-based position in the study and the number of analyses.
    pub index: usize,
    pub count: usize,
    pub name: String,
    /// `static`, `modal`, `reduce`, `equilibrium`, `dynamic`, `linearized`.
    pub kind: String,
    /// `part 'rod'` or `the mechanism`.
    pub of: String,
}

/// What a long computation is doing, for progress displays.
#[derive(Clone, Debug)]
pub enum Progress {
    /// A line of information ("reduced body found in the cache").
    Info(String),
    /// Something the user should know that does not stop the run.
    Warning(String),
    /// The stage of a computation without a known length ("factorising K_ii").
    Stage(String),
    /// `done` of `total` steps (time steps).
    Steps { what: String, done: u64, total: u64 },
    /// The computation reported by `Stage` or `Steps` is over.
    Finished,
}

/// Receives the results of a study run (module docs). Every method has a default that
/// ignores the event, so an observer implements only what it uses.
#[allow(unused_variables)]
pub trait Observer {
    /// An analysis starts.
    fn begin(&mut self, analysis: &AnalysisInfo) -> Result<(), BoxError> {
        Ok(())
    }
    /// Progress of a long computation.
    fn progress(&mut self, progress: &Progress) {}
    /// A complete result table.
    fn table(&mut self, table: &Table) -> Result<(), BoxError> {
        Ok(())
    }
    /// A sensor stream starts.
    fn sensors(&mut self, stream: &SensorStream<'_>) -> Result<(), BoxError> {
        Ok(())
    }
    /// One sample of every sensor of the stream: `values[g]` holds the columns of group `g`.
    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        Ok(())
    }
    /// The sensor stream is complete.
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        Ok(())
    }
    /// One frame of a mesh series.
    fn frame(&mut self, series: Series, key: f64, mesh: &VtuMesh, fields: &[PointField<'_>]) -> Result<(), BoxError> {
        Ok(())
    }
    /// The data of the results page (`crate::output::view`): bodies, poses, a part's fields.
    fn view(&mut self, event: &ViewEvent<'_>) {}
    /// A file the analysis produced (the reduced body `name` at `path`).
    fn file(&mut self, name: &str, path: &Path) -> Result<(), BoxError> {
        Ok(())
    }
    /// Files written for the current analysis, relative to the results folder (for the
    /// summary); taken once per analysis.
    fn take_files(&mut self) -> Vec<String> {
        Vec::new()
    }
    /// The analysis is over (done, or failed with `summary.error`).
    fn end(&mut self, analysis: &AnalysisInfo, summary: &AnalysisSummary) -> Result<(), BoxError> {
        Ok(())
    }
    /// The whole run so far, after every analysis.
    fn summary(&mut self, summary: &Summary) -> Result<(), BoxError> {
        Ok(())
    }
}

/// An observer that ignores everything.
impl Observer for () {}

/// Two observers: every event to the first, then to the second.
impl<A: Observer, B: Observer> Observer for (A, B) {
    fn begin(&mut self, a: &AnalysisInfo) -> Result<(), BoxError> {
        self.0.begin(a)?;
        self.1.begin(a)
    }
    fn progress(&mut self, p: &Progress) {
        self.0.progress(p);
        self.1.progress(p);
    }
    fn table(&mut self, t: &Table) -> Result<(), BoxError> {
        self.0.table(t)?;
        self.1.table(t)
    }
    fn sensors(&mut self, s: &SensorStream<'_>) -> Result<(), BoxError> {
        self.0.sensors(s)?;
        self.1.sensors(s)
    }
    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        self.0.sample(x, values)?;
        self.1.sample(x, values)
    }
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        self.0.sensors_end()?;
        self.1.sensors_end()
    }
    fn frame(&mut self, series: Series, key: f64, mesh: &VtuMesh, fields: &[PointField<'_>]) -> Result<(), BoxError> {
        self.0.frame(series, key, mesh, fields)?;
        self.1.frame(series, key, mesh, fields)
    }
    fn view(&mut self, e: &ViewEvent<'_>) {
        self.0.view(e);
        self.1.view(e);
    }
    fn file(&mut self, name: &str, path: &Path) -> Result<(), BoxError> {
        self.0.file(name, path)?;
        self.1.file(name, path)
    }
    fn take_files(&mut self) -> Vec<String> {
        let mut f = self.0.take_files();
        f.extend(self.1.take_files());
        f
    }
    fn end(&mut self, a: &AnalysisInfo, s: &AnalysisSummary) -> Result<(), BoxError> {
        self.0.end(a, s)?;
        self.1.end(a, s)
    }
    fn summary(&mut self, s: &Summary) -> Result<(), BoxError> {
        self.0.summary(s)?;
        self.1.summary(s)
    }
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn begin(&mut self, a: &AnalysisInfo) -> Result<(), BoxError> {
        (**self).begin(a)
    }
    fn progress(&mut self, p: &Progress) {
        (**self).progress(p)
    }
    fn table(&mut self, t: &Table) -> Result<(), BoxError> {
        (**self).table(t)
    }
    fn sensors(&mut self, s: &SensorStream<'_>) -> Result<(), BoxError> {
        (**self).sensors(s)
    }
    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        (**self).sample(x, values)
    }
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        (**self).sensors_end()
    }
    fn frame(&mut self, series: Series, key: f64, mesh: &VtuMesh, fields: &[PointField<'_>]) -> Result<(), BoxError> {
        (**self).frame(series, key, mesh, fields)
    }
    fn view(&mut self, e: &ViewEvent<'_>) {
        (**self).view(e)
    }
    fn file(&mut self, name: &str, path: &Path) -> Result<(), BoxError> {
        (**self).file(name, path)
    }
    fn take_files(&mut self) -> Vec<String> {
        (**self).take_files()
    }
    fn end(&mut self, a: &AnalysisInfo, s: &AnalysisSummary) -> Result<(), BoxError> {
        (**self).end(a, s)
    }
    fn summary(&mut self, s: &Summary) -> Result<(), BoxError> {
        (**self).summary(s)
    }
}

/// The sensor samples of one analysis, kept in memory.
#[derive(Clone, Debug, Default)]
pub struct SensorHistory {
    pub x_label: String,
    pub groups: Vec<SensorGroup>,
    pub x: Vec<f64>,
    /// `rows[g][k]`: the columns of group `g` at sample `k`.
    pub rows: Vec<Vec<Vec<f64>>>,
}

impl SensorHistory {
    /// Column `c` of sensor `name` over the samples.
    pub fn column(&self, name: &str, c: usize) -> Option<Vec<f64>> {
        let g = self.groups.iter().position(|g| g.name == name)?;
        self.rows[g].iter().map(|r| r.get(c).copied()).collect()
    }
}

/// What one analysis produced, as a [`Recorder`] keeps it.
#[derive(Clone, Debug, Default)]
pub struct Recorded {
    pub name: String,
    pub kind: String,
    pub tables: Vec<Table>,
    pub sensors: Option<SensorHistory>,
    /// Mesh frames: (series, key, number of points).
    pub frames: Vec<(Series, f64, usize)>,
    pub summary: Option<AnalysisSummary>,
}

/// An observer that keeps every table, sensor sample and frame key in vectors.
#[derive(Clone, Debug, Default)]
pub struct Recorder {
    pub analyses: Vec<Recorded>,
    pub progress: Vec<String>,
}

impl Recorder {
    fn current(&mut self) -> &mut Recorded {
        if self.analyses.is_empty() {
            self.analyses.push(Recorded::default());
        }
        let n = self.analyses.len();
        &mut self.analyses[n - 1]
    }

    /// The analysis called `name`.
    pub fn analysis(&self, name: &str) -> Option<&Recorded> {
        self.analyses.iter().find(|a| a.name == name)
    }
}

impl Observer for Recorder {
    fn begin(&mut self, a: &AnalysisInfo) -> Result<(), BoxError> {
        self.analyses.push(Recorded {
            name: a.name.clone(),
            kind: a.kind.clone(),
            ..Recorded::default()
        });
        Ok(())
    }
    fn progress(&mut self, p: &Progress) {
        match p {
            Progress::Info(s) | Progress::Warning(s) => self.progress.push(s.clone()),
            _ => {}
        }
    }
    fn table(&mut self, t: &Table) -> Result<(), BoxError> {
        self.current().tables.push(t.clone());
        Ok(())
    }
    fn sensors(&mut self, s: &SensorStream<'_>) -> Result<(), BoxError> {
        self.current().sensors = Some(SensorHistory {
            x_label: s.x_label.to_string(),
            groups: s.groups.to_vec(),
            x: Vec::new(),
            rows: vec![Vec::new(); s.groups.len()],
        });
        Ok(())
    }
    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        if let Some(h) = &mut self.current().sensors {
            h.x.push(x);
            for (g, v) in h.rows.iter_mut().zip(values) {
                g.push(v.clone());
            }
        }
        Ok(())
    }
    fn frame(&mut self, series: Series, key: f64, mesh: &VtuMesh, _fields: &[PointField<'_>]) -> Result<(), BoxError> {
        self.current().frames.push((series, key, mesh.points.len()));
        Ok(())
    }
    fn end(&mut self, _a: &AnalysisInfo, s: &AnalysisSummary) -> Result<(), BoxError> {
        self.current().summary = Some(s.clone());
        Ok(())
    }
}

/// What an analysis hands the page, besides its tables and sensors.
pub enum ViewEvent<'a> {
    /// The bodies and markers of a mechanism, before its first pose.
    Bodies { bodies: &'a [Body], markers: &'a [Marker] },
    /// The poses the modes of the analysis are about (a buckling analysis's loaded state).
    Base(&'a Frame),
    /// The poses of every body at `key` (a time, a load factor, a mode number) of `series`.
    Pose { series: Series, key: f64, frame: &'a Frame },
    /// A field of a part: six values a node (translation, rotation) on `mesh`, with the
    /// stress tensor (six components a node) when it has one; a static displacement, a mode
    /// or a reduction shape, key its number.
    PartField {
        series: Series,
        key: f64,
        mesh: &'a VtuMesh,
        /// The label of each mesh node in its file (empty when unknown).
        labels: &'a [u64],
        values: &'a [[f64; 6]],
        stress: Option<&'a [[f64; 6]]>,
    },
}
