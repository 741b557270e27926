#![allow(non_snake_case)]

//! Mechanisms set up in study files: initial states that follow the joints, analyses that
//! start where another ended, actuators, springs and stops, buckling, adaptive and retried
//! time steps, each against an independent solution.

use std::path::PathBuf;
use study::observer::Recorder;
use study::output::Summary;
use study::run::Options;

/// `text` written as `<name>.toml` in a scratch folder, loaded, and run in memory.
fn run(name: &str, text: &str) -> (Recorder, Result<Summary, String>, PathBuf) {
    let dir = crate::scratch(name);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let study = study::load(&file).unwrap();
    let options = Options {
        out: Some(dir.join("results")),
        cache: Some(dir.join("cache")),
        t_end: None,
        foreign: Default::default(),
    };
    let mut rec = Recorder::default();
    let summary = study::run_with(&study, &options, &mut rec).map_err(|e| study::error::chain(&*e));
    (rec, summary, file)
}

fn column(rec: &Recorder, analysis: &str, sensor: &str, c: usize) -> Vec<f64> {
    rec.analysis(analysis)
        .unwrap()
        .sensors
        .as_ref()
        .unwrap()
        .column(sensor, c)
        .unwrap()
}

fn times(rec: &Recorder, analysis: &str) -> Vec<f64> {
    rec.analysis(analysis).unwrap().sensors.as_ref().unwrap().x.clone()
}

fn results(rec: &Recorder, analysis: &str) -> serde_json::Value {
    rec.analysis(analysis)
        .unwrap()
        .summary
        .as_ref()
        .unwrap()
        .results
        .clone()
}

/// The reduced body of the first flexible body of the study at `file` (mass data).
fn first_body(file: &std::path::Path) -> (reduction::ReducedBody, nalgebra::Isometry3<f64>) {
    let study = study::load(file).unwrap();
    let b = study::mechanism::build(&study, &file.parent().unwrap().join("cache"), &mut ()).unwrap();
    ((*b.bodies[0].reduced).clone(), b.bodies[0].placement)
}

/// The rigid double pendulum of two bodies of mass m, centre of mass at L/2, inertia I_c
/// about it, absolute angles from the downward vertical, by RK4 with step `h`: the angles at
/// the times `at`.
fn rigid_double_pendulum(m: f64, L: f64, Ic: f64, theta0: f64, at: &[f64], h: f64) -> Vec<[f64; 2]> {
    let g = 9.81;
    let d = L / 2.0;
    let f = |y: [f64; 4]| -> [f64; 4] {
        let (t1, t2, w1, w2) = (y[0], y[1], y[2], y[3]);
        let c = (t1 - t2).cos();
        let s = (t1 - t2).sin();
        let (a, b, e) = (m * d * d + Ic + m * L * L, m * L * d * c, m * d * d + Ic);
        let r1 = -m * L * d * s * w2 * w2 - (m * d + m * L) * g * t1.sin();
        let r2 = m * L * d * s * w1 * w1 - m * g * d * t2.sin();
        let det = a * e - b * b;
        [w1, w2, (e * r1 - b * r2) / det, (a * r2 - b * r1) / det]
    };
    let mut y = [theta0, theta0, 0.0, 0.0];
    let mut t = 0.0;
    let mut out = Vec::new();
    for &target in at {
        while t < target - 1e-12 {
            let hh = h.min(target - t);
            let add = |y: [f64; 4], k: [f64; 4], s: f64| std::array::from_fn::<f64, 4, _>(|i| y[i] + s * k[i]);
            let k1 = f(y);
            let k2 = f(add(y, k1, hh / 2.0));
            let k3 = f(add(y, k2, hh / 2.0));
            let k4 = f(add(y, k3, hh));
            y = std::array::from_fn(|i| y[i] + hh / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]));
            t += hh;
        }
        out.push([y[0], y[1]]);
    }
    out
}

