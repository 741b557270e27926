//! Our side of the slider-crank comparison (validation problem C2; see the crate docs): builds the
//! mechanism with the rod reduced from the solid mesh, integrates it with the Lie-group
//! generalized-α at a fixed step and prints the wall time per step, the steps per second and
//! the rod's midpoint deflection relative to its chord.
//!
//! ```text
//! cargo run --release -p flexmbs-benchmarks --bin slider_crank -- [--h 1e-4] [--t-end T]
//!     [--modes 4] [--segments 1] [--kind hex20 --along 24 --across 2] [--frame com|node]
//!     [--rho-inf 0.9] [--rod solid|beam|round --beam-elements 4] [--geometric-stiffening]
//!     [--inertia-correction] [--planar] [--mass exact|lumped]
//!     [--newton full|modified] [--tolerance 1e-9] [--csv out.csv] [--reference ref.csv]
//! ```
//!
//! Defaults: h = T/400 with T = 2π/Ω, t_end = 2T. With one segment the midpoint is the mesh's
//! axis node at mid-length (recovered from the reduced body, as the Exudyn script measures
//! it); with an even number of segments it is the node between the middle segments (the
//! `LineDistance` sensor). `--rod beam` replaces each solid segment by Timoshenko beam elements
//! with the same section (the nonlinear reference: no rigid faces at the junctions); `--rod
//! round` by Euler-Bernoulli beam elements with the round section of validation problem C2 (the
//! rod Exudyn's beam elements model in `benchmarks/exudyn/slider_crank_beam.py`).
//! `--geometric-stiffening` reduces the rod with the geometric stiffness of its CB coordinates
//! (`CbSettings::geometric_stiffening`): each superelement's strain energy gains the cubic term
//! through which the axial force changes the bending stiffness. `--inertia-correction` adds the
//! static correction for the interfaces' inertia to the modes (`CbSettings::inertia_correction`:
//! the rod's axial force under its own inertia in the span whatever the number of modes).
//! `--planar` makes it a 2D mechanism: the rod segments are reduced as planar parts
//! (`CbSettings::planar`: the out-of-plane dofs of their interior supported, so `--modes m` are
//! the first m in-plane modes, where the 3D rod's alternate in-plane and out-of-plane bending),
//! the bodies are evaluated in the plane (`FlexibleBody::planar`: 3 coordinates per interface)
//! and the free nodes between the segments are supported to the plane
//! (`models::confine_to_plane`); beam rods only.
//! `--mass lumped` uses the
//! AIC-FFR paper's lumped inertia variant instead of the exact one. `--newton modified` keeps the
//! factorised iteration matrix across corrections and steps (`mbs::NewtonStrategy`); the
//! Jacobians (factorisations) per step are printed next to the iterations per step.
//! `--tolerance` sets Newton's relative tolerance (`DynamicSettings::tolerance`). `--csv`
//! writes `t, w, slider_x`; `--reference` reads such a file (a finer run) and prints the
//! deflection error against it. The time loop (steps and sensor records) is timed both by the
//! wall clock and by the process's CPU time ([`flexmbs_benchmarks::cpu_seconds`]), which the
//! load of a shared machine does not inflate.

use flexmbs_benchmarks::{
    beam_rod_body, cpu_seconds, median, midpoint_from_mesh, rod_body_with, slider_crank_model, Args, BeamRod,
    BenchError, RodMesh, SliderCrank,
};
use mbs::{DynamicSettings, Integrator, NewtonStrategy, System};
use nalgebra::Vector3;
use reduction::{CbSettings, ModeSelection};
use std::fmt::Write as _;
use std::process::ExitCode;
use std::time::Instant;
use superelement::{FrameChoice, MassVariant};

/// `(t, w)` pairs of a CSV written by this binary.
fn read_history(path: &str) -> Result<Vec<(f64, f64)>, Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string(path)?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let cols: Vec<f64> = line
            .split(',')
            .map(|c| c.trim().parse::<f64>())
            .collect::<Result<_, _>>()?;
        if cols.len() < 2 {
            return Err(format!("{path}:{}: expected t, w", i + 1).into());
        }
        out.push((cols[0], cols[1]));
    }
    Ok(out)
}

