//! Tests of the plot crate: the PNG decodes with the expected size and has ink where the
//! title, the axes and the series are; bad input and bad paths are errors, not panics.

use plot::{write_panels_png, write_png, Figure, PlotError, Series, HEIGHT, PANEL_HEIGHT, WIDTH};
use std::path::PathBuf;

/// A fresh path under the system temp directory, unique per test.
fn temp_png(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("plot-tests-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Decodes an RGB PNG into (width, height, pixels).
fn decode(path: &std::path::Path) -> (u32, u32, Vec<u8>, png::ColorType) {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf, info.color_type)
}

/// Number of pixels in rows `rows` that are clearly not white.
fn ink(pixels: &[u8], rows: std::ops::Range<u32>) -> usize {
    let stride = 3 * WIDTH as usize;
    rows.map(|r| &pixels[r as usize * stride..(r as usize + 1) * stride])
        .map(|row| row.chunks(3).filter(|p| p.iter().any(|&c| c < 200)).count())
        .sum()
}

fn sine_figure() -> Figure {
    let t: Vec<f64> = (0..200).map(|i| i as f64 * 0.05).collect();
    let mut fig = Figure::new("tip deflection w(t)", "t [s]", "w [m]");
    fig.series
        .push(Series::line("flexmbs", t.clone(), t.iter().map(|t| t.sin()).collect()));
    fig.series.push(Series::markers(
        "reference",
        t.iter().step_by(10).copied().collect(),
        t.iter().step_by(10).map(|t| t.sin()).collect(),
    ));
    fig
}

#[test]
fn time_history_png_decodes_with_title_and_curves() {
    let path = temp_png("history.png");
    write_png(&sine_figure(), &path).unwrap();
    let (w, h, pixels, colour) = decode(&path);
    assert_eq!((w, h), (WIDTH, HEIGHT));
    assert_eq!(colour, png::ColorType::Rgb);
    // The caption sits in the top 50 rows: ink there means the embedded font drew text.
    assert!(ink(&pixels, 0..50) > 200, "no title drawn");
    // The plotting area holds axes, grid, two curves and the legend.
    assert!(ink(&pixels, 50..HEIGHT - 60) > 5000, "no curves drawn");
    // Both series' colours appear (tab10 blue and orange).
    let has = |rgb: [u8; 3]| pixels.chunks(3).any(|p| p == rgb);
    assert!(has([31, 119, 180]) && has([255, 127, 14]));
    let bytes = std::fs::metadata(&path).unwrap().len();
    assert!(bytes > 5_000, "suspiciously small PNG: {bytes} bytes");
}

#[test]
fn log_log_convergence_png() {
    let path = temp_png("convergence.png");
    let n: Vec<f64> = vec![1.0, 2.0, 4.0, 8.0, 16.0];
    let mut fig = Figure::new("error against N", "N superelements", "relative error");
    fig.x_log = true;
    fig.y_log = true;
    fig.series.push(Series::line_markers(
        "w/L",
        n.clone(),
        n.iter().map(|n| 0.3 / (n * n)).collect(),
    ));
    fig.series.push(Series::line(
        "slope -2",
        n.clone(),
        n.iter().map(|n| 1.0 / (n * n)).collect(),
    ));
    write_png(&fig, &path).unwrap();
    let (w, h, pixels, _) = decode(&path);
    assert_eq!((w, h), (WIDTH, HEIGHT));
    assert!(ink(&pixels, 50..HEIGHT - 60) > 3000);
}

#[test]
fn unwritable_path_is_an_error() {
    let path = PathBuf::from("/nonexistent-directory-for-plot-tests/x.png");
    match write_png(&sine_figure(), &path) {
        Err(PlotError::Write { path: p, .. }) => assert_eq!(p, path),
        other => panic!("expected a write error, got {other:?}"),
    }
}

#[test]
fn bad_data_is_refused_with_the_series_named() {
    let path = temp_png("bad.png");
    let mut fig = Figure::new("bad", "x", "y");
    fig.series.push(Series::line("short", vec![1.0, 2.0], vec![1.0]));
    assert!(matches!(
        write_png(&fig, &path),
        Err(PlotError::LengthMismatch { x_len: 2, y_len: 1, .. })
    ));

    let mut fig = Figure::new("bad", "x", "y");
    fig.y_log = true;
    fig.series.push(Series::line("zero", vec![1.0, 2.0], vec![1.0, 0.0]));
    let err = write_png(&fig, &path).unwrap_err();
    assert!(matches!(err, PlotError::NotPositiveOnLogAxis { index: 1, .. }));
    assert!(err.to_string().contains("'zero'"), "{err}");

    let mut fig = Figure::new("bad", "x", "y");
    fig.series
        .push(Series::line("nan", vec![1.0, 2.0], vec![f64::NAN, 0.0]));
    assert!(matches!(
        write_png(&fig, &path),
        Err(PlotError::NotFinite { index: 0, .. })
    ));

    let fig = Figure::new("empty", "x", "y");
    assert!(matches!(write_png(&fig, &path), Err(PlotError::Empty { .. })));
}

#[test]
fn constant_series_still_draws() {
    // All values equal: the axis span must be widened, not zero (plotters would divide by it).
    let path = temp_png("constant.png");
    let mut fig = Figure::new("constant", "x", "y");
    fig.series.push(Series::line("c", vec![1.0, 1.0], vec![0.0, 0.0]));
    write_png(&fig, &path).unwrap();
    let mut fig = Figure::new("constant log", "x", "y");
    fig.x_log = true;
    fig.y_log = true;
    fig.series.push(Series::markers("c", vec![2.0], vec![3.0]));
    write_png(&fig, &path).unwrap();
}

#[test]
fn keep_example_pngs_when_asked() {
    // PLOT_TEST_OUT=dir keeps the two example figures for a look by eye.
    if let Ok(dir) = std::env::var("PLOT_TEST_OUT") {
        write_png(&sine_figure(), &PathBuf::from(dir).join("history.png")).unwrap();
    }
}

/// Components of different size or unit get a panel each, with their own y axis: the
/// millimetre deflection is drawn over the panel's height, not flattened beside a 10 m
/// position on a shared axis.
#[test]
fn panels_give_each_component_its_own_axis() {
    let t: Vec<f64> = (0..300).map(|i| i as f64 * 0.1).collect();
    let mut x = Figure::new("x", "t [s]", "x [m]");
    x.series
        .push(Series::line("x [m]", t.clone(), t.iter().map(|_| 10.0).collect()));
    let mut w = Figure::new("y", "t [s]", "y [m]");
    w.series.push(Series::line(
        "y [m]",
        t.clone(),
        t.iter().map(|t| -1e-3 * (t / 5.0).sin()).collect(),
    ));
    let path = temp_png("panels.png");
    write_panels_png("sensor tip", &[x, w], &path).unwrap();
    let (width, height, pixels, _) = decode(&path);
    assert_eq!(width, WIDTH);
    assert_eq!(height, (2 * PANEL_HEIGHT + 48).max(HEIGHT));
    // The second component's curve (tab10 orange) spans most of its panel's height: find the
    // rows of the lower half that hold orange.
    let stride = 3 * WIDTH as usize;
    let orange_rows: Vec<u32> = (height / 2..height)
        .filter(|&r| {
            pixels[r as usize * stride..(r as usize + 1) * stride]
                .chunks(3)
                .any(|p| p == [255, 127, 14])
        })
        .collect();
    let span = orange_rows.last().unwrap() - orange_rows.first().unwrap();
    // A sine over its own axis fills about 90 % of the plotting area (about 200 of the
    // panel's 300 rows); on an axis shared with 10 m it would be a flat line of 2-3 rows.
    assert!(span > 120, "the small component is flattened: {span} rows");
    // One panel is the plain figure.
    write_panels_png("one", &[sine_figure()], &path).unwrap();
    assert_eq!(decode(&path).1, HEIGHT);
    assert!(matches!(
        write_panels_png("none", &[], &path),
        Err(PlotError::Empty { .. })
    ));
}