#[test]
fn the_double_pendulum_example_with_stiff_links_follows_the_rigid_solution() {
    // The example with links a thousand times stiffer (the rigid limit), released from 30
    // degrees by its one [[initial]] line, for 1 s.
    let text = std::str::from_utf8(
        study::examples::EXAMPLES
            .iter()
            .find(|e| e.name == "double_pendulum")
            .unwrap()
            .files[0]
            .1,
    )
    .unwrap()
    .replace("E = 70e9", "E = 70e12")
    .replace("t_end = 2.0", "t_end = 1.0")
    .replace("vtu_every = 10", "every = 10");
    let (rec, summary, file) = run("double-pendulum", &text);
    summary.unwrap();
    let (body, _) = first_body(&file);
    let m = body.inertia.mass;
    let Ic = body.inertia.inertia_com[2][2];
    let t = times(&rec, "dynamic");
    let rigid = rigid_double_pendulum(m, 0.5, Ic, 30f64.to_radians(), &t, 1e-4);
    let tip = [column(&rec, "dynamic", "tip", 0), column(&rec, "dynamic", "tip", 1)];
    let mut worst: f64 = 0.0;
    for (k, [t1, t2]) in rigid.iter().enumerate() {
        let x = 0.5 * (t1.sin() + t2.sin());
        let y = -0.5 * (t1.cos() + t2.cos());
        worst = worst.max(((tip[0][k] - x).powi(2) + (tip[1][k] - y).powi(2)).sqrt());
    }
    let energy: Vec<f64> = (0..t.len())
        .map(|k| (0..3).map(|c| column(&rec, "dynamic", "energy", c)[k]).sum())
        .collect();
    let kinetic = column(&rec, "dynamic", "energy", 0);
    let scale = kinetic.iter().copied().fold(0.0, f64::max);
    let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max) / scale;
    eprintln!("tip within {worst:.3e} m of the rigid solution over 1 s; energy drift {drift:.3e} of the largest kinetic energy {scale:.4} J");
    // The issue's bounds: 1 mm, and 1e-4 of the energy of the motion (generalized-alpha with
    // rho_inf = 0.9 and 1 ms steps dissipates O(h^2) of it at the pendulum's 0.7 Hz).
    assert!(worst < 1e-3, "{worst}");
    assert!(drift < 1e-4, "{drift}");
}

#[test]
fn one_initial_line_spins_a_free_flexible_body_rigidly() {
    let text = r#"
[[materials]]
name = "steel"
E = 210e9
nu = 0.3
rho = 7850.0
[[sections]]
name = "bar"
shape = "rectangle"
b = 0.02
h = 0.03
[[parts]]
name = "bar"
material = "steel"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [0.6, 0.0, 0.0]
elements = 8
section = "bar"
[[parts.interfaces]]
name = "a"
set = "bar.start"
[[parts.interfaces]]
name = "b"
set = "bar.end"
[parts.reduction]
modes = 3
[[bodies]]
name = "bar"
part = "bar"
position = [0.1, 0.2, 0.3]
[[initial]]
body = "bar"
velocity = [0.3, -0.2, 0.1]
angular_velocity = [0.4, -1.5, 6.0]
point = [0.2, 0.1, 0.0]
[[sensors]]
name = "energy"
type = "energy"
[[analyses]]
type = "dynamic"
t_end = 1e-3
dt = 1e-3
"#;
    let (rec, summary, file) = run("free-spin", text);
    summary.unwrap();
    let (body, place) = first_body(&file);
    let (v, w, p) = (
        nalgebra::Vector3::new(0.3, -0.2, 0.1),
        nalgebra::Vector3::new(0.4, -1.5, 6.0),
        nalgebra::Vector3::new(0.2, 0.1, 0.0),
    );
    let c = place * nalgebra::Point3::from(nalgebra::Vector3::from(body.inertia.center_of_mass));
    let vc = v + w.cross(&(c.coords - p));
    let I = nalgebra::Matrix3::from_fn(|i, j| body.inertia.inertia_com[i][j]);
    let T = 0.5 * body.inertia.mass * vc.norm_squared() + 0.5 * w.dot(&(I * w));
    let kinetic = column(&rec, "dynamic", "energy", 0)[0];
    eprintln!("kinetic energy {kinetic:.15e} J, rigid motion {T:.15e} J");
    // Round-off of the mass-matrix products (the issue's bound, 1e-10).
    assert!((kinetic - T).abs() < 1e-10 * T, "{kinetic} vs {T}");
    assert!(
        column(&rec, "dynamic", "energy", 1)[0].abs() < 1e-12,
        "no strain at the start"
    );
}

