//! B1-B3: geometrically nonlinear statics through superelements in series: Mattiasson's
//! elastica, the roll-up into a circle, and the Bathe-Bolourchi 45-degree bend.

use crate::models::{bend_45, elastica_EI, elastica_cantilever, Variant, MATTIASSON};
use crate::{sci, slope, Block, Extent, Grid, Row, Table};
use mbs::{solve_static, StaticSettings, System};
use nalgebra::Vector3;
use plot::{Figure, Series};
use std::error::Error;
use std::f64::consts::PI;

type Result<T> = std::result::Result<T, Box<dyn Error>>;

/// Mattiasson (1981), validation problem B1: a = PL^2/EI -> (w/L, u/L, tip rotation).
pub const ELASTICA: [(f64, [f64; 3]); 4] = [MATTIASSON[0], MATTIASSON[1], MATTIASSON[4], MATTIASSON[6]];

/// Elements per elastica superelement (static modes only: the segment's interface statics
/// are the FE model's exactly, so the element count inside a segment does not matter for the
/// cubic Euler-Bernoulli element, which is exact for end loads).
const ELASTICA_ELEMENTS: usize = 2;

/// What one static solve gives: tip (w/L, u/L, rotation), load steps and Newton iterations.
pub struct TipResult {
    pub tip: [f64; 3],
    pub steps: usize,
    pub iterations: usize,
    pub seconds: f64,
}

/// Tip of the elastica cantilever of `n` superelements under a tip dead force (a = PL^2/EI)
/// or, with `moment`, a tip moment (b = ML/EI).
pub fn elastica_tip(n: usize, load: f64, moment: bool, variant: Variant) -> Result<TipResult> {
    let (mut model, tip) = elastica_cantilever(n, ELASTICA_ELEMENTS, variant)?;
    let EI = elastica_EI();
    if moment {
        model.add_dead_moment(tip, Vector3::new(0.0, 0.0, load * EI));
    } else {
        model.add_dead_force(tip, Vector3::new(0.0, load * EI, 0.0));
    }
    let t0 = std::time::Instant::now();
    let sys = System::new(&model)?;
    // Load steps: a quarter turn of the tip per step at most keeps Newton in its basin.
    let steps = if moment {
        (4.0 * load / PI).ceil() as usize + 1
    } else {
        4
    };
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(steps)).map_err(|e| e.error)?;
    let seconds = t0.elapsed().as_secs_f64();
    let d = sol.sensors.series("tip").ok_or("no tip sensor")?;
    let r = sol.sensors.series("rot").ok_or("no rot sensor")?;
    let (d, r) = (d.last().ok_or("no step")?, r.last().ok_or("no step")?);
    Ok(TipResult {
        tip: [d[1], -d[0], r[2]],
        steps: sol.steps.len(),
        iterations: sol.steps.iter().map(|s| s.residuals.len() - 1).sum(),
        seconds,
    })
}

/// Largest relative error of (w/L, u/L, rotation) against `reference`.
fn max_rel(tip: &[f64; 3], reference: &[f64; 3]) -> f64 {
    (0..3)
        .map(|i| ((tip[i] - reference[i]) / reference[i]).abs())
        .fold(0.0, f64::max)
}

