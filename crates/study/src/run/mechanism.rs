//! The analyses of the mechanism: `mbs::solve_static` (equilibrium), the generalized-α
//! time integration (dynamic, [`super::dynamic`]), `mbs::spectrum` (linearized) and
//! `mbs::buckling` on the built mechanism, each from the state its `start` names.
//!
//! Results stream as they are computed: one CSV file per sensor (header with units), flushed
//! after every row, and the deformed meshes of every body (`mechanism_NNNNN.vtu`, listed in
//! `mechanism.pvd`, rewritten after each) at the output times, so an interrupted run keeps
//! them. A solver failure keeps what was written and reports time, step and residual.

use super::dynamic::dynamic;
use super::mesh::MeshRecovery;
use super::outcome::Outcome;
use super::sensors::{report_last, SensorSampler};
use crate::build::BuiltMechanism;
use crate::error::BoxError;
use crate::input::validate::mechanism::{About, MbsAnalysis};
use crate::input::validate::Study;
use crate::output::observer::{Cell, Observer, Progress, Series, Table};
use mbs::System;
use nalgebra::Vector3;
use serde_json::json;
use std::sync::Arc;
use std::time::Instant;

/// Runs one analysis of the mechanism, every result to `obs`.
/// `start`: the final state of the analysis named in its `start` key; `forces`: the run's
/// force law.
pub fn run_analysis(
    study: &Study,
    analysis: &MbsAnalysis,
    b: &BuiltMechanism,
    start: Option<&mbs::State>,
    forces: &super::force_law::Forces,
    obs: &mut dyn Observer,
) -> Result<Outcome, BoxError> {
    let sys = Arc::new(super::force_law::system(study, b, forces)?);
    let mut out = Outcome::of_mechanism(study, b, &sys);
    match analysis {
        MbsAnalysis::Equilibrium {
            steps,
            tolerance,
            max_iterations,
            time,
            arc_length,
        } => {
            let method = static_method(*steps, *tolerance, *max_iterations, *time, *arc_length);
            equilibrium(study, &sys, b, (&method, *time), start, obs, &mut out)?
        }
        MbsAnalysis::Dynamic { .. } => dynamic(study, &sys, b, analysis, start, obs, &mut out)?,
        MbsAnalysis::Linearized { modes, about } => linearized(&sys, b, *modes, about, start, obs, &mut out)?,
        MbsAnalysis::Buckling {
            modes,
            steps,
            tolerance,
            max_iterations,
        } => run_buckling(
            study,
            &sys,
            b,
            start,
            [*modes, *steps, *max_iterations],
            *tolerance,
            obs,
            &mut out,
        )?,
    }
    Ok(out)
}

/// The load stepping (or arc-length continuation, `arc_length`) of an `equilibrium` analysis.
fn static_method(
    steps: usize,
    tolerance: f64,
    max_iterations: usize,
    time: f64,
    arc_length: bool,
) -> mbs::StaticMethod {
    if arc_length {
        // The first arc spans about 1/steps of the load (the scaled norm weighs the load
        // factor by 1); the path may take up to 50 times as many steps to pass limit points.
        let mut s = mbs::ArcLengthSettings::new(1.0 / steps as f64, 1.0, (50 * steps).max(1000));
        s.tolerance = tolerance;
        s.max_iterations = max_iterations;
        s.time = time;
        mbs::StaticMethod::ArcLength(s)
    } else {
        let mut s = mbs::StaticSettings::new(steps);
        s.tolerance = tolerance;
        s.max_iterations = max_iterations;
        s.time = time;
        mbs::StaticMethod::LoadStepping(s)
    }
}

