//! Convergence studies (slow; run with `cargo test --release --test convergence -- --nocapture`).
//! Each prints its table; the asserts check the rates the method can honestly reach. In a debug
//! build (`cargo test --workspace`) they are ignored: they take 25 s in release, a minute in
//! debug.

#![allow(non_snake_case)]

#[path = "unit/fixtures.rs"]
mod fixtures;

use fixtures::{pendulum, spin_up, spin_up_with, try_elastica_tip, ELASTICA};
use mbs::{solve_dynamic, DynamicSettings, InitialCondition, SensorKind, System};
use reduction::ModeSelection;

/// Least-squares slope of log(err) against log(x).
fn slope(x: &[f64], err: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = x.iter().zip(err).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum::<f64>()
        / lx.iter().map(|a| (a - mx) * (a - mx)).sum::<f64>()
}

/// Formats an error, or the reason there is none.
fn cell(e: &Result<f64, mbs::SolveError>) -> String {
    match e {
        Ok(e) => format!("{e:>10.2e}"),
        Err(_) => format!("{:>10}", "no conv."),
    }
}

/// B1: every load of the table with N = 1..16 superelements; the error of (w/L, u/L,
/// rotation) falls as 1/N^2.
#[test]
#[cfg_attr(debug_assertions, ignore = "release only: cargo test --release --test convergence")]
fn elastica_all_loads() {
    let ns = [1usize, 2, 4, 8, 16];
    println!("elastica: max |error| of (w/L, u/L, tip rotation) against Mattiasson (1981)");
    println!(
        "{:>5} {}",
        "a",
        ns.iter()
            .map(|n| format!("{:>10}", format!("N = {n}")))
            .collect::<String>()
    );
    for &(a, reference) in &ELASTICA {
        let errs: Vec<Result<f64, mbs::SolveError>> = ns
            .iter()
            .map(|&n| {
                let (t, _) = try_elastica_tip(n, a, false)?;
                Ok((0..3).map(|i| (t[i] - reference[i]).abs()).fold(0.0, f64::max))
            })
            .collect();
        println!("{a:>5} {}", errs.iter().map(cell).collect::<String>());
        // N = 4, 8, 16 converge for every load and their error falls at second order (the
        // table's five digits are far below the N = 16 errors, 4e-5 and more).
        let e: Vec<f64> = errs[2..]
            .iter()
            .map(|e| *e.as_ref().expect("N >= 4 converges"))
            .collect();
        let s = slope(&[4.0, 8.0, 16.0], &e);
        assert!(s < -1.8, "a = {a}: slope {s}, errors {errs:?}");
    }
}

/// B2: the roll-up to b = pi/2, pi and 3 pi/2 with N = 2..16, and the closed circle at 2 pi.
#[test]
#[cfg_attr(debug_assertions, ignore = "release only: cargo test --release --test convergence")]
fn roll_up_to_the_circle() {
    use std::f64::consts::PI;
    println!("roll-up: max |error| of (w/L, u/L, rotation) against the arc");
    for b in [PI / 2.0, PI, 1.5 * PI] {
        let exact = [(1.0 - b.cos()) / b, 1.0 - b.sin() / b, b];
        let ns = [2usize, 4, 8, 16];
        let errs: Vec<Result<f64, mbs::SolveError>> = ns
            .iter()
            .map(|&n| {
                let (t, _) = try_elastica_tip(n, b, true)?;
                // The rotation sensor is a rotation vector (|.| <= pi): compare angles mod 2 pi.
                let e = (0..2).map(|i| (t[i] - exact[i]).abs()).fold(0.0, f64::max);
                let d = (t[2] - exact[2]).rem_euclid(2.0 * PI);
                Ok(e.max(d.min(2.0 * PI - d)))
            })
            .collect();
        println!("b = {b:.4}: {}", errs.iter().map(cell).collect::<String>());
        let e: Vec<f64> = errs[1..]
            .iter()
            .map(|e| *e.as_ref().expect("N >= 4 converges"))
            .collect();
        let s = slope(&[4.0, 8.0, 16.0], &e);
        assert!(s < -1.8, "b = {b}: slope {s}, errors {errs:?}");
    }
    // At b = 2 pi the beam closes into a circle: with N equal superelements the tip returns to
    // the clamp by symmetry (a regular polygon of exact constant-moment arcs), to round-off.
    for n in [4usize, 8, 16] {
        let (t, _) = try_elastica_tip(n, 2.0 * PI, true).expect("closes");
        println!(
            "b = 2 pi, N = {n}: tip at ({:.2e}, {:.2e}) from the clamp",
            1.0 - t[1],
            t[0]
        );
        assert!((1.0 - t[1]).abs() < 1e-9 && t[0].abs() < 1e-9, "{t:?}");
    }
}