/// B1: the elastica at a = 1, 2, 5, 10 with N = 1..16 superelements.
pub fn b1_elastica(extent: Extent) -> Result<Vec<Block>> {
    let ns: Vec<usize> = match extent {
        Extent::Quick => vec![8, 16],
        Extent::Full => vec![1, 2, 4, 8, 16],
    };
    let mut rows = Vec::new();
    let mut grid_rows = Vec::new();
    let mut fig = Figure::new(
        "B1 elastica: error against the number of superelements",
        "N",
        "max relative error of w/L, u/L, rotation",
    );
    fig.x_log = true;
    fig.y_log = true;
    for &(a, reference) in &ELASTICA {
        let mut errs = Vec::new();
        let mut cells = vec![format!("{a}")];
        let mut last = None;
        for &n in &ns {
            match elastica_tip(n, a, false, Variant::REFERENCE) {
                Ok(r) => {
                    let e = max_rel(&r.tip, &reference);
                    cells.push(sci(e));
                    errs.push((n as f64, e));
                    last = Some(r.tip);
                }
                // A coarse chain may not reach the load: say so in the table, as a result.
                Err(e) => cells.push(format!("no conv. ({e})")),
            }
        }
        let fine: Vec<(f64, f64)> = errs.iter().copied().filter(|(n, _)| *n >= 4.0).collect();
        let rate = if fine.len() >= 2 {
            -slope(
                &fine.iter().map(|p| p.0).collect::<Vec<_>>(),
                &fine.iter().map(|p| p.1).collect::<Vec<_>>(),
            )
        } else {
            f64::NAN
        };
        cells.push(format!("{rate:.2}"));
        grid_rows.push(cells);
        fig.series.push(Series::line_markers(
            format!("a = {a}"),
            errs.iter().map(|p| p.0).collect(),
            errs.iter().map(|p| p.1).collect(),
        ));
        let tip = last.ok_or_else(|| format!("elastica a = {a}: the finest chain did not converge"))?;
        // Tolerance 1e-3 relative at N = 16 (the required accuracy): the error falls as 1/N^2
        // (measured 0.08-0.17 at N = 1, 4.4e-4 to 6.4e-4 at N = 16); the table's five digits are
        // 2e-5 relative.
        for (k, what) in ["w/L", "u/L", "tip rotation [rad]"].iter().enumerate() {
            rows.push(Row::new(
                format!("a = {a}: {what}, N = {}", ns.last().unwrap()),
                reference[k],
                tip[k],
                1e-3,
            ));
        }
    }
    let mut header = vec!["a".to_string()];
    header.extend(ns.iter().map(|n| format!("N = {n}")));
    header.push("rate (N >= 4)".into());
    let n_last = *ns.last().unwrap();
    let reference_curve: Vec<f64> = ns.iter().map(|&n| 0.05 / (n * n) as f64).collect();
    fig.series.push(Series::line(
        "1/N^2",
        ns.iter().map(|&n| n as f64).collect(),
        reference_curve,
    ));
    Ok(vec![
        Block::Heading("B. Geometrically nonlinear statics".into()),
        Block::Table(Table {
            title: format!("B1 elastica (Mattiasson 1981), N = {n_last} superelements"),
            note: "Cantilever L = 1, square 10 mm (L/r = 346), EI = 1, tip dead force a = PL^2/EI; a chain of N superelements (2 Euler-Bernoulli elements each, static modes only, frame at the centre of mass), Newton with 4 load steps. The tip rotation is the angle of the tip's rotation vector. Tolerance 1e-3 relative: the error falls as 1/N^2 (table below).".into(),
            rows,
        }),
        Block::Grid(Grid {
            title: "B1 convergence: max relative error of (w/L, u/L, rotation) against N".into(),
            note: "Each superelement is exact for its own end loads, so the error is that of replacing the curved elastica by N chords of corotated linear beams: it falls as 1/N^2. The rate is the least-squares slope over N = 4, 8, 16.".into(),
            header,
            rows: grid_rows,
        }),
        Block::Figure {
            file: "b1_convergence.png".into(),
            figure: fig,
        },
    ])
}