/// The `equilibrium` analysis: `method` from `start` (at rest at time `time`) or the initial
/// state; the final state when every load step converged.
fn equilibrium(
    study: &Study,
    sys: &Arc<System>,
    b: &BuiltMechanism,
    (method, time): (&mbs::StaticMethod, f64),
    start: Option<&mbs::State>,
    obs: &mut dyn Observer,
    out: &mut Outcome,
) -> Result<(), BoxError> {
    let output = &study.mechanism.output;
    let t0 = Instant::now();
    let first = match start {
        Some(s) => sys.at_rest(s, time),
        None => sys.initial_state(),
    };
    let (sol, failure) = match mbs::solve_static_with(sys, first, method) {
        Ok(s) => (s, None),
        Err(inc) => (inc.partial, Some(inc.error)),
    };
    let mut files = SensorSampler::start(obs, &b.groups, &sol.sensors, "load factor [-]", output.plots)?;
    let mut rec = sys.sensor_record();
    // A sensor that is not finite stopped the analysis at its row: the rows before it are
    // written, as in a dynamic run.
    let good = match &failure {
        Some(mbs::SolveError::NonFiniteSensor { .. }) => sol.sensors.rows.len().saturating_sub(1),
        _ => sol.sensors.rows.len(),
    };
    for (t, row) in sol.sensors.times.iter().zip(&sol.sensors.rows).take(good) {
        rec.times.push(*t);
        rec.rows.push(row.clone());
        files.sample(obs, *t, &rec)?;
    }
    let mut mw = MeshRecovery::new(b, sys)?;
    mw.write(obs, 1.0, sys, &sol.state, b)?;
    let (hot_spots, hot_lines) = mw.hot_spot_summary(sys, b, "load_factor");
    out.report.extend(hot_lines);
    let iterations: usize = sol.steps.iter().map(|s| s.residuals.len().saturating_sub(1)).sum();
    out.report.push(format!(
        "{} load steps, {iterations} Newton iterations, {} rejected attempts; last relative residual {:.2e}",
        sol.steps.len(),
        sol.rejected.len(),
        sol.steps
            .last()
            .and_then(|s| s.residuals.last())
            .copied()
            .unwrap_or(f64::NAN)
    ));
    report_last(&mut out.report, b, &files);
    out.results = json!({
        "model": b.size(sys),
        "load_steps": sol.steps.len(),
        "newton_iterations": iterations,
        "rejected_steps": sol.rejected.len(),
        "load_factor_reached": sol.sensors.times.last().copied().unwrap_or(0.0),
        "seconds_solving": t0.elapsed().as_secs_f64(),
        "hot_spots": hot_spots,
    });
    obs.sensors_end()?;
    if failure.is_none() {
        out.final_state = Some(sol.state.clone());
    }
    out.failure = failure.map(|e| {
        let message = "equilibrium stopped; the converged load steps are written".into();
        let step = e.step().filter(|&s| s > 0).unwrap_or(sol.steps.len() + 1);
        b.stopped(study, message, Some(step), e)
    });

    Ok(())
}

/// The state a `linearized` analysis linearises about: that of `start`, else the initial
/// state, the equilibrium or the state of a dynamic run to a time, as `about` says.
fn linearization_state(sys: &System, about: &About, start: Option<&mbs::State>) -> Result<mbs::State, BoxError> {
    Ok(match (start, about) {
        (Some(s), _) => s.clone(),
        (None, About::Initial) => sys.initial_state(),
        (None, About::Equilibrium) => {
            mbs::solve_static(sys, sys.initial_state(), &mbs::StaticSettings::new(1))
                .map_err(|e| format!("the equilibrium to linearise about: {}", e.error))?
                .state
        }
        (None, About::Time { t, dt }) => {
            let settings = mbs::DynamicSettings::new(*dt, *t, mbs::DynamicSettings::DEFAULT_RHO_INF);
            mbs::solve_dynamic(sys, sys.initial_state(), &settings)
                .map_err(|e| format!("the dynamic run up to t = {t} s to linearise about: {}", e.error))?
                .final_state
        }
    })
}

