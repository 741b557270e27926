//! # plot: PNG line plots for results and the validation report
//!
//! Plain data in, a PNG file out: a [`Figure`] holds a title, axis labels, a linear or
//! logarithmic scale per axis and a list of [`Series`] (label, x, y, drawn as a line, as
//! markers, or both); [`write_png`] draws it with a legend. Time histories use linear axes;
//! convergence studies use log-log axes, where a rate is a straight line.
//!
//! Drawing is pure Rust (plotters' bitmap backend into an RGB buffer, ab_glyph text, the `png`
//! crate's encoder) with DejaVu Sans embedded in the crate (`fonts/DejaVuSans.ttf`, licence in
//! `fonts/DejaVuSans-LICENSE.txt`), so a machine without fonts or C libraries draws the same
//! picture.
//!
//! ```no_run
//! use plot::{write_png, Figure, Series};
//! let h = vec![0.1, 0.05, 0.025];
//! let e: Vec<f64> = h.iter().map(|h| 3.0 * h * h).collect();
//! let mut fig = Figure::new("error against element size", "h [m]", "relative error");
//! fig.x_log = true;
//! fig.y_log = true;
//! fig.series.push(Series::line_markers("tip deflection", h, e));
//! write_png(&fig, std::path::Path::new("convergence.png")).unwrap();
//! ```

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// Width of every PNG, in pixels.
pub const WIDTH: u32 = 960;
/// Height of every PNG, in pixels.
pub const HEIGHT: u32 = 640;

/// The family name the embedded font is registered under; plotters' default text style
/// asks for "sans-serif", so every label of the chart uses it.
const FONT_FAMILY: &str = "sans-serif";
static DEJAVU_SANS: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A polyline through the points, in order.
    Line,
    /// A marker at each point, no line (reference values, sparse samples).
    Markers,
    /// Both (convergence studies: the levels are the points).
    LineMarkers,
}

/// One curve: `y[i]` against `x[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend entry; an empty label leaves the series out of the legend.
    pub label: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub style: Style,
}

impl Series {
    pub fn new(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>, style: Style) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            style,
        }
    }
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, Style::Line)
    }
    pub fn markers(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, Style::Markers)
    }
    pub fn line_markers(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self::new(label, x, y, Style::LineMarkers)
    }
}

/// A chart: title, axes and the series drawn on them.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Logarithmic x axis (every x must then be positive).
    pub x_log: bool,
    /// Logarithmic y axis (every y must then be positive).
    pub y_log: bool,
    pub series: Vec<Series>,
}

impl Figure {
    /// A figure with linear axes and no series yet.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>, y_label: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            x_log: false,
            y_log: false,
            series: Vec::new(),
        }
    }
}

/// Which axis a value belongs to, for error messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
}

impl std::fmt::Display for Axis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Axis::X => "x",
            Axis::Y => "y",
        })
    }
}

/// Why a figure could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The figure has no series with at least one point: there is nothing to scale the axes on.
    #[error("figure '{title}': no series has a point to draw")]
    Empty { title: String },
    /// `x` and `y` of a series differ in length.
    #[error("figure '{title}', series '{series}': x has {x_len} values but y has {y_len}")]
    LengthMismatch {
        title: String,
        series: String,
        x_len: usize,
        y_len: usize,
    },
    /// A value is NaN or infinite: it has no place on a chart and usually means a failed run.
    #[error("figure '{title}', series '{series}': {axis}[{index}] = {value} is not finite")]
    NotFinite {
        title: String,
        series: String,
        axis: Axis,
        index: usize,
        value: f64,
    },
    /// A value on a logarithmic axis is zero or negative.
    #[error("figure '{title}', series '{series}': {axis}[{index}] = {value} is not positive, but the {axis} axis is logarithmic")]
    NotPositiveOnLogAxis {
        title: String,
        series: String,
        axis: Axis,
        index: usize,
        value: f64,
    },
    /// The embedded font did not parse (a corrupted build).
    #[error("the embedded DejaVu Sans font could not be loaded")]
    Font,
    /// Drawing or encoding failed, or the file could not be written (missing directory,
    /// no permission).
    #[error("cannot write plot '{title}' to {path}: {message}")]
    Write {
        title: String,
        path: PathBuf,
        message: String,
    },
}