/// B2: roll-up under a tip moment, b = ML/EI up to 2 pi (the circle).
pub fn b2_roll_up(extent: Extent) -> Result<Vec<Block>> {
    let ns: Vec<usize> = match extent {
        Extent::Quick => vec![8, 16],
        Extent::Full => vec![2, 4, 8, 16],
    };
    let bs = [PI / 2.0, PI, 1.5 * PI, 2.0 * PI];
    let mut rows = Vec::new();
    let mut grid_rows = Vec::new();
    let mut fig = Figure::new("B2 roll-up: tip error against N", "N", "|tip - exact| / L");
    fig.x_log = true;
    fig.y_log = true;
    for &b in &bs {
        // The arc: x_tip/L = sin b / b, w/L = (1 - cos b)/b; u/L = 1 - x_tip/L.
        let exact = [(1.0 - b.cos()) / b, 1.0 - b.sin() / b];
        let mut cells = vec![format!("{:.2} pi", b / PI)];
        let mut errs = Vec::new();
        let mut last = None;
        for &n in &ns {
            match elastica_tip(n, b, true, Variant::REFERENCE) {
                Ok(r) => {
                    let e = ((r.tip[0] - exact[0]).powi(2) + (r.tip[1] - exact[1]).powi(2)).sqrt();
                    cells.push(sci(e));
                    // At b = 2 pi the error is zero up to round-off: plot it at a floor.
                    errs.push((n as f64, e.max(1e-16)));
                    last = Some(r.tip);
                }
                // A coarse chain may not reach the load: a result, reported as such.
                Err(e) => {
                    cells.push(format!("no conv. ({e})"));
                    last = None;
                }
            }
        }
        grid_rows.push(cells);
        fig.series.push(Series::line_markers(
            format!("b = {:.2} pi", b / PI),
            errs.iter().map(|p| p.0).collect(),
            errs.iter().map(|p| p.1).collect(),
        ));
        let tip = last.ok_or_else(|| format!("roll-up b = {b}: the finest chain did not converge"))?;
        let n_last = ns.last().unwrap();
        // Tip position error per unit length. No figure is required for B2: 2e-3 at N = 16
        // is the 1/N^2 chord error measured at b = pi (4.1e-3 at N = 8, 1.02e-3 at N = 16)
        // with a factor 2 of margin. At 2 pi the closed circle is exact by symmetry (a regular
        // polygon of exact constant-moment arcs), so round-off: 1e-9.
        let tol = if (b - 2.0 * PI).abs() < 1e-12 { 1e-9 } else { 2e-3 };
        for (k, what) in ["w", "u"].into_iter().enumerate() {
            rows.push(Row::scaled(
                format!("b = {:.2} pi: {what}/L, N = {n_last}", b / PI),
                exact[k],
                tip[k],
                1.0,
                tol,
            ));
        }
    }
    let mut header = vec!["b = ML/EI".to_string()];
    header.extend(ns.iter().map(|n| format!("N = {n}")));
    Ok(vec![
        Block::Table(Table {
            title: "B2 roll-up under a tip moment (exact arc)".into(),
            note: "The elastica cantilever of B1 under a tip dead moment b = ML/EI; the exact solution is an arc. Errors are per unit length (the column 'rel. error' is |ours - exact| / L). At b = 2 pi the beam closes into a circle and the tip returns to the clamp.".into(),
            rows,
        }),
        Block::Grid(Grid {
            title: "B2 convergence: |tip - exact| / L against N".into(),
            note: "Constant moment: each superelement bends into a circular arc that its corotated linear statics approximate by a chord with end rotations; the tip error falls as 1/N^2 except at 2 pi, where symmetry makes it exact.".into(),
            header,
            rows: grid_rows,
        }),
        Block::Figure {
            file: "b2_convergence.png".into(),
            figure: fig,
        },
    ])
}

/// Simo & Vu-Quoc (1986), validation problem B3: load P -> tip position.
pub const BEND: [(f64, [f64; 3]); 3] = [
    (300.0, [58.84, 22.33, 40.08]),
    (450.0, [52.32, 18.62, 48.39]),
    (600.0, [47.23, 15.79, 53.37]),
];