/// The `linearized` analysis: the `modes` lowest frequencies and state-space eigenvalues
/// about the state of [`linearization_state`], with the bodies and nodes that carry each
/// mode.
fn linearized(
    sys: &System,
    b: &BuiltMechanism,
    modes: usize,
    about: &About,
    start: Option<&mbs::State>,
    obs: &mut dyn Observer,
    out: &mut Outcome,
) -> Result<(), BoxError> {
    let state = linearization_state(sys, about, start)?;
    let s = mbs::spectrum(sys, &state)?;
    let mut csv = Table::new("frequencies", &["mode", "frequency [Hz]", "omega [rad/s]"]);
    let shown: Vec<f64> = s.omega.iter().take(modes).copied().collect();
    for (k, w) in shown.iter().enumerate() {
        csv.row(vec![
            Cell::from(k + 1),
            Cell::Num(w / (2.0 * std::f64::consts::PI)),
            Cell::Num(*w),
        ]);
    }
    obs.table(&csv)?;
    let mut csv = Table::new(
        "state_space",
        &["eigenvalue", "real [1/s]", "imaginary [rad/s]", "damped frequency [Hz]"],
    );
    for (k, (re, im)) in s.state_space.iter().enumerate() {
        csv.row(vec![
            Cell::from(k + 1),
            Cell::Num(*re),
            Cell::Num(*im),
            Cell::Num(im / (2.0 * std::f64::consts::PI)),
        ]);
    }
    obs.table(&csv)?;
    // Which bodies and nodes carry each mode's energy (mbs::mode_energies).
    let energies = mbs::mode_energies(sys, &state)?;
    let mut csv = Table::new(
        "modes",
        &[
            "mode",
            "frequency [Hz]",
            "damping ratio [-]",
            "rigid body [-]",
            "carried by",
            "growth rate [1/s]",
        ],
    );
    for (k, e) in energies.iter().take(modes).enumerate() {
        csv.row(vec![
            Cell::from(k + 1),
            Cell::Num(e.frequency_hz),
            e.damping_ratio.map_or(Cell::Empty, Cell::Num),
            Cell::from(usize::from(e.rigid_body)),
            Cell::from(e.label.clone()),
            e.growth_rate.map_or(Cell::Empty, Cell::Num),
        ]);
    }
    obs.table(&csv)?;
    // A growing eigenvalue: the state is not a stable one, whatever the frequencies say.
    let growing = s.growing();
    let fastest = growing.iter().map(|g| g.0).fold(0.0, f64::max);
    if !growing.is_empty() {
        let unstable: Vec<String> = energies
            .iter()
            .enumerate()
            .filter(|(_, e)| e.unstable)
            .map(|(k, _)| (k + 1).to_string())
            .collect();
        let line = format!(
            "UNSTABLE: {} state-space eigenvalue(s) with a positive real part (the fastest grows at {fastest:.4e} 1/s: amplitude doubled every {:.4e} s){}; the state linearised about is not a stable equilibrium or steady motion",
            growing.len(),
            std::f64::consts::LN_2 / fastest,
            if unstable.is_empty() {
                String::new()
            } else {
                format!(", modes {}", unstable.join(", "))
            }
        );
        obs.progress(&Progress::Warning(format!("linearized analysis: {line}")));
        out.report.insert(0, line);
    }
    for (k, e) in energies.iter().take(modes).enumerate() {
        out.report
            .push(format!("mode {}: {:.6e} Hz, {}", k + 1, e.frequency_hz, e.label));
    }
    let hz: Vec<f64> = shown.iter().map(|w| w / (2.0 * std::f64::consts::PI)).collect();
    out.report.push(format!(
        "lowest {} frequencies [Hz]: {}",
        hz.len(),
        hz.iter().map(|f| format!("{f:.6e}")).collect::<Vec<_>>().join(", ")
    ));
    // Each mode on the results page, about the state linearised about: a small motion along
    // it (its largest coordinate 1e-3, so that the bodies' frames follow it; a mode of the
    // bodies' elastic coordinates moves no node), which the page scales: the linearised mode
    // is the direction of that motion. A mode whose frames cannot be solved along it is left
    // off the page, and the report says which and why.
    let mut mw = MeshRecovery::new(b, sys)?;
    mw.view_base(obs, sys, &state, b)?;
    for (k, e) in energies.iter().take(modes).enumerate() {
        let largest = e.shape.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
        let shown = if e.shape.len() == sys.n_dof() && largest > 0.0 {
            let step: Vec<f64> = e.shape.iter().map(|x| x * 1e-3 / largest).collect();
            let mut moved = sys.retract(&state, &step);
            sys.reset_frames(&mut moved);
            mw.view_pose(obs, Series::Modes, (k + 1) as f64, sys, &moved, b)
                .map_err(|e| e.to_string())
        } else {
            Err("it has no shape in the mechanism's coordinates".to_string())
        };
        if let Err(why) = shown {
            out.report
                .push(format!("mode {} is not on the results page: {why}", k + 1));
        }
    }
    let labels: Vec<&str> = energies.iter().take(modes).map(|e| e.label.as_str()).collect();
    out.results = json!({
        "model": b.size(sys),
        "frequencies_hz": hz,
        "mode_labels": labels,
        "stable": growing.is_empty(),
        "growing_eigenvalues": growing.iter().map(|g| json!([g.0, g.1])).collect::<Vec<_>>(),
        "largest_growth_rate": if growing.is_empty() { json!(null) } else { json!(fastest) },
        "about": if start.is_some() { "start".to_string() } else { format!("{about:?}") },
    });
    Ok(())
}

