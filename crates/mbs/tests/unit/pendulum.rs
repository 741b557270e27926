//! Rigid pendulum on a revolute joint under gravity.

use crate::fixtures::{pendulum, released};
use mbs::{solve_dynamic, DynamicSettings, InitialCondition, SensorKind, System};
use std::f64::consts::PI;

const G: f64 = 9.81;

/// Complete elliptic integral of the first kind, $K(k) = \pi/(2\,\mathrm{AGM}(1, \sqrt{1-k^2}))$.
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        let (an, bn) = (0.5 * (a + b), (a * b).sqrt());
        a = an;
        b = bn;
    }
    PI / (2.0 * a)
}

/// Angle history of the pendulum released from rest at `theta0`.
fn run(theta0: f64, h: f64, end: f64, rho: f64) -> (Vec<f64>, Vec<f64>) {
    let sys = released(theta0);
    let mut settings = DynamicSettings::new(h, end, rho);
    settings.tolerance = 1e-12;
    let traj = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap();
    (traj.sensors.times.clone(), traj.sensors.column("theta", 0).unwrap())
}

/// Times of the downward zero crossings of theta (linear interpolation: theta'' = 0 at theta
/// = 0, so its error is third order in the step).
fn down_crossings(t: &[f64], x: &[f64]) -> Vec<f64> {
    (1..x.len())
        .filter(|&i| x[i - 1] > 0.0 && x[i] <= 0.0)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * x[i - 1] / (x[i - 1] - x[i]))
        .collect()
}

/// I_O / (m g d) of the fixture pendulum (m = 1, d = 1, I_G = 0.01).
fn ratio() -> f64 {
    (0.01 + 1.0) / G
}

#[test]
fn small_amplitude_period() {
    let T0 = 2.0 * PI * ratio().sqrt();
    let (t, x) = run(1e-3, T0 / 400.0, 2.6 * T0, 1.0);
    let c = down_crossings(&t, &x);
    let T = c[1] - c[0];
    // Generalized-alpha (rho_inf = 1, trapezoidal) lengthens the period by (w h)^2/12 = 2.1e-5
    // at 400 steps per period; the finite-amplitude correction theta0^2/16 is 6e-8.
    let rel = (T - T0).abs() / T0;
    eprintln!("small amplitude: T = {T:.9}, exact {T0:.9}, relative error {rel:.3e}");
    assert!(rel < 5e-5, "period {T} vs {T0}");
}

#[test]
fn large_amplitude_period_is_the_elliptic_one() {
    let theta0: f64 = 2.0;
    let T = 4.0 * ratio().sqrt() * elliptic_k((theta0 / 2.0).sin());
    let (t, x) = run(theta0, T / 1000.0, 2.6 * T, 1.0);
    let c = down_crossings(&t, &x);
    let Tn = c[1] - c[0];
    let rel = (Tn - T).abs() / T;
    eprintln!("amplitude 2 rad: T = {Tn:.9}, elliptic {T:.9}, relative error {rel:.3e}");
    // Period error of the trapezoidal rule at 1000 steps per period: ~(2 pi / 1000)^2 / 12 =
    // 3e-6 for the linear part; the nonlinear motion is slower near the top, so allow 2e-5.
    assert!(rel < 2e-5);
}

#[test]
fn second_order_in_time() {
    // theta(1 s) from rest at 1 rad with rho_inf = 0.8, against a reference at h = 1/3200.
    let end = 1.0;
    let last = |h: f64| *run(1.0, h, end, 0.8).1.last().unwrap();
    let reference = last(end / 3200.0);
    let hs = [end / 25.0, end / 50.0, end / 100.0, end / 200.0];
    let errs: Vec<f64> = hs.iter().map(|&h| (last(h) - reference).abs()).collect();
    let (lx, ly): (Vec<f64>, Vec<f64>) = hs.iter().zip(&errs).map(|(h, e)| (h.ln(), e.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / 4.0, ly.iter().sum::<f64>() / 4.0);
    let slope = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum::<f64>()
        / lx.iter().map(|x| (x - mx) * (x - mx)).sum::<f64>();
    eprintln!("errors {errs:?}, fitted order {slope:.3}");
    assert!(slope >= 1.8, "order {slope}");
}

#[test]
fn driver_effort_is_the_inverse_dynamics_torque() {
    // A driven pendulum: the driver supplies I_O theta'' + m g d sin(theta) (about z).
    let (mut model, j) = pendulum(1.0, 1.0, 0.01);
    let (a, w) = (0.8, 2.5);
    let d = model.add_driver(
        "drive",
        mbs::DriverTarget::Joint {
            joint: j,
            coordinate: 0,
        },
        mbs::TimeFunction::Sine {
            offset: 0.0,
            amplitude: a,
            omega: w,
            phase: 0.3,
        },
    );
    model.add_sensor("torque", SensorKind::DriverEffort { driver: d });
    let sys = System::new(&model).unwrap();
    let traj = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(0.01, 1.0, 0.8)).unwrap();
    let torque = traj.sensors.column("torque", 0).unwrap();
    for (t, q) in traj.sensors.times.iter().zip(&torque) {
        let th = a * (w * t + 0.3).sin();
        let thdd = -a * w * w * (w * t + 0.3).sin();
        let exact = 1.01 * thdd + G * th.sin();
        // No unknowns: the effort is evaluated exactly at each step (round-off only).
        assert!(
            (q - exact).abs() < 1e-10 * (1.0 + exact.abs()),
            "t = {t}: {q} vs {exact}"
        );
    }
}

