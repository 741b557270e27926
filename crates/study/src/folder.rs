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

    /// A PNG per sensor: every column against the abscissa, on one axis when the columns
    /// share a unit and a size, else in panels ([`plot_panels`]).
    fn sensors_end(&mut self) -> Result<(), BoxError> {
        let Some(s) = self.stream.take() else {
            return Ok(());
        };
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
            let path = self.path(&format!("{}.png", g.name));
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