/// A cantilever of four superelements (aluminium, 1 m, 10 mm square) under gravity.
const CANTILEVER: &str = r#"
[[materials]]
name = "aluminium"
E = 70e9
nu = 0.33
rho = 2700.0
[[sections]]
name = "bar"
shape = "rectangle"
b = 0.01
h = 0.01
[[parts]]
name = "segment"
material = "aluminium"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [0.25, 0.0, 0.0]
elements = 4
section = "bar"
theory = "euler-bernoulli"
[[parts.interfaces]]
name = "a"
set = "segment.start"
[[parts.interfaces]]
name = "b"
set = "segment.end"
[parts.reduction]
modes = 2
[[bodies]]
name = "s0"
part = "segment"
[[bodies]]
name = "s1"
part = "segment"
position = [0.25, 0.0, 0.0]
[[bodies]]
name = "s2"
part = "segment"
position = [0.5, 0.0, 0.0]
[[bodies]]
name = "s3"
part = "segment"
position = [0.75, 0.0, 0.0]
[[joints]]
name = "w1"
type = "fixed"
between = ["s0.b", "s1.a"]
[[joints]]
name = "w2"
type = "fixed"
between = ["s1.b", "s2.a"]
[[joints]]
name = "w3"
type = "fixed"
between = ["s2.b", "s3.a"]
[[supports]]
at = "s0.a"
type = "clamp"
[[loads]]
name = "weight"
type = "gravity"
g = [0.0, -9.81, 0.0]
[[sensors]]
name = "tip"
type = "position"
of = "s3.b"
"#;

#[test]
fn a_cantilever_started_from_its_equilibrium_stays_there() {
    let text = format!(
        "{CANTILEVER}
[[analyses]]
type = \"equilibrium\"
name = \"sag\"
tolerance = 1e-13
[[analyses]]
type = \"dynamic\"
name = \"from-sag\"
start = \"sag\"
t_end = 0.2
dt = 1e-3
[[analyses]]
type = \"dynamic\"
name = \"from-rest\"
t_end = 0.2
dt = 1e-3
"
    );
    let (rec, summary, _) = run("hanging", &text);
    summary.unwrap();
    let y_eq = *column(&rec, "sag", "tip", 1).last().unwrap();
    let drift = column(&rec, "from-sag", "tip", 1)
        .iter()
        .map(|y| (y - y_eq).abs())
        .fold(0.0, f64::max);
    eprintln!("static tip {y_eq:.6e} m; drift from it {drift:.3e} m");
    // The issue's bound, 1e-9 m.
    assert!(drift < 1e-9, "{drift}");
    // Without `start` gravity arrives as a step: the tip overshoots the sag by far.
    let lowest = column(&rec, "from-rest", "tip", 1).into_iter().fold(0.0, f64::min);
    assert!(lowest < 1.5 * y_eq, "{lowest} vs {y_eq}");
}

#[test]
fn an_euler_column_of_eight_superelements_buckles_at_eulers_load() {
    // Steel, 10 mm square, 1 m, clamped-free; eight superelements of static modes only.
    let (E, a, L): (f64, f64, f64) = (2.1e11, 0.01, 1.0);
    let p_euler = std::f64::consts::PI.powi(2) * E * a.powi(4) / 12.0 / (4.0 * L * L);
    let mut text = String::from(
        r#"
[[materials]]
name = "steel"
E = 2.1e11
nu = 0.3
rho = 7800.0
[[sections]]
name = "bar"
shape = "rectangle"
b = 0.01
h = 0.01
[[parts]]
name = "segment"
material = "steel"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [0.125, 0.0, 0.0]
elements = 2
section = "bar"
theory = "euler-bernoulli"
[[parts.interfaces]]
name = "a"
set = "segment.start"
[[parts.interfaces]]
name = "b"
set = "segment.end"
[parts.reduction]
modes = 0
[[supports]]
at = "s0.a"
type = "clamp"
"#,
    );
    for i in 0..8 {
        text += &format!(
            "[[bodies]]\nname = \"s{i}\"\npart = \"segment\"\nposition = [{}, 0.0, 0.0]\n",
            0.125 * i as f64
        );
        if i > 0 {
            text += &format!(
                "[[joints]]\nname = \"w{i}\"\ntype = \"fixed\"\nbetween = [\"s{}.b\", \"s{i}.a\"]\n",
                i - 1
            );
        }
    }
    let with_load = |factor: f64| {
        format!(
            "{text}[[loads]]\nname = \"push\"\ntype = \"point\"\nat = \"s7.b\"\nforce = [{}, 0.0, 0.0]\n[[analyses]]\ntype = \"buckling\"\nmodes = 2\n",
            -factor * p_euler
        )
    };
    let (rec, summary, _) = run("euler-column", &with_load(0.1));
    summary.unwrap();
    let r = results(&rec, "buckling");
    let p_cr = r["load_factors"][0].as_f64().unwrap() * 0.1 * p_euler;
    let err = (p_cr - p_euler) / p_euler;
    eprintln!("P_cr = {p_cr:.5} N, Euler {p_euler:.5} N: error {err:.3e}");
    // The issue's bound, 0.5 %: eight chord-like superelements are 0.3 % above (1/N^2).
    assert!(err.abs() < 5e-3, "{err}");
    assert_eq!(r["past_critical_point"], serde_json::json!(false));
    let frames = &rec.analysis("buckling").unwrap().frames;
    assert_eq!(frames.len(), 2, "a mode shape per load factor");
    // Loaded beyond its critical load, the straight column is reported past it.
    let (rec, summary, _) = run("euler-column-over", &with_load(1.3));
    summary.unwrap();
    let s = rec.analysis("buckling").unwrap().summary.clone().unwrap();
    assert_eq!(
        s.results["past_critical_point"],
        serde_json::json!(true),
        "{:?}",
        s.report
    );
    assert!(
        s.report.iter().any(|l| l.contains("past a critical point")),
        "{:?}",
        s.report
    );
}