/// Pendulum at 1 rad: theta(2 s) against a 1/6400 s reference for rho_inf = 0, 0.5, 0.8, 1.
#[test]
#[cfg_attr(debug_assertions, ignore = "release only: cargo test --release --test convergence")]
fn pendulum_time_step_order() {
    let run = |h: f64, rho: f64| {
        let (mut model, j) = pendulum(1.0, 1.0, 0.01);
        model.initial.push(InitialCondition::JointValue {
            joint: j,
            coordinate: 0,
            value: 1.0,
        });
        model.add_sensor(
            "theta",
            SensorKind::JointCoordinate {
                joint: j,
                coordinate: 0,
            },
        );
        let sys = System::new(&model).unwrap();
        let settings = DynamicSettings {
            tolerance: 1e-13,
            ..DynamicSettings::new(h, 2.0, rho)
        };
        *solve_dynamic(&sys, sys.initial_state(), &settings)
            .unwrap()
            .sensors
            .column("theta", 0)
            .unwrap()
            .last()
            .unwrap()
    };
    let hs = [2.0 / 50.0, 2.0 / 100.0, 2.0 / 200.0, 2.0 / 400.0, 2.0 / 800.0];
    for rho in [0.0, 0.5, 0.8, 1.0] {
        let reference = run(2.0 / 12800.0, rho);
        let errs: Vec<f64> = hs.iter().map(|&h| (run(h, rho) - reference).abs()).collect();
        let s = slope(&hs, &errs);
        println!(
            "pendulum rho_inf = {rho}: errors {}, order {s:.3}",
            errs.iter().map(|e| format!("{e:.2e} ")).collect::<String>()
        );
        assert!(s > 1.8, "rho_inf = {rho}: order {s}");
    }
}

/// C1: spin-up of the 10 m beam to 4, 6 and 10 rad/s (above the first clamped frequency,
/// 3.80 rad/s); the tip deflection in the hub's axes stays bounded and converges with the
/// number of superelements.
#[test]
#[cfg_attr(debug_assertions, ignore = "release only: cargo test --release --test convergence")]
fn spin_up_stays_bounded() {
    for omega in [4.0, 6.0, 10.0] {
        let mut peaks = Vec::new();
        let mut finals = Vec::new();
        for n in [2usize, 4, 8] {
            let model = spin_up(n, ModeSelection::Count(2), omega);
            let sys = System::new(&model).unwrap();
            let settings = DynamicSettings {
                output_every: 10,
                ..DynamicSettings::new(0.005, 30.0, 0.9)
            };
            let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
            let y = traj.sensors.column("tip", 1).unwrap();
            let peak = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let z = traj
                .sensors
                .column("tip", 2)
                .unwrap()
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(z < 1e-12, "out-of-plane motion {z}");
            let iters = traj.iterations.iter().sum::<usize>() as f64 / traj.iterations.len() as f64;
            println!("spin-up to {omega} rad/s, N = {n}: peak tip deflection {peak:.4} m, at 30 s {:.4} m ({iters:.2} iterations/step)", y.last().unwrap());
            peaks.push(peak);
            finals.push(*y.last().unwrap());
        }
        // Bounded: a model without geometric stiffening diverges above 3.8 rad/s.
        assert!(peaks.iter().all(|p| *p < 1.0), "{peaks:?}");
        // Refinement: N = 4 and 8 agree on the peak to a few percent.
        assert!((peaks[1] - peaks[2]).abs() < 0.05 * peaks[2] + 1e-3, "{peaks:?}");
    }
}