/// Registers the embedded font once per process; plotters keeps fonts in a global table.
fn register_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok =
        *REGISTERED.get_or_init(|| plotters::style::register_font(FONT_FAMILY, FontStyle::Normal, DEJAVU_SANS).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

/// Draws `figure` into a `WIDTH` x `HEIGHT` PNG at `path` (overwritten if present).
///
/// The axes span the data with a margin; a logarithmic axis spans whole or part decades
/// around the data. Series are coloured in order from a ten-colour palette and listed in a
/// legend at the upper right when any has a label.
pub fn write_png(figure: &Figure, path: &Path) -> Result<(), PlotError> {
    let (x_range, y_range) = data_ranges(figure)?;
    register_font()?;
    let write_error = |message: String| PlotError::Write {
        title: figure.title.clone(),
        path: path.to_path_buf(),
        message,
    };
    let mut pixels = rgb_buffer(WIDTH, HEIGHT);
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| write_error(e.to_string()))?;
        draw_figure(&root, figure, x_range, y_range, 0).map_err(write_error)?;
        root.present().map_err(|e| write_error(e.to_string()))?;
    }
    write_rgb_png(&pixels, WIDTH, HEIGHT, path).map_err(write_error)
}

/// A zeroed RGB buffer of `width` x `height` pixels for the backend
/// (the drawing fills it white first).
fn rgb_buffer(width: u32, height: u32) -> Vec<u8> {
    vec![0; 3 * width as usize * height as usize]
}

/// Encodes 8-bit RGB `pixels` as a PNG and writes it to `path`; an unwritable path is the
/// error. The settings are those of the `image` crate's PNG encoder (default compression,
/// adaptive filtering), which plotters' `bitmap_encoder` feature would use; the `png` crate
/// alone keeps `image` and its JPEG and BMP codecs out of the build (about 100 CPU-s of a
/// cold build).
fn write_rgb_png(pixels: &[u8], width: u32, height: u32, path: &Path) -> Result<(), String> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Default);
        encoder.set_filter(png::FilterType::Sub);
        encoder.set_adaptive_filter(png::AdaptiveFilterType::Adaptive);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(pixels).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())?;
    }
    std::fs::write(path, bytes).map_err(|e| e.to_string())
}

/// Height of one panel of [`write_panels_png`], in pixels.
pub const PANEL_HEIGHT: u32 = 300;

/// Draws `panels` one above the other into one PNG at `path`, each with its own y axis,
/// label and legend, all sharing the span of x: for a quantity whose components differ in
/// size or unit (a tip's 10 m position beside its millimetre deflection, a force beside a
/// moment), which one axis would flatten or mislabel. The PNG is `WIDTH` wide and
/// `PANEL_HEIGHT` per panel (at least `HEIGHT`); `title` heads the picture. One panel gives
/// the same picture as [`write_png`].
pub fn write_panels_png(title: &str, panels: &[Figure], path: &Path) -> Result<(), PlotError> {
    if panels.is_empty() {
        return Err(PlotError::Empty { title: title.into() });
    }
    if let [one] = panels {
        return write_png(one, path);
    }
    let mut ranges = Vec::with_capacity(panels.len());
    let mut x_all = (f64::INFINITY, f64::NEG_INFINITY);
    for p in panels {
        let (x, y) = data_ranges(p)?;
        x_all = (x_all.0.min(x.0), x_all.1.max(x.1));
        ranges.push(y);
    }
    register_font()?;
    let write_error = |message: String| PlotError::Write {
        title: title.into(),
        path: path.to_path_buf(),
        message,
    };
    let height = (PANEL_HEIGHT * panels.len() as u32 + 48).max(HEIGHT);
    let mut pixels = rgb_buffer(WIDTH, height);
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (WIDTH, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| write_error(e.to_string()))?;
        let body = root
            .titled(title, (FONT_FAMILY, 26))
            .map_err(|e| write_error(e.to_string()))?;
        // Colours continue from panel to panel, so each component keeps one colour throughout.
        let mut first_colour = 0;
        for (area, (panel, y_range)) in body
            .split_evenly((panels.len(), 1))
            .iter()
            .zip(panels.iter().zip(ranges))
        {
            draw_figure(area, panel, x_all, y_range, first_colour).map_err(write_error)?;
            first_colour += panel.series.len();
        }
        root.present().map_err(|e| write_error(e.to_string()))?;
    }
    write_rgb_png(&pixels, WIDTH, height, path).map_err(write_error)
}