#[test]
fn a_failed_step_returns_the_history_so_far() {
    // One Newton iteration allowed and a tolerance below round-off: the first step cannot
    // converge; the error says where, and the initial sensors come back with it.
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
        max_iterations: 1,
        tolerance: 1e-30,
        ..DynamicSettings::new(0.01, 1.0, 0.8)
    };
    let err = solve_dynamic(&sys, sys.initial_state(), &settings).unwrap_err();
    match err.error {
        mbs::SolveError::NotConverged {
            step,
            iterations,
            at: mbs::At::Time(t),
            ..
        } => {
            assert_eq!((step, iterations), (1, 1));
            assert!((t - 0.01).abs() < 1e-15);
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(err.partial.sensors.times, vec![0.0]);
    assert_eq!(err.partial.final_state.time(), 0.0);
    eprintln!("{err}");
}

/// The pendulum released from 2 rad, integrated to `end` with the adaptive step at local
/// tolerance `tol`: (times, angles).
fn run_adaptive(tol: f64, end: f64) -> (Vec<f64>, Vec<f64>) {
    let sys = released(2.0);
    let mut settings = DynamicSettings::new(1e-3, end, 1.0);
    settings.tolerance = 1e-12;
    let adaptive = mbs::AdaptiveSettings::new(tol, 1e-6, 0.1);
    let traj = mbs::solve_dynamic_adaptive(&sys, sys.initial_state(), &settings, &adaptive).unwrap();
    (traj.sensors.times.clone(), traj.sensors.column("theta", 0).unwrap())
}

#[test]
fn adaptive_step_meets_the_tolerance_and_shrinks_where_the_motion_is_fast() {
    let theta0: f64 = 2.0;
    let T = 4.0 * ratio().sqrt() * elliptic_k((theta0 / 2.0).sin());
    let end = 1.3 * T;
    // Reference: fixed steps T/4000 and T/8000, Richardson-extrapolated (second order).
    let n = (end / (T / 4000.0)).round();
    let (_, x1) = run(theta0, end / n, end, 1.0);
    let (_, x2) = run(theta0, end / (2.0 * n), end, 1.0);
    let reference = x2.last().unwrap() + (x2.last().unwrap() - x1.last().unwrap()) / 3.0;
    let mut errors = Vec::new();
    for tol in [1e-5, 1e-7] {
        let (t, x) = run_adaptive(tol, end);
        assert!((t.last().unwrap() - end).abs() < 1e-12, "ends at {}", t.last().unwrap());
        let err = (x.last().unwrap() - reference).abs();
        // Step sizes near the bottom (|theta| < 0.3, fastest: the largest jerk, theta' cos
        // theta) and near the turning points (|theta| > 1.8, theta' -> 0).
        let mean = |keep: &dyn Fn(f64) -> bool| {
            let h: Vec<f64> = (1..t.len() - 1)
                .filter(|&i| keep(x[i]))
                .map(|i| t[i + 1] - t[i])
                .collect();
            h.iter().sum::<f64>() / h.len() as f64
        };
        let (h_bottom, h_top) = (mean(&|th: f64| th.abs() < 0.3), mean(&|th: f64| th.abs() > 1.8));
        eprintln!(
            "tol {tol:.0e}: {} steps, final error {err:.2e}, mean h at the bottom {h_bottom:.2e}, at the turning points {h_top:.2e}",
            t.len() - 1
        );
        assert!(h_bottom < 0.7 * h_top, "{h_bottom} vs {h_top}");
        errors.push((err, t.len() - 1));
    }
    // A local error per step of tol over ~tol^(-1/3) steps: the global error falls like
    // tol^(2/3), a factor 21 for 100 times tighter (measured 18 with the plain (tol/e)^(1/3)
    // step rule, 6 with the PI controller: 1.8e-4 and 3.0e-5 rad; the end-time error is one
    // sample of a phase error, so a factor 4 is asserted), and stays below the sum of the
    // local tolerances (steps x tol: the errors add up, mostly as a phase error).
    assert!(errors[0].0 / errors[1].0 > 4.0, "{errors:?}");
    for (&(err, steps), tol) in errors.iter().zip([1e-5, 1e-7]) {
        assert!(err < steps as f64 * tol, "{errors:?}");
    }
    assert!(errors[1].1 > 3 * errors[0].1, "{errors:?}");
}

/// Output times are the step grid, not a sum of rounded steps: 6000 steps of 0.005 s end at
/// 30 exactly (adding 0.005 6000 times gives 29.999999999998316), and every time is the
/// decimal k h.
#[test]
fn output_times_do_not_drift() {
    let sys = released(0.3);
    let run = solve_dynamic(&sys, sys.initial_state(), &DynamicSettings::new(0.005, 30.0, 0.9)).unwrap();
    let times = &run.sensors.times;
    assert_eq!(times.len(), 6001);
    for (k, t) in times.iter().enumerate() {
        let grid: f64 = format!("{:.3}", k as f64 * 0.005).parse().unwrap();
        assert_eq!(*t, grid, "step {k}");
    }
    assert_eq!(*times.last().unwrap(), 30.0);
    // A step without a short decimal form is left as computed (no rounding to a coarser grid).
    let h = 1.0 / 3.0;
    assert_eq!(mbs::dynamic_solver::step_end_time(0.0, h), h);
    assert_eq!(mbs::dynamic_solver::step_end_time(h, h), h + h);
}
