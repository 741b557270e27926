//! The results folder as an [`Observer`]: tables as CSV, mesh frames as VTU files listed in a
//! PVD collection, sensor streams as CSV files flushed after every row (and a PNG per sensor
//! at the end), reduced bodies copied, and `summary.json`/`summary.md` rewritten after every
//! analysis. Layout in `crate::output`.

use crate::error::{BoxError, ResultExt};
use crate::observer::{AnalysisInfo, Cell, Observer, SensorGroup, SensorStream, Series, Table};
use crate::output::{num, prepare_analysis_dir, Csv, Summary};
use crate::vtu::{write_pvd, write_vtu, PointField, VtuMesh};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A sensor stream being written: one CSV per sensor, and the values for the plots.
struct Stream {
    x_label: String,
    groups: Vec<SensorGroup>,
    plots: bool,
    files: Vec<std::io::BufWriter<std::fs::File>>,
    x: Vec<f64>,
    rows: Vec<Vec<Vec<f64>>>,
}

/// Writes a study's results into a folder (module docs).
pub struct ResultsFolder {
    root: PathBuf,
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
    /// A results folder at `root`, created now.
    pub fn new(root: &Path) -> Result<Self, BoxError> {
        std::fs::create_dir_all(root).context(|| format!("cannot create the results folder {}", root.display()))?;
        Ok(Self {
            root: root.to_path_buf(),
            dir: root.to_path_buf(),
            prefix: String::new(),
            files: Vec::new(),
            series: Vec::new(),
            stream: None,
        })
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The path of `name` in the current analysis folder, listed for the summary.
    fn path(&mut self, name: &str) -> PathBuf {
        self.files.push(format!("{}/{name}", self.prefix));
        self.dir.join(name)
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
        prepare_analysis_dir(&self.dir).context(|| format!("cannot prepare the results folder {}", self.dir.display()))
    }

    fn table(&mut self, t: &Table) -> Result<(), BoxError> {
        let header: Vec<&str> = t.columns.iter().map(String::as_str).collect();
        let mut csv = Csv::new(&header);
        for r in &t.rows {
            csv.row(&r.iter().map(cell_text).collect::<Vec<_>>());
        }
        let p = self.path(&format!("{}.csv", t.name));
        csv.write(&p).context(|| format!("cannot write {}", p.display()))
    }

    fn sensors(&mut self, s: &SensorStream<'_>) -> Result<(), BoxError> {
        let mut files = Vec::new();
        for g in s.groups {
            let path = self.path(&format!("{}.csv", g.name));
            let f = std::fs::File::create(&path).context(|| format!("cannot create {}", path.display()))?;
            let mut w = std::io::BufWriter::new(f);
            let mut header = vec![s.x_label.to_string()];
            header.extend(g.columns.iter().cloned());
            writeln!(w, "{}", header.join(",")).context(|| format!("cannot write {}", path.display()))?;
            files.push(w);
        }
        self.stream = Some(Stream {
            x_label: s.x_label.to_string(),
            groups: s.groups.to_vec(),
            plots: s.plots,
            files,
            x: Vec::new(),
            rows: vec![Vec::new(); s.groups.len()],
        });
        Ok(())
    }

    fn sample(&mut self, x: f64, values: &[Vec<f64>]) -> Result<(), BoxError> {
        let Some(s) = &mut self.stream else {
            return Ok(());
        };
        for (k, (w, v)) in s.files.iter_mut().zip(values).enumerate() {
            let mut line = num(x);
            for v in v {
                line.push(',');
                line.push_str(&num(*v));
            }
            writeln!(w, "{line}")
                .and_then(|_| w.flush())
                .context(|| "cannot write a sensor file".to_string())?;
            if s.plots {
                s.rows[k].push(v.clone());
            }
        }
        if s.plots {
            s.x.push(x);
        }
        Ok(())
    }

    /// A PNG per sensor: every column against the abscissa.
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        let Some(s) = self.stream.take() else {
            return Ok(());
        };
        if !s.plots || s.x.len() < 2 {
            return Ok(());
        }
        for (g, rows) in s.groups.iter().zip(&s.rows) {
            let unit = g
                .columns
                .first()
                .and_then(|c| c.split_once('['))
                .map(|(_, u)| u.trim_end_matches(']').to_string())
                .unwrap_or_default();
            let mut fig = plot::Figure::new(format!("sensor {}", g.name), &s.x_label, format!("{} [{unit}]", g.name));
            for (k, c) in g.columns.iter().enumerate() {
                fig.series.push(plot::Series::line(
                    c.clone(),
                    s.x.clone(),
                    rows.iter().map(|r| r[k]).collect(),
                ));
            }
            let path = self.path(&format!("{}.png", g.name));
            plot::write_png(&fig, &path).context(|| format!("cannot draw {}", path.display()))?;
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
        let p = self.path(&name);
        write_vtu(&p, mesh, fields).context(|| format!("cannot write {}", p.display()))?;
        self.series[k].1.push((key, name));
        // The collection is rewritten after every frame, so an interrupted run keeps a
        // readable one; it is listed once.
        let path = self.dir.join(pvd);
        write_pvd(&path, &self.series[k].1).context(|| format!("cannot write {}", path.display()))?;
        if self.series[k].1.len() == 1 {
            self.files.push(format!("{}/{pvd}", self.prefix));
        }
        Ok(())
    }

    fn file(&mut self, name: &str, path: &Path) -> Result<(), BoxError> {
        let target = self.path(name);
        std::fs::copy(path, &target)
            .map(|_| ())
            .context(|| format!("cannot copy {} to {}", path.display(), target.display()))
    }

    fn take_files(&mut self) -> Vec<String> {
        std::mem::take(&mut self.files)
    }

    fn summary(&mut self, s: &Summary) -> Result<(), BoxError> {
        s.write(&self.root)
            .context(|| format!("cannot write the summary into {}", self.root.display()))
    }
}
