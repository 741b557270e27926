//! `flexmbs run` without a file: the flexible planar slider-crank of validation problem C2
//! (`examples/slider_crank.toml`, compiled in), run like any study with its results in
//! `./slider_crank-results/` and the reduced rod cached in `./.flexmbs-cache/`; then a plot
//! of the rod's midpoint deflection against the crank angle, `slider-crank.png`.

use std::path::Path;
use study::error::{BoxError, ResultExt};
use study::input::source::Source;
use study::Options;

/// The study text of the built-in example: the library's copy of the slider-crank example.
pub const STUDY: &str = study::input::examples::SLIDER_CRANK;

/// Reads column `k` (after the header) of a CSV file written by the run.
fn column(path: &Path, k: usize) -> Result<Vec<f64>, BoxError> {
    let text = std::fs::read_to_string(path).context(|| format!("cannot read {}", path.display()))?;
    text.lines()
        .skip(1)
        .map(|l| {
            l.split(',')
                .nth(k)
                .and_then(|x| x.parse::<f64>().ok())
                .ok_or_else(|| format!("{}: a row without column {k}: '{l}'", path.display()).into())
        })
        .collect()
}

/// Runs the built-in study in the current folder and draws the deflection plot.
pub fn run(options: &Options) -> Result<(), BoxError> {
    let cwd = std::env::current_dir().context(|| "cannot read the current folder".to_string())?;
    let source = Source::from_text(&cwd.join("slider_crank.toml"), STUDY.to_string());
    let study = study::parse_and_validate(source)?;
    crate::tell!(
        "flexmbs: the built-in example: {}",
        study.title.as_deref().unwrap_or("slider-crank")
    );
    let summary = crate::console::run(&study, options, None)?;
    let out = options.results_dir(&study);
    let dir = out.join(&summary.analyses[0].name);
    let angle = column(&dir.join("crank-angle.csv"), 1)?;
    let deflection = column(&dir.join("rod-mid.csv"), 1)?;
    let angle_deg: Vec<f64> = angle.iter().map(|a| a.to_degrees()).collect();
    let mm: Vec<f64> = deflection.iter().map(|d| 1e3 * d).collect();
    let mut fig = plot::Figure::new(
        "Flexible slider-crank (C2): rod midpoint deflection",
        "crank angle [deg]",
        "midpoint deflection from the chord [mm]",
    );
    fig.series.push(plot::Series::line(
        "flexmbs, rod as 4 superelements, 2 modes each",
        angle_deg,
        mm.clone(),
    ));
    let png = out.join("slider-crank.png");
    plot::write_png(&fig, &png).context(|| format!("cannot draw {}", png.display()))?;
    let peak = mm.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let last_rev: Vec<f64> = {
        // The last full revolution: the crank angle grows by 2 pi.
        let end = *angle.last().unwrap_or(&0.0);
        angle
            .iter()
            .zip(&mm)
            .filter(|(a, _)| **a >= end - 2.0 * std::f64::consts::PI)
            .map(|(_, d)| *d)
            .collect()
    };
    let (lo, hi) = last_rev
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| (l.min(*d), h.max(*d)));
    crate::say!("rod midpoint deflection: largest |w| = {peak:.4} mm; over the last revolution {lo:.4} .. {hi:.4} mm");
    crate::say!("plot: {}", png.display());
    Ok(())
}