/// A rigid pendulum: 1 kg, centre of mass 1 m below the pivot, 0.01 kg m^2 about it (1.01
/// kg m^2 about the pivot).
const PENDULUM: &str = r#"
[[rigid_bodies]]
name = "bob"
mass = 1.0
center_of_mass = [0.0, -1.0, 0.0]
inertia = [[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]]
points = { O = [0.0, 0.0, 0.0] }
[[joints]]
name = "pivot"
type = "revolute"
between = ["ground", "bob.O"]
axis = [0.0, 0.0, 1.0]
[[sensors]]
name = "angle"
type = "joint"
of = "pivot"
"#;

#[test]
fn a_pid_actuator_in_a_study_holds_its_set_point() {
    let text = format!(
        "{PENDULUM}
[[loads]]
name = \"weight\"
type = \"gravity\"
g = [0.0, -9.81, 0.0]
[[actuators]]
name = \"motor\"
joint = \"pivot\"
pid = {{ kp = 50.0, ki = 200.0, kd = 10.0, sensor = \"angle\", setpoint = {{ type = \"ramp\", t_end = 1.0, to = 0.5 }} }}
[[sensors]]
name = \"torque\"
type = \"actuator-effort\"
of = \"motor\"
[[analyses]]
type = \"dynamic\"
t_end = 10.0
dt = 0.01
[output]
every = 10
"
    );
    let (rec, summary, _) = run("pid", &text);
    summary.unwrap();
    let angle = *column(&rec, "dynamic", "angle", 0).last().unwrap();
    let torque = *column(&rec, "dynamic", "torque", 0).last().unwrap();
    eprintln!("angle {angle:.10} rad, torque {torque:.6} N m");
    // The integral term removes the steady error under gravity (closed-loop poles below
    // -2.6 1/s: e^-24 of the error is left after the 9 s past the ramp).
    assert!((angle - 0.5).abs() < 1e-6, "{angle}");
    assert!((torque - 9.81 * 0.5f64.sin()).abs() < 1e-4, "{torque}");
}

#[test]
fn a_torsional_spring_damper_in_a_study_has_the_analytic_damped_frequency() {
    let text = format!(
        "{PENDULUM}
[[joint_springs]]
name = \"torsion\"
joint = \"pivot\"
stiffness = 4.0
damping = 0.2
[[analyses]]
type = \"linearized\"
modes = 1
"
    );
    let (rec, summary, _) = run("torsion", &text);
    summary.unwrap();
    let ss = rec
        .analysis("linearized")
        .unwrap()
        .tables
        .iter()
        .find(|t| t.name == "state_space")
        .unwrap();
    let (re, im) = (ss.column(1)[0], ss.column(2)[0]);
    let (k, c, I): (f64, f64, f64) = (4.0, 0.2, 1.01);
    let wd = (k / I - (c / (2.0 * I)).powi(2)).sqrt();
    eprintln!(
        "damped frequency {im:.10} rad/s (analytic {wd:.10}), decay {re:.10} (analytic {:.10})",
        -c / (2.0 * I)
    );
    // The issue's bound, 1e-4 (the eigensolver gives round-off).
    assert!((im - wd).abs() < 1e-4 * wd && (re + c / (2.0 * I)).abs() < 1e-4 * c / (2.0 * I));
}

/// The pendulum released from 1.2 rad onto a stop at -0.5 rad.
fn stopped_pendulum(extra: &str) -> String {
    format!(
        "{PENDULUM}
[[loads]]
name = \"weight\"
type = \"gravity\"
g = [0.0, -9.81, 0.0]
[[initial]]
joint = \"pivot\"
value = 1.2
[[joint_limits]]
name = \"stop\"
joint = \"pivot\"
lower = -0.5
stiffness = 1e5
damping = 50.0
[[analyses]]
type = \"dynamic\"
t_end = 1.5
dt = 5e-3
{extra}
"
    )
}

#[test]
fn a_joint_limit_in_a_study_stops_the_pendulum() {
    let (rec, summary, _) = run("stop", &stopped_pendulum(""));
    summary.unwrap();
    let angle = column(&rec, "dynamic", "angle", 0);
    let lowest = angle.iter().copied().fold(f64::INFINITY, f64::min);
    eprintln!("lowest {lowest:.5} rad");
    // m g d (cos 0.5 - cos 1.2) = 5.05 J into 1e5 N m/rad: 0.010 rad at most.
    assert!(lowest > -0.511 && lowest < -0.5, "{lowest}");
    assert_eq!(results(&rec, "dynamic")["retried_steps"], serde_json::json!(0));
}

#[test]
fn a_failed_fixed_step_is_retried_and_the_summary_says_so() {
    // One Newton correction per step: enough for the free swing, not for the steps that hit
    // the stop. With dt_min = dt nothing can be retried and the run stops there.
    let (_, summary, _) = run("no-retry", &stopped_pendulum("max_iterations = 1\ndt_min = 5e-3"));
    let e = summary.unwrap_err();
    assert!(e.contains("Newton did not converge"), "{e}");
    let (rec, summary, _) = run("retry", &stopped_pendulum("max_iterations = 1"));
    summary.unwrap();
    let s = rec.analysis("dynamic").unwrap().summary.clone().unwrap();
    let retried = s.results["retried_steps"].as_u64().unwrap();
    eprintln!("{}", s.report.join("\n"));
    assert!(retried > 0);
    assert!(s.report.iter().any(|l| l.contains("retried with halved steps")));
    let lowest = column(&rec, "dynamic", "angle", 0)
        .into_iter()
        .fold(f64::INFINITY, f64::min);
    assert!(lowest > -0.511, "{lowest}");
}

#[test]
fn adaptive_steps_match_the_fixed_step_on_the_slider_crank_with_fewer_steps() {
    // The slider-crank example for 1.5 crank turns: the rod's midpoint deflection and the
    // slider at the end time against a run with a quarter of the example's step.
    let base = std::str::from_utf8(
        study::examples::EXAMPLES
            .iter()
            .find(|e| e.name == "slider_crank")
            .unwrap()
            .files[0]
            .1,
    )
    .unwrap()
    .replace("t_end = 0.126    # three revolutions", "t_end = 0.063")
    .replace("vtu_every = 20", "");
    let end = |name: &str, dynamic: &str| {
        let text = base.replace("dt = 1e-4\nrho_inf = 0.9", dynamic);
        let (rec, summary, _) = run(name, &text);
        summary.unwrap();
        let r = results(&rec, "run-up");
        (
            *column(&rec, "run-up", "rod-mid", 0).last().unwrap(),
            *column(&rec, "run-up", "slider", 0).last().unwrap(),
            r["steps"].as_u64().unwrap(),
        )
    };
    let (d_ref, s_ref, _) = end("sc-ref", "dt = 2.5e-5\nrho_inf = 0.9");
    let (d_fix, s_fix, n_fix) = end("sc-fixed", "dt = 1e-4\nrho_inf = 0.9");
    let e_fix = (d_fix - d_ref).abs();
    eprintln!(
        "fixed: {n_fix} steps, deflection error {e_fix:.3e} m, slider error {:.3e} m",
        (s_fix - s_ref).abs()
    );
    let (d, s, n) = end(
        "sc-adaptive",
        "dt = 1e-4\nrho_inf = 0.9\nerror_tolerance = 1e-4\ndt_max = 1e-3",
    );
    let (e_d, e_s) = ((d - d_ref).abs(), (s - s_ref).abs());
    eprintln!("adaptive: {n} steps, deflection error {e_d:.3e} m, slider error {e_s:.3e} m");
    // Measured: 630 fixed steps give 1.04e-5 m on the deflection and 1.03e-5 m on the slider;
    // 567 adaptive steps 1.60e-5 and 3.1e-6 m. The crank turns at constant speed, so the
    // motion keeps one pace and the adaptive step settles near the fixed one: the same
    // accuracy (within a factor 2 on each quantity) with 10 % fewer steps, no more.
    assert!(n < n_fix, "{n} adaptive steps against {n_fix} fixed");
    assert!(e_d < 2.0 * e_fix && e_s < 2.0 * (s_fix - s_ref).abs(), "{e_d}, {e_s}");
}