/// Draws one figure on `root` with the given data ranges.
fn draw_figure(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    figure: &Figure,
    x_range: Interval,
    y_range: Interval,
    first_colour: usize,
) -> Result<(), String> {
    let x = axis_span(x_range, figure.x_log);
    let y = axis_span(y_range, figure.y_log);
    // The four scale combinations are four coordinate types in plotters: one generic body.
    // A tick within round-off of zero on a linear axis is labelled 0, not -2.22e-16.
    let zero = (1e-9 * (x.1 - x.0), 1e-9 * (y.1 - y.0));
    match (figure.x_log, figure.y_log) {
        (false, false) => draw_chart(root, figure, x.0..x.1, y.0..y.1, zero, first_colour),
        (true, false) => draw_chart(root, figure, (x.0..x.1).log_scale(), y.0..y.1, zero, first_colour),
        (false, true) => draw_chart(root, figure, x.0..x.1, (y.0..y.1).log_scale(), zero, first_colour),
        (true, true) => draw_chart(
            root,
            figure,
            (x.0..x.1).log_scale(),
            (y.0..y.1).log_scale(),
            zero,
            first_colour,
        ),
    }
}

/// (min, max) of the values on one axis.
type Interval = (f64, f64);

/// Checks every series and returns the data's (min, max) in x and in y.
fn data_ranges(figure: &Figure) -> Result<(Interval, Interval), PlotError> {
    let mut x_range = (f64::INFINITY, f64::NEG_INFINITY);
    let mut y_range = (f64::INFINITY, f64::NEG_INFINITY);
    for s in &figure.series {
        if s.x.len() != s.y.len() {
            return Err(PlotError::LengthMismatch {
                title: figure.title.clone(),
                series: s.label.clone(),
                x_len: s.x.len(),
                y_len: s.y.len(),
            });
        }
        for (axis, values, log, range) in [
            (Axis::X, &s.x, figure.x_log, &mut x_range),
            (Axis::Y, &s.y, figure.y_log, &mut y_range),
        ] {
            for (index, &value) in values.iter().enumerate() {
                if !value.is_finite() {
                    return Err(PlotError::NotFinite {
                        title: figure.title.clone(),
                        series: s.label.clone(),
                        axis,
                        index,
                        value,
                    });
                }
                if log && !(value > 0.0) {
                    return Err(PlotError::NotPositiveOnLogAxis {
                        title: figure.title.clone(),
                        series: s.label.clone(),
                        axis,
                        index,
                        value,
                    });
                }
                range.0 = range.0.min(value);
                range.1 = range.1.max(value);
            }
        }
    }
    if !(x_range.0 <= x_range.1) {
        return Err(PlotError::Empty {
            title: figure.title.clone(),
        });
    }
    Ok((x_range, y_range))
}