/// Linear interpolation of a sorted history at `t` (clamped at the ends).
fn interpolate(h: &[(f64, f64)], t: f64) -> f64 {
    let k = h.partition_point(|p| p.0 < t);
    if k == 0 {
        return h[0].1;
    }
    if k == h.len() {
        return h[h.len() - 1].1;
    }
    let ((t0, w0), (t1, w1)) = (h[k - 1], h[k]);
    w0 + (w1 - w0) * (t - t0) / (t1 - t0)
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::from_env()?;
    let p = SliderCrank::C2;
    let h: f64 = args.get("h", p.period() / 400.0)?;
    let t_end: f64 = args.get("t-end", 2.0 * p.period())?;
    let modes: usize = args.get("modes", 4)?;
    let n: usize = args.get("segments", 1)?;
    let rho_inf: f64 = args.get("rho-inf", 0.9)?;
    let mesh = args.rod_mesh()?;
    let frame = args.choice(
        "frame",
        &[
            ("com", FrameChoice::CenterOfMass),
            ("node", FrameChoice::InterfaceNode(0)),
        ],
    )?;
    let mass = args.choice(
        "mass",
        &[("exact", MassVariant::Exact), ("lumped", MassVariant::Lumped)],
    )?;
    let newton = args.choice(
        "newton",
        &[("full", NewtonStrategy::Full), ("modified", NewtonStrategy::Modified)],
    )?;
    if n == 0 || (n != 1 && n % 2 == 1) {
        return Err(BenchError::Argument {
            arg: "--segments".into(),
            why: "1 (solid rod) or an even number (the midpoint must be a node or the mesh's axis node)".into(),
        }
        .into());
    }
    let rod = args.choice(
        "rod",
        &[
            ("solid", None),
            ("beam", Some(BeamRod::Square)),
            ("round", Some(BeamRod::Round)),
        ],
    )?;
    if rod.is_none() && mesh.along % n != 0 {
        return Err(BenchError::Argument {
            arg: "--along".into(),
            why: format!(
                "{} elements along the rod do not split into {n} equal segments",
                mesh.along
            ),
        }
        .into());
    }
    let seg = p.rod / n as f64;
    let t0 = Instant::now();
    let geometric = args.flag("geometric-stiffening")?;
    let mut settings = CbSettings::new(ModeSelection::Count(modes));
    // One segment: the midpoint is recovered from the mesh shapes (module docs).
    settings.keep_mesh_shapes = n == 1;
    settings.geometric_stiffening = geometric;
    settings.inertia_correction = args.flag("inertia-correction")?;
    let planar = args.flag("planar")?;
    settings.planar = planar;
    let body = if let Some(rod) = rod {
        beam_rod_body(&p, seg, args.get("beam-elements", 4)?, rod, &settings)?
    } else {
        rod_body_with(
            &p,
            seg,
            RodMesh {
                along: mesh.along / n,
                ..mesh
            },
            &settings,
        )?
    };
    if geometric && body.geometric_stiffness.is_none() {
        return Err(BenchError::Argument {
            arg: "--geometric-stiffening".into(),
            why: "the reduction returned no geometric stiffness".into(),
        }
        .into());
    }
    let t_reduce = t0.elapsed().as_secs_f64();
    let (mut model, _) = slider_crank_model(&p, n, &body, frame, mass);
    if planar {
        models::confine_to_plane(&mut model);
    }
    let sys = System::new(&model)?;
    let steps = (t_end / h).round() as usize;
    let settings = DynamicSettings {
        newton,
        tolerance: args.get("tolerance", DynamicSettings::DEFAULT_TOLERANCE)?,
        ..DynamicSettings::new(h, steps as f64 * h, rho_inf)
    };
    let mut it = Integrator::new(&sys, sys.initial_state(), settings)?;
    let mut record = sys.sensor_record();
    it.record(&mut record)?;
    let mut per_step = Vec::with_capacity(steps);
    let (mut iterations, mut jacobians) = (0usize, 0usize);
    let (start, cpu_start) = (Instant::now(), cpu_seconds());
    for _ in 0..steps {
        let s = Instant::now();
        let report = it.step()?;
        iterations += report.residuals.len() - 1;
        jacobians += report.jacobians;
        it.record(&mut record)?;
        per_step.push(s.elapsed().as_secs_f64());
    }
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu_start;
    let w: Vec<f64> = if n == 1 {
        midpoint_from_mesh(&body, frame, &Vector3::new(p.crank, 0.0, 0.0), &record)?
    } else {
        record.column("midpoint", 0).ok_or(BenchError::MissingSensor {
            name: "midpoint".into(),
        })?
    };
    let slider = record
        .column("slider", 0)
        .ok_or(BenchError::MissingSensor { name: "slider".into() })?;
    let peak = w.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    println!(
        "flexmbs slider-crank: {}rod {n} x {} ({} coordinates each), {modes} modes, frame {frame:?}, geometric stiffening {}, {} unknowns, reduction {t_reduce:.2} s",
        if planar { "planar " } else { "" },
        if let Some(rod) = rod {
            format!("{} beam elements ({rod:?})", args.get("beam-elements", 4)?)
        } else {
            format!("{:?} {} x {} x {}", mesh.kind, mesh.along / n, mesh.across, mesh.across)
        },
        if planar {
            // 3 of the 6 coordinates of each interface are evaluated in the plane.
            format!("{}; {} in the plane", body.n_coordinates(), body.n_coordinates() - 3 * body.interfaces.len())
        } else {
            body.n_coordinates().to_string()
        },
        if geometric { "on" } else { "off" },
        sys.n_dof()
    );
    println!(
        "rod mass {:.6e} kg; first fixed-interface frequency of a segment {:.2} rad/s",
        body.inertia.mass * n as f64,
        body.fixed_interface_omega.first().copied().unwrap_or(f64::NAN)
    );
    println!(
        "h = {h:.6e} s, {steps} steps to t = {:.6} s, rho_inf = {rho_inf}, {newton:?} Newton: {:.2} iterations/step, {:.2} Jacobians/step",
        steps as f64 * h,
        iterations as f64 / steps as f64,
        jacobians as f64 / steps as f64
    );
    println!(
        "wall {wall:.4} s; per step: mean {:.3} us, median {:.3} us; {:.0} steps/s; CPU {cpu:.2} s = {:.3} us/step",
        wall / steps as f64 * 1e6,
        median(&per_step) * 1e6,
        steps as f64 / wall,
        cpu / steps as f64 * 1e6
    );
    println!(
        "midpoint deflection: peak |w| = {peak:.6e} m, w(t_end) = {:.6e} m",
        w[w.len() - 1]
    );
    println!(
        "RESULT s_per_step={:.6e} cpu_per_step={:.6e} peak_w={peak:.9e}",
        wall / steps as f64,
        cpu / steps as f64
    );
    if let Some(path) = args.text("csv") {
        let mut text = String::from("t,w,slider_x\n");
        for (k, t) in record.times.iter().enumerate() {
            writeln!(text, "{t:.9e},{:.9e},{:.9e}", w[k], slider[k])?;
        }
        std::fs::write(path, text)?;
    }
    if let Some(path) = args.text("reference") {
        let reference = read_history(path)?;
        let ref_peak = reference.iter().fold(0.0f64, |m, x| m.max(x.1.abs()));
        let worst = record
            .times
            .iter()
            .zip(&w)
            .map(|(&t, &wk)| (wk - interpolate(&reference, t)).abs())
            .fold(0.0f64, f64::max);
        println!(
            "against {path}: max |w - w_ref| / max |w_ref| = {:.3e}, peak error {:.3e}",
            worst / ref_peak,
            (peak - ref_peak) / ref_peak
        );
        println!(
            "RESULT history_error={:.6e} peak_error={:.6e}",
            worst / ref_peak,
            (peak - ref_peak) / ref_peak
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // The whole chain: a model error names the body, its source what is wrong with it.
            let mut text = format!("slider_crank: {e}");
            let mut source = e.source();
            while let Some(s) = source {
                text += &format!(": {s}");
                source = s.source();
            }
            eprintln!("{text}");
            ExitCode::from(2)
        }
    }
}