/// C1 after the spin-up: 100 s of steady rotation at 10 and 15 rad/s, N = 4 superelements
/// with two modes, h = 5 ms, with and without geometric stiffening, for rho_inf = 0.8, 0.9 and
/// 1 (no numerical damping); and N = 8 at 10 rad/s with rho_inf = 1, whose axial modes are the
/// stiffest of the set (omega h of about 40). The out-of-plane tip motion is zero in exact arithmetic; it must
/// stay at round-off, below 1e-9 m (a run that goes unstable grows from ~1e-20 m by a factor
/// 1000 every 2 s and passes 1e-9 m within 10 s of the onset; the stable runs stay below
/// 1e-18 m, so the bound has ten orders of margin on both sides).
///
/// This failed when the generalized-alpha recursion ran on spatial angular velocities
/// (module docs of `mbs::solvers::dynamic`, "Body axes"): the fixed-interface modes of the
/// 2.5 m segments (about 346 rad/s, omega h = 1.7) grew at 3.4 /s at 10 rad/s. With the
/// rotations in body axes and the translations still in fixed axes, N = 8 at rho_inf = 1 grew
/// an in-plane (axial) mode and stopped at t = 26.2 s; with the translations in body axes too
/// (`DynamicSettings::body_axis_translations`) it stays in plane for the 100 s.
#[test]
#[cfg_attr(debug_assertions, ignore = "release only: cargo test --release --test convergence")]
fn spin_up_steady_rotation_stays_in_plane() {
    let mut cases = Vec::new();
    for omega in [10.0, 15.0] {
        for stiffening in [false, true] {
            for rho in [0.8, 0.9, 1.0] {
                cases.push((4usize, omega, stiffening, rho));
            }
        }
    }
    cases.push((8, 10.0, false, 1.0));
    let results: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = cases
            .iter()
            .map(|&(n, omega, stiffening, rho)| {
                scope.spawn(move || {
                    let model = spin_up_with(n, ModeSelection::Count(2), omega, stiffening);
                    let sys = System::new(&model).unwrap();
                    let settings = DynamicSettings {
                        output_every: 10,
                        // N = 8 at rho_inf = 1 needs the translations in body axes too.
                        body_axis_translations: n == 8,
                        ..DynamicSettings::new(0.005, 100.0, rho)
                    };
                    let traj = solve_dynamic(&sys, sys.initial_state(), &settings)
                        .map_err(|e| format!("{} (after {} rows)", e.error, e.partial.sensors.times.len()))?;
                    let col = |c| traj.sensors.column("tip", c).unwrap();
                    let z = col(2).iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    let y = col(1);
                    Ok::<_, String>((z, y.last().copied().unwrap()))
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    println!("steady rotation, h = 5 ms, 100 s: max |z| of the tip (out of plane)");
    for ((n, omega, stiffening, rho), r) in cases.iter().zip(&results) {
        match r {
            Ok((z, y)) => println!(
                "  N = {n}, {omega:>4} rad/s, stiffening {stiffening:<5}, rho_inf {rho}: max |z| {z:.1e} m, y(100 s) {y:.5} m"
            ),
            Err(e) => println!("  N = {n}, {omega:>4} rad/s, stiffening {stiffening:<5}, rho_inf {rho}: failed: {e}"),
        }
    }
    for ((n, omega, stiffening, rho), r) in cases.iter().zip(&results) {
        let (z, _) = r
            .as_ref()
            .unwrap_or_else(|e| panic!("N = {n}, {omega} rad/s, {stiffening}, {rho}: {e}"));
        assert!(
            *z < 1e-9,
            "N = {n}, {omega} rad/s, stiffening {stiffening}, rho_inf {rho}: max |z| {z:e}"
        );
    }
}