/// Tip position of the bend with `n` superelements under P (along z).
pub fn bend_tip(n: usize, elements: usize, P: f64, variant: Variant) -> Result<[f64; 3]> {
    let (mut model, tip) = bend_45(n, elements, variant)?;
    model.add_dead_force(tip, Vector3::new(0.0, 0.0, P));
    let sys = System::new(&model)?;
    let sol = solve_static(&sys, sys.initial_state(), &StaticSettings::new(6)).map_err(|e| e.error)?;
    let p = sol.sensors.series("tip").ok_or("no tip sensor")?;
    let p = p.last().ok_or("no step")?;
    Ok([p[0], p[1], p[2]])
}

/// B3: the 45-degree bend at P = 300, 450, 600.
pub fn b3_bend(extent: Extent) -> Result<Vec<Block>> {
    let ns: Vec<usize> = match extent {
        Extent::Quick => vec![16],
        Extent::Full => vec![2, 4, 8, 16],
    };
    let elements = 2;
    let mut rows = Vec::new();
    let mut grid_rows = Vec::new();
    let n_last = *ns.last().unwrap();
    for &(P, reference) in &BEND {
        let mut cells = vec![format!("{P}")];
        let mut last = [0.0; 3];
        for &n in &ns {
            match bend_tip(n, elements, P, Variant::REFERENCE) {
                Ok(tip) => {
                    cells.push(format!("({:.2}, {:.2}, {:.2})", tip[0], tip[1], tip[2]));
                    last = tip;
                }
                Err(e) => cells.push(format!("no conv. ({e})")),
            }
        }
        let coordinate_errors: Vec<f64> = (0..3)
            .map(|k| ((last[k] - reference[k]) / reference[k]).abs())
            .collect();
        cells.push(format!(
            "{} / {} / {}",
            sci(coordinate_errors[0]),
            sci(coordinate_errors[1]),
            sci(coordinate_errors[2])
        ));
        grid_rows.push(cells);
        // 1 % of the tip's distance from the clamp: published solutions scatter by
        // 0.5 %. Per coordinate, y (the smallest) differs from Simo & Vu-Quoc by up to 1.5 %
        // while N = 8 and 16 agree within 0.2 %: see the grid and the report.
        let distance = reference.iter().map(|c| c * c).sum::<f64>().sqrt();
        let miss = (0..3).map(|k| (last[k] - reference[k]).powi(2)).sum::<f64>().sqrt();
        rows.push(Row::scaled(
            format!("P = {P}: |tip - reference| / |reference|, N = {n_last}"),
            0.0,
            miss,
            distance,
            1e-2,
        ));
    }
    let mut header = vec!["P".to_string()];
    header.extend(ns.iter().map(|n| format!("N = {n}")));
    header.push(format!("error x / y / z at N = {n_last}"));
    Ok(vec![
        Block::Table(Table {
            title: format!("B3 45-degree bend (Bathe & Bolourchi 1979), N = {n_last} superelements"),
            note: format!(
                "Arc R = 100, 45 degrees in the x-y plane from the origin, clamped there; square 1 x 1, E = 1e7, G = 5e6 (nu = 0), GJ = {:.3e} (J = 0.141, the benchmark's value); Timoshenko elements, {elements} per superelement, static modes only; dead tip force P along z in 6 load steps. Reference: Simo & Vu-Quoc (1986), 8 elements. Tolerance: the required 1 % on the tip position, |tip - reference| / |reference| (published solutions scatter by about 0.5 %). Per coordinate (grid below), y is 1.0-1.5 % below the reference at all loads and z 1 % above it at P = 300, so a per-coordinate 1 % would not hold for y; N = 8 and N = 16 agree within 0.2 %, so this is the gap between the converged AIC-FFR chain and Simo & Vu-Quoc's 8-element solution, not a discretisation error of ours.",
                crate::models::BEND_GJ
            ),
            rows,
        }),
        Block::Grid(Grid {
            title: "B3 tip position against N".into(),
            note: "Tip (x, y, z) for each load and number of superelements.".into(),
            header,
            rows: grid_rows,
        }),
    ])
}
