//! Convergence studies (slow; run with `cargo test --release --test convergence -- --nocapture`).
//! Each prints its table; the asserts check the rates the method can honestly reach.

#![allow(non_snake_case)]

#[path = "unit/fixtures.rs"]
mod fixtures;

use fixtures::{elastica_tip, pendulum, spin_up, ELASTICA};
use mbs::{solve_dynamic, DynamicSettings, InitialCondition, SensorKind, System};
use reduction::ModeSelection;

/// Least-squares slope of log(err) against log(x).
fn slope(x: &[f64], err: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = x.iter().zip(err).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum::<f64>() / lx.iter().map(|a| (a - mx) * (a - mx)).sum::<f64>()
}

/// B1: every load of the table with N = 1..16 superelements; the error of (w/L, u/L,
/// rotation) falls as 1/N^2 until the table's five digits.
#[test]
fn elastica_all_loads() {
    let ns = [1usize, 2, 4, 8, 16];
    println!("elastica: max |error| of (w/L, u/L, tip rotation) against Mattiasson (1981)");
    println!("{:>5} {}", "a", ns.iter().map(|n| format!("{:>10}", format!("N = {n}"))).collect::<String>());
    for &(a, reference) in &ELASTICA {
        let errs: Vec<f64> = ns
            .iter()
            .map(|&n| {
                let (t, _) = elastica_tip(n, a, false);
                (0..3).map(|i| (t[i] - reference[i]).abs()).fold(0.0, f64::max)
            })
            .collect();
        println!("{a:>5} {}", errs.iter().map(|e| format!("{e:>10.2e}")).collect::<String>());
        // From N = 2 to 8 the ratio per halving is ~4 (second order); at N = 16 the error of a =
        // 1..3 meets the table's rounding (5e-6), so only N <= 8 enters the fitted slope.
        let s = slope(&[2.0, 4.0, 8.0], &errs[1..4]);
        assert!(s < -1.8, "a = {a}: slope {s}, errors {errs:?}");
    }
}

/// B2: the roll-up to b = pi/2, pi and 2 pi (closed circle) with N = 2..16.
#[test]
fn roll_up_to_the_circle() {
    use std::f64::consts::PI;
    println!("roll-up: max |error| of (w/L, u/L, rotation) against the arc");
    for b in [PI / 2.0, PI, 2.0 * PI] {
        let exact = [(1.0 - b.cos()) / b, 1.0 - b.sin() / b, b];
        let ns = [2usize, 4, 8, 16];
        let errs: Vec<f64> = ns
            .iter()
            .map(|&n| {
                let (t, _) = elastica_tip(n, b, true);
                // The rotation sensor is a rotation vector (|.| <= pi): compare angles mod 2 pi.
                let mut e = (0..2).map(|i| (t[i] - exact[i]).abs()).fold(0.0, f64::max);
                let d = (t[2] - exact[2]).rem_euclid(2.0 * PI);
                e = e.max(d.min(2.0 * PI - d));
                e
            })
            .collect();
        println!("b = {b:.4}: {}", errs.iter().map(|e| format!("{e:>10.2e}")).collect::<String>());
        let s = slope(&[2.0, 4.0, 8.0, 16.0], &errs);
        assert!(s < -1.8, "b = {b}: slope {s}, errors {errs:?}");
    }
}

/// Pendulum at 1 rad: theta(2 s) against a 1/6400 s reference for rho_inf = 0, 0.5, 0.8, 1.
#[test]
fn pendulum_time_step_order() {
    let run = |h: f64, rho: f64| {
        let (mut model, j) = pendulum(1.0, 1.0, 0.01);
        model.initial.push(InitialCondition::JointValue { joint: j, coordinate: 0, value: 1.0 });
        model.add_sensor("theta", SensorKind::JointCoordinate { joint: j, coordinate: 0 });
        let sys = System::new(&model).unwrap();
        let settings = DynamicSettings { tolerance: 1e-13, ..DynamicSettings::new(h, 2.0, rho) };
        *solve_dynamic(&sys, sys.initial_state(), &settings).unwrap().sensors.column("theta", 0).unwrap().last().unwrap()
    };
    let hs = [2.0 / 50.0, 2.0 / 100.0, 2.0 / 200.0, 2.0 / 400.0, 2.0 / 800.0];
    for rho in [0.0, 0.5, 0.8, 1.0] {
        let reference = run(2.0 / 12800.0, rho);
        let errs: Vec<f64> = hs.iter().map(|&h| (run(h, rho) - reference).abs()).collect();
        let s = slope(&hs, &errs);
        println!("pendulum rho_inf = {rho}: errors {}, order {s:.3}", errs.iter().map(|e| format!("{e:.2e} ")).collect::<String>());
        assert!(s > 1.8, "rho_inf = {rho}: order {s}");
    }
}

/// C1: spin-up of the 10 m beam to 4, 6 and 10 rad/s (above the first clamped frequency,
/// 3.80 rad/s); the tip deflection in the hub's axes stays bounded and converges with the
/// number of superelements.
#[test]
fn spin_up_stays_bounded() {
    for omega in [4.0, 6.0, 10.0] {
        let mut peaks = Vec::new();
        let mut finals = Vec::new();
        for n in [2usize, 4, 8] {
            let model = spin_up(n, ModeSelection::Count(2), omega);
            let sys = System::new(&model).unwrap();
            let settings = DynamicSettings { output_every: 10, ..DynamicSettings::new(0.005, 30.0, 0.9) };
            let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
            let y = traj.sensors.column("tip", 1).unwrap();
            let peak = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
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