/// The state `base` moved along the mode `phi` (coordinates of the system's dofs) until its
/// largest node displacement is a tenth of the model's size, its frames reset: the mode as
/// drawn.
fn mode_state(sys: &System, base_state: &mbs::State, phi: &[f64]) -> mbs::State {
    let base = sys.node_motions(base_state);
    let size = {
        let n = base.len().max(1) as f64;
        let c = base.iter().map(|m| m.r).sum::<Vector3<f64>>() / n;
        base.iter().map(|m| (m.r - c).norm()).fold(1e-3, f64::max)
    };
    let probe = sys.retract(base_state, &phi.iter().map(|x| x * 1e-6).collect::<Vec<_>>());
    let moved = sys
        .node_motions(&probe)
        .iter()
        .zip(&base)
        .map(|(a, b)| (a.r - b.r).norm())
        .fold(0.0, f64::max)
        / 1e-6;
    let scale = if moved > 0.0 { 0.1 * size / moved } else { 0.0 };
    let mut state = sys.retract(base_state, &phi.iter().map(|x| x * scale).collect::<Vec<_>>());
    sys.reset_frames(&mut state);
    state
}

/// The `buckling` analysis (`mbs::buckling` about the equilibrium under the full load, or the
/// state of `start`), with the stability of that equilibrium (`mbs::stability`): the load
/// factors as a table, each mode drawn on the loaded configuration for ParaView.
fn run_buckling(
    study: &Study,
    sys: &System,
    b: &BuiltMechanism,
    start: Option<&mbs::State>,
    [modes, steps, max_iterations]: [usize; 3],
    tolerance: f64,
    obs: &mut dyn Observer,
    out: &mut Outcome,
) -> Result<(), BoxError> {
    let unloaded = sys.initial_state();
    let loaded = match start {
        Some(s) => s.clone(),
        None => {
            let mut settings = mbs::StaticSettings::new(steps);
            settings.tolerance = tolerance;
            settings.max_iterations = max_iterations;
            match mbs::solve_static(sys, unloaded.clone(), &settings) {
                Ok(sol) => sol.state,
                // A value that is not finite is no limit point: say what it is.
                Err(inc)
                    if matches!(
                        inc.error,
                        mbs::SolveError::NonFiniteSensor { .. } | mbs::SolveError::NonFinite { .. }
                    ) =>
                {
                    out.results = json!({ "model": b.size(sys) });
                    let message = "buckling stopped: the equilibrium under the full load is not finite".into();
                    out.failure = Some(b.stopped(study, message, Some(inc.partial.steps.len() + 1), inc.error));
                    return Ok(());
                }
                Err(inc) => {
                    let reached = inc.partial.steps.last().map_or(0.0, |s| s.lambda);
                    out.report.push(format!(
                        "no equilibrium under the full load: load stepping stopped at load factor {reached:.6}"
                    ));
                    out.results = json!({
                        "model": b.size(sys),
                        "past_critical_point": true,
                        "load_factor_reached": reached,
                    });
                    let message = format!(
                        "the structure is past a limit point: no equilibrium beyond load factor {reached:.6}; an 'equilibrium' analysis with method = \"arc-length\" follows the path through it"
                    );
                    out.failure = Some(b.stopped(study, message, Some(inc.partial.steps.len() + 1), inc.error));
                    return Ok(());
                }
            }
        }
    };
    let stability = mbs::stability(sys, &loaded, 1.0)?;
    let bk = mbs::buckling(sys, &unloaded, &loaded, 1.0)?;
    let mut table = Table::new("load_factors", &["mode", "critical load factor [-]"]);
    for (k, f) in bk.load_factors.iter().take(modes).enumerate() {
        table.row(vec![Cell::from(k + 1), Cell::Num(*f)]);
    }
    obs.table(&table)?;
    // Each mode on the loaded configuration, its largest displacement a tenth of the model.
    let mut mw = MeshRecovery::new(b, sys)?;
    mw.view_base(obs, sys, &loaded, b)?;
    for k in 0..bk.load_factors.len().min(modes) {
        let phi: Vec<f64> = (0..sys.n_dof()).map(|i| bk.modes[(i, k)]).collect();
        let state = mode_state(sys, &loaded, &phi);
        mw.write_series(obs, Series::Modes, (k + 1) as f64, sys, &state, b)?;
    }
    let first = bk.load_factors.iter().copied().find(|f| *f > 0.0);
    let past = stability.past_critical_point() || first.is_some_and(|f| f < 1.0);
    out.report.push(format!(
        "critical load factors: {}",
        bk.load_factors
            .iter()
            .take(modes)
            .map(|f| format!("{f:.6e}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    if past {
        out.report.push(format!(
            "the structure is past a critical point under the full load: {} negative eigenvalue(s) of the tangent stiffness{}",
            stability.negative,
            first.map_or(String::new(), |f| format!(", lowest positive critical load factor {f:.6}"))
        ));
    }
    out.results = json!({
        "model": b.size(sys),
        "load_factors": bk.load_factors.iter().take(modes).collect::<Vec<_>>(),
        "past_critical_point": past,
        "negative_eigenvalues": stability.negative,
    });
    Ok(())
}