/// The drawn span of an axis: the data range with a 5 % margin (of the range, or of the
/// decades on a log axis), widened when all values are equal so the axis has a length.
fn axis_span((lo, hi): (f64, f64), log: bool) -> (f64, f64) {
    if log {
        let (l0, l1) = (lo.log10(), hi.log10());
        let pad = if l1 > l0 { 0.05 * (l1 - l0) } else { 0.5 };
        (10f64.powf(l0 - pad), 10f64.powf(l1 + pad))
    } else {
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else if lo != 0.0 {
            0.1 * lo.abs()
        } else {
            1.0
        };
        (lo - pad, hi + pad)
    }
}

/// Tick labels short enough for the axis: plain decimals in [1e-3, 1e5), else scientific;
/// `|v| <= zero` prints as 0.
fn tick_label(v: f64, zero: f64) -> String {
    let a = v.abs();
    if a <= zero {
        "0".to_string()
    } else if (1e-3..1e5).contains(&a) {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        let s = format!("{v:.2e}");
        // 1.00e-3 -> 1e-3, 2.50e4 -> 2.5e4
        match s.split_once('e') {
            Some((m, e)) => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            None => s,
        }
    }
}

/// Ten well-separated colours (matplotlib's "tab10").
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

fn draw_chart<XR, YR>(
    root: &DrawingArea<BitMapBackend<'_>, Shift>,
    figure: &Figure,
    x_spec: XR,
    y_spec: YR,
    (x_zero, y_zero): (f64, f64),
    first_colour: usize,
) -> Result<(), String>
where
    XR: AsRangedCoord<Value = f64>,
    YR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
    YR::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(root)
        .caption(&figure.title, (FONT_FAMILY, 26))
        .margin(16)
        .x_label_area_size(56)
        .y_label_area_size(88)
        .build_cartesian_2d(x_spec, y_spec)
        .map_err(|e| e.to_string())?;
    let x_fmt = |v: &f64| tick_label(*v, x_zero);
    let y_fmt = |v: &f64| tick_label(*v, y_zero);
    chart
        .configure_mesh()
        .x_desc(figure.x_label.as_str())
        .y_desc(figure.y_label.as_str())
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style((FONT_FAMILY, 16))
        .axis_desc_style((FONT_FAMILY, 18))
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(205, 205, 205))
        .draw()
        .map_err(|e| e.to_string())?;
    let mut any_label = false;
    for (i, s) in figure.series.iter().enumerate() {
        let colour = PALETTE[(first_colour + i) % PALETTE.len()];
        let points: Vec<(f64, f64)> = s.x.iter().copied().zip(s.y.iter().copied()).collect();
        let line_style = colour.stroke_width(2);
        let drawn = match s.style {
            Style::Line => chart.draw_series(LineSeries::new(points, line_style)),
            Style::Markers => chart.draw_series(points.into_iter().map(|p| Circle::new(p, 4, colour.filled()))),
            Style::LineMarkers => {
                chart
                    .draw_series(LineSeries::new(points.iter().copied(), line_style))
                    .map_err(|e| e.to_string())?;
                chart.draw_series(points.into_iter().map(|p| Circle::new(p, 4, colour.filled())))
            }
        }
        .map_err(|e| e.to_string())?;
        if !s.label.is_empty() {
            any_label = true;
            // One element type for every style: the part a style does not draw is transparent.
            let (line_alpha, marker_alpha) = match s.style {
                Style::Line => (1.0, 0.0),
                Style::Markers => (0.0, 1.0),
                Style::LineMarkers => (1.0, 1.0),
            };
            drawn.label(s.label.as_str()).legend(move |(x, y)| {
                EmptyElement::at((x, y))
                    + PathElement::new(vec![(0, 0), (24, 0)], colour.mix(line_alpha).stroke_width(2))
                    + Circle::new((12, 0), 4, colour.mix(marker_alpha).filled())
            });
        }
    }
    if any_label {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT_FAMILY, 16))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    Ok(())
}
