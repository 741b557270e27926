#![allow(non_snake_case)]

//! Mechanisms set up in study files: initial states that follow the joints, analyses that
//! start where another ended, actuators, springs and stops, buckling, adaptive and retried
//! time steps, a reduction's inertia correction, each against an independent solution.

use crate::common::{
    clamp, dynamic, equilibrium, gravity, linearized, material, named_dynamic, pendulum, rectangle, rigid_body, sensor,
    two_ended_beam, welded_chain, Text,
};
use std::path::PathBuf;
use study::output::observer::Recorder;
use study::output::summary::Summary;
use study::Options;

/// `text` written as `<name>.toml` in a scratch folder, loaded, and run in memory.
pub(crate) fn run(name: &str, text: &str) -> (Recorder, Result<Summary, String>, PathBuf) {
    let dir = crate::scratch(name);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let study = study::load(&file).unwrap();
    let options = crate::options_in(&dir, None);
    let mut rec = Recorder::default();
    let summary = study::run_with(&study, &options, &mut rec).map_err(|e| study::error::chain(&*e));
    (rec, summary, file)
}

pub(crate) fn column(rec: &Recorder, analysis: &str, sensor: &str, c: usize) -> Vec<f64> {
    rec.analysis(analysis)
        .unwrap()
        .sensors
        .as_ref()
        .unwrap()
        .column(sensor, c)
        .unwrap()
}

pub(crate) fn times(rec: &Recorder, analysis: &str) -> Vec<f64> {
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
pub(crate) fn first_body(file: &std::path::Path) -> (reduction::ReducedBody, nalgebra::Isometry3<f64>) {
    let study = study::load(file).unwrap();
    let b = study::build_mechanism(&study, &file.parent().unwrap().join("cache"), &mut ()).unwrap();
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
        study::input::examples::EXAMPLES
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
    // The required bounds: 1 mm, and 1e-4 of the energy of the motion (generalized-alpha with
    // rho_inf = 0.9 and 1 ms steps dissipates O(h^2) of it at the pendulum's 0.7 Hz).
    assert!(worst < 1e-3, "{worst}");
    assert!(drift < 1e-4, "{drift}");
}

#[test]
fn one_initial_line_spins_a_free_flexible_body_rigidly() {
    let text = [
        material("steel", 210e9, 0.3, 7850.0),
        rectangle("bar", 0.02, 0.03),
        two_ended_beam("bar", "steel", "bar", 0.6, 8, None, 3),
        r#"[[bodies]]
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
"#
        .to_string(),
        dynamic("1e-3", "1e-3"),
    ]
    .concat();
    let (rec, summary, file) = run("free-spin", &text);
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
    // Round-off of the mass-matrix products (the required bound, 1e-10).
    assert!((kinetic - T).abs() < 1e-10 * T, "{kinetic} vs {T}");
    assert!(
        column(&rec, "dynamic", "energy", 1)[0].abs() < 1e-12,
        "no strain at the start"
    );
}

/// A cantilever of four superelements (aluminium, 1 m, 10 mm square) under gravity.
const CANTILEVER: Text = Text(|| {
    [
        material("aluminium", 70e9, 0.33, 2700.0),
        rectangle("bar", 0.01, 0.01),
        two_ended_beam("segment", "aluminium", "bar", 0.25, 4, Some("euler-bernoulli"), 2),
        welded_chain("segment", 4, 0.25),
        clamp("s0.a"),
        gravity("weight", [0.0, -9.81, 0.0]),
        sensor("tip", "position", "s3.b"),
    ]
    .concat()
});

#[test]
fn a_cantilever_started_from_its_equilibrium_stays_there() {
    let text = [
        CANTILEVER.to_string(),
        equilibrium("sag", "1e-13"),
        named_dynamic("from-sag", Some("sag"), "0.2", "1e-3"),
        named_dynamic("from-rest", None, "0.2", "1e-3"),
    ]
    .concat();
    let (rec, summary, _) = run("hanging", &text);
    summary.unwrap();
    let y_eq = *column(&rec, "sag", "tip", 1).last().unwrap();
    let drift = column(&rec, "from-sag", "tip", 1)
        .iter()
        .map(|y| (y - y_eq).abs())
        .fold(0.0, f64::max);
    eprintln!("static tip {y_eq:.6e} m; drift from it {drift:.3e} m");
    // The required bound, 1e-9 m.
    assert!(drift < 1e-9, "{drift}");
    // Without `start` gravity arrives as a step: the tip overshoots the sag by far.
    let lowest = column(&rec, "from-rest", "tip", 1).into_iter().fold(0.0, f64::min);
    assert!(lowest < 1.5 * y_eq, "{lowest} vs {y_eq}");
}

#[test]
fn one_analysis_run_alone_runs_its_start_chain_first() {
    // equilibrium -> dynamic from it -> dynamic from that one; the last run alone
    // (`study::run_only`, the CLI's and Python's single analysis) must give the numbers of the
    // whole study, with the analyses of its chain run and recorded first.
    let text = [
        CANTILEVER.to_string(),
        r#"[[loads]]
name = "push"
type = "point"
at = "s3.b"
force = [0.0, 0.0, 1.0]
function = { type = "ramp", t_end = 0.02, to = 1.0 }
"#
        .to_string(),
        equilibrium("sag", "1e-13"),
        named_dynamic("first", Some("sag"), "0.03", "1e-3"),
        named_dynamic("second", Some("first"), "0.06", "1e-3"),
    ]
    .concat();
    let (whole, summary, file) = run("chain", &text);
    summary.unwrap();
    let study = study::load(&file).unwrap();
    let dir = file.parent().unwrap();
    let options = Options {
        out: Some(dir.join("alone")),
        ..crate::options_in(dir, None)
    };
    let mut rec = Recorder::default();
    let summary = study::run_only(&study, &options, 2, &mut rec)
        .map_err(|e| study::error::chain(&*e))
        .unwrap();
    let names: Vec<&str> = rec.analyses.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["sag", "first", "second"]);
    assert!(summary
        .analyses
        .iter()
        .all(|a| a.status == study::output::summary::Status::Done));
    let report = &summary.analyses[2].report;
    assert!(
        report
            .iter()
            .any(|l| l.contains("started from the final state of 'first'")),
        "{report:?}"
    );
    // The same computation in the same order: equal to the last bit.
    for (analysis, c) in [("second", 1), ("second", 2)] {
        assert_eq!(column(&rec, analysis, "tip", c), column(&whole, analysis, "tip", c));
    }
    // The second run starts where the first ended (the push is on, so it is not the sag).
    let end_first = *column(&rec, "first", "tip", 2).last().unwrap();
    assert_eq!(column(&rec, "second", "tip", 2)[0], end_first);
    assert!(end_first.abs() > 1e-6, "{end_first}");
    assert!(dir.join("alone/first").is_dir() && dir.join("alone/sag").is_dir());
}

#[test]
fn an_euler_column_of_eight_superelements_buckles_at_eulers_load() {
    // Steel, 10 mm square, 1 m, clamped-free; eight superelements of static modes only.
    let (E, a, L): (f64, f64, f64) = (2.1e11, 0.01, 1.0);
    let p_euler = std::f64::consts::PI.powi(2) * E * a.powi(4) / 12.0 / (4.0 * L * L);
    let text = [
        material("steel", 2.1e11, 0.3, 7800.0),
        rectangle("bar", 0.01, 0.01),
        two_ended_beam("segment", "steel", "bar", 0.125, 2, Some("euler-bernoulli"), 0),
        clamp("s0.a"),
        welded_chain("segment", 8, 0.125),
    ]
    .concat();
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
    // The required bound, 0.5 %: eight chord-like superelements are 0.3 % above (1/N^2).
    assert!(err.abs() < 5e-3, "{err}");
    assert_eq!(r["past_critical_point"], serde_json::json!(false));
    let frames = &rec.analysis("buckling").unwrap().frames;
    assert_eq!(frames.len(), 2, "a mode shape per load factor");
    // The results page: both modes, labelled with their load factors, about the loaded
    // column, the first a sideways deflection of the tip.
    let dir = crate::scratch("euler-column-page");
    let file = dir.join("column.toml");
    std::fs::write(&file, with_load(0.1)).unwrap();
    let mut page = study::output::view::SceneBuilder::new("column");
    study::run_with(&study::load(&file).unwrap(), &crate::options_in(&dir, None), &mut page).unwrap();
    let scene = page.scene();
    let a = scene.analyses.iter().find(|a| a.name == "buckling").unwrap();
    assert_eq!(a.bodies.len(), 8);
    assert_eq!(a.modes.len(), 2);
    let factor = r["load_factors"][0].as_f64().unwrap();
    assert_eq!(a.modes[0].label, format!("mode 1: load factor {factor:.6}"));
    let (base, mode) = (&a.base.as_ref().unwrap().poses[7], &a.modes[0].pose.poses[7]);
    let sideways = (mode.r[1] - base.r[1]).hypot(mode.r[2] - base.r[2]);
    assert!(
        sideways > 1e-3,
        "the top segment's frame moves sideways in the mode: {sideways}"
    );
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

/// The rigid pendulum of `common::pendulum` with its sensor `angle`.
const PENDULUM: Text = Text(|| pendulum(&[]) + &sensor("angle", "joint", "pivot"));

/// The pendulum under gravity (9.81 m/s^2 down).
const HANGING: Text = Text(|| PENDULUM.to_string() + &gravity("weight", [0.0, -9.81, 0.0]));

/// The hanging pendulum released from `angle` \[rad\] by its `[[initial]]` line.
fn released(angle: f64) -> String {
    format!("{HANGING}[[initial]]\njoint = \"pivot\"\nvalue = {angle:?}\n")
}

#[test]
fn a_pid_actuator_in_a_study_holds_its_set_point() {
    let text = format!(
        "{HANGING}[[actuators]]
name = \"motor\"
joint = \"pivot\"
pid = {{ kp = 50.0, ki = 200.0, kd = 10.0, sensor = \"angle\", setpoint = {{ type = \"ramp\", t_end = 1.0, to = 0.5 }} }}
[[sensors]]
name = \"torque\"
type = \"actuator-effort\"
of = \"motor\"
{}[output]
every = 10
",
        dynamic("10.0", "0.01")
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
{}",
        linearized(1)
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
    // The required bound, 1e-4 (the eigensolver gives round-off).
    assert!((im - wd).abs() < 1e-4 * wd && (re + c / (2.0 * I)).abs() < 1e-4 * c / (2.0 * I));
}

/// The pendulum released from 1.2 rad onto a stop at -0.5 rad.
fn stopped_pendulum(extra: &str) -> String {
    format!(
        "{}[[joint_limits]]
name = \"stop\"
joint = \"pivot\"
lower = -0.5
stiffness = 1e5
damping = 50.0
{}{extra}
",
        released(1.2),
        dynamic("1.5", "5e-3")
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
    // The stop rings at sqrt(k / m) = some 300 rad/s: the 5 ms steps in contact are retried
    // with steps of omega h <= 0.1.
    let retried = results(&rec, "dynamic")["retried_steps"].as_u64().unwrap();
    assert!(retried >= 1, "{retried}");
}

#[test]
fn a_stop_no_step_resolves_is_refused_at_the_start_of_the_run() {
    // 1e300 N m/rad on the pendulum's inertia about its pivot rings at some 1e149 rad/s,
    // against the smallest step dt/1024 = 4.9e-6 s.
    let text = stopped_pendulum("").replace("stiffness = 1e5", "stiffness = 1e300");
    let (rec, summary, _) = run("stop-1e300", &text);
    let e = summary.unwrap_err();
    eprintln!("{e}");
    for part in ["joint limit 'stop'", "joint 'pivot'", "1e300", "4.8828125e-6 s"] {
        assert!(e.contains(part), "{part}: {e}");
    }
    // Refused before the first step: only the start was recorded.
    let rows = rec
        .analysis("dynamic")
        .and_then(|a| a.sensors.as_ref())
        .map_or(0, |s| s.x.len());
    assert!(rows <= 1, "{rows} rows");
}

/// A shallow two-spring truss (von Mises truss): an apex of 1 kg on a vertical slider, held
/// by two springs of 1e7 N/m (and 2e4 N s/m) to ground points 1 m to either side and 0.1 m
/// below; the load on the apex grows to 8 kN in 0.1 s, twice the limit load, and the apex
/// snaps through to the far side and settles there.
fn snapping_truss(extra: &str) -> String {
    let spring = |side: &str, x: f64| {
        format!(
            "[[springs]]\nname = \"{side}\"\nbetween = [\"apex.P\", \"ground\"]\nground_point = [{x:?}, 0.0, 0.0]\n\
             stiffness = 1e7\ndamping = 2e4\n"
        )
    };
    format!(
        "{}[[supports]]
at = \"apex.P\"
type = \"slider\"
axis = [0.0, 1.0, 0.0]
{}{}[[loads]]
name = \"push\"
type = \"point\"
at = \"apex.P\"
force = [0.0, -8e3, 0.0]
function = {{ type = \"ramp\", t_end = 0.1, to = 1.0, smooth = false }}
{}{}{extra}
",
        rigid_body("apex", 1.0, [0.0, 0.1, 0.0], [0.01; 3], &[("P", [0.0, 0.1, 0.0])]),
        spring("left", -1.0),
        spring("right", 1.0),
        sensor("apex", "position", "apex.P"),
        dynamic("0.5", "1e-2")
    )
}

#[test]
fn a_snap_through_the_fixed_step_cannot_take_is_retried_and_the_summary_says_so() {
    // The limit load of the truss is k y0^3 / (sqrt(27) L0^2) = 3.8 kN (y0 = 0.1 m, L0 the
    // springs' length). Past it the apex falls through the unstable middle, where the
    // springs' vertical stiffness is -k y0^2 / L0^2 = -1e5 N/m, while the mass contributes
    // only about 4 m / h^2 = 4e4 N/m to the iteration matrix at h = 10 ms: the step's Newton
    // iteration has no well-posed solution to converge to. With dt_min = dt nothing is
    // retried and the run stops at the snap.
    let (_, summary, _) = run("snap-no-retry", &snapping_truss("dt_min = 1e-2"));
    let e = summary.unwrap_err();
    assert!(e.contains("Newton did not converge at t = 0.12"), "{e}");
    // With the default dt_min (dt/1024) the step is retried with halved steps.
    let (rec, summary, _) = run("snap-retry", &snapping_truss(""));
    summary.unwrap();
    let s = rec.analysis("dynamic").unwrap().summary.clone().unwrap();
    eprintln!("{}", s.report.join("\n"));
    assert_eq!(s.results["retried_steps"], serde_json::json!(1));
    let retry = &s.results["retries"][0];
    // Where (the interval [0.11, 0.12] s), how (two steps of 5 ms) and why.
    assert!((retry["time"].as_f64().unwrap() - 0.11).abs() < 1e-12, "{retry}");
    assert_eq!(retry["smallest_step"], serde_json::json!(5e-3));
    assert_eq!(retry["substeps"], serde_json::json!(2));
    assert!(retry["cause"].as_str().unwrap().contains("Newton did not converge"));
    assert!(s
        .report
        .iter()
        .any(|l| l.contains("retried with halved steps") && l.contains("t = 0.110000")));
    // The apex settles on the far side at the static equilibrium under 8 kN:
    // 2 k (L - L0) y / L = -P with L = sqrt(1 + y^2), solved by bisection.
    let (k, P, L0) = (1e7, 8e3, (1.0f64 + 0.01).sqrt());
    let f = |y: f64| 2.0 * k * ((1.0 + y * y).sqrt() - L0) * y / (1.0 + y * y).sqrt() + P;
    let (mut a, mut b) = (-0.3, -0.1);
    for _ in 0..100 {
        let m = 0.5 * (a + b);
        if f(a) * f(m) <= 0.0 {
            b = m
        } else {
            a = m
        }
    }
    let y = *column(&rec, "dynamic", "apex", 1).last().unwrap();
    eprintln!("apex at the end {y:.9} m, static equilibrium {a:.9} m");
    // The motion left 0.4 s after the snap decays as exp(-zeta omega t), zeta omega about
    // 300 1/s (vertical damping 2 c y^2 / L^2 = 650 N s/m on 1 kg): far below 1e-6 m.
    // The 10 ms step does not resolve the snap itself (the far side's vibration has
    // omega h = 4.5); the settled state does not depend on it.
    assert!((y - a).abs() < 1e-6, "{y} vs {a}");
}

#[test]
fn a_snap_through_stepped_from_a_simulation_is_retried_as_in_the_run_to_the_bit() {
    // The snap at t = 0.11 s needs a retried step (above): stepped one step at a time, the
    // simulation takes the run's step control, so it passes the snap and every output row
    // equals the run's.
    let shared = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/studies/snapping_truss.toml");
    let text = std::fs::read_to_string(shared).unwrap();
    // The shared study is the one the test above builds.
    assert!(
        text.ends_with(&snapping_truss("")),
        "tests/studies/snapping_truss.toml differs"
    );
    let (rec, summary, file) = run("snap-stepped", &text);
    summary.unwrap();
    let (t_run, y_run) = (times(&rec, "dynamic"), column(&rec, "dynamic", "apex", 1));
    let study = study::load(&file).unwrap();
    let options = crate::options_in(file.parent().unwrap(), None);
    let mut sim = study::Simulation::new(&study, "dynamic", &options).unwrap();
    let mut retried = 0;
    for (k, t) in t_run.iter().enumerate().skip(1) {
        let taken = sim
            .step()
            .unwrap_or_else(|f| panic!("step {k} to t = {t}: {}", f.error));
        retried += usize::from(taken.retry.is_some());
        assert_eq!(sim.time(), *t, "step {k}");
        assert_eq!(sim.sensor("apex").unwrap()[1], y_run[k], "apex at t = {t}");
    }
    assert_eq!(retried, 1);
    // One step of a size of its own, then the analysis' steps again: the plan is made anew,
    // so the steps land on the grid of dt again and on the end time.
    let mut sim = study::Simulation::new(&study, "dynamic", &options).unwrap();
    sim.step_by(2.5e-3).unwrap();
    assert_eq!(sim.time(), 2.5e-3);
    sim.advance_to(0.5).unwrap();
    assert!((sim.time() - 0.5).abs() < 1e-15, "{}", sim.time());
    let y_end = sim.sensor("apex").unwrap()[1];
    // Another step history, the same settled state (the run's, to its settling, 1e-6 m).
    assert!(
        (y_end - y_run.last().unwrap()).abs() < 1e-6,
        "{y_end} vs {}",
        y_run.last().unwrap()
    );
}

/// The pendulum under gravity with a `dynamic` analysis of `t_end` and `dt`.
fn swinging(t_end: &str, dt: &str) -> String {
    released(0.5) + &dynamic(t_end, dt)
}

/// A `t_end` that is not a multiple of `dt` ends exactly at `t_end` with a shortened last step
/// (it ran a full step past it); a `dt` longer than the run is refused at its key.
#[test]
fn a_dynamic_run_ends_exactly_at_t_end() {
    let (rec, summary, _) = run("t-end-exact", &swinging("0.25", "0.1"));
    summary.unwrap();
    assert_eq!(times(&rec, "dynamic"), vec![0.0, 0.1, 0.2, 0.25]);
    let r = results(&rec, "dynamic");
    assert_eq!(
        (r["t_reached"].as_f64(), r["steps"].as_u64()),
        (Some(0.25), Some(3)),
        "{r}"
    );
    let dir = crate::scratch("dt-longer");
    let file = dir.join("dt.toml");
    std::fs::write(&file, swinging("0.05", "0.1")).unwrap();
    let e = study::error::chain(&*study::load(&file).unwrap_err());
    assert!(e.contains("dt") && e.contains("longer than the run"), "{e}");
}

/// `--t-end` that is not a multiple of `dt` ends there too; one shorter than a step is refused
/// with the analysis named.
#[test]
fn the_t_end_option_ends_exactly_there_and_refuses_less_than_a_step() {
    let dir = crate::scratch("t-end-option");
    let file = dir.join("p.toml");
    std::fs::write(&file, swinging("1.0", "0.1")).unwrap();
    let study = study::load(&file).unwrap();
    let options = |t_end| crate::options_in(&dir, Some(t_end));
    let mut rec = Recorder::default();
    study::run_with(&study, &options(0.35), &mut rec).unwrap();
    assert_eq!(times(&rec, "dynamic").last().copied(), Some(0.35));
    let mut rec = Recorder::default();
    let e = study::error::chain(&*study::run_with(&study, &options(0.05), &mut rec).unwrap_err());
    assert!(
        e.contains("--t-end 0.05 s is shorter than one time step of analysis 'dynamic'"),
        "{e}"
    );
}

/// An inverted pendulum (gravity up: the bob 1 m above the pivot) linearised about its
/// start: the summary, the report and the mode labels say it is unstable, with the growth rate
/// sqrt(m g d / (I_G + m d^2)) = sqrt(9.81 / 1.01) = 3.1165 1/s (it was a stable "0 Hz" mode).
#[test]
fn an_inverted_pendulum_is_reported_unstable_in_a_study() {
    let text = format!("{PENDULUM}{}{}", gravity("weight", [0.0, 9.81, 0.0]), linearized(1));
    let (rec, summary, _) = run("inverted", &text);
    summary.unwrap();
    let r = results(&rec, "linearized");
    assert_eq!(r["stable"], serde_json::json!(false), "{r}");
    // The dense eigensolver on one unknown: exact to round-off.
    let rate = r["largest_growth_rate"].as_f64().unwrap();
    assert!((rate - (9.81f64 / 1.01).sqrt()).abs() < 1e-9, "{rate}");
    assert!(r["mode_labels"][0].as_str().unwrap().starts_with("UNSTABLE"), "{r}");
    let s = rec.analysis("linearized").unwrap().summary.clone().unwrap();
    assert!(
        s.report[0].starts_with("UNSTABLE: 1 state-space eigenvalue"),
        "{:?}",
        s.report
    );
    assert!(
        rec.progress.iter().any(|p| p.contains("UNSTABLE")),
        "{:?}",
        rec.progress
    );
}

/// `[parts.reduction] inertia_correction` on the spin-up beam of validation problem C1 as one
/// stiffened superelement (8 elements, 2 modes, to t = 6 s): a wrong type is refused at its
/// key and line; the key reaches the reduction (12 more coordinates for the 2 interfaces: the
/// static responses to the inertia of the 12 constraint modes) and the cache key (a body
/// reduced without it is not reused for a part that asks for it, and each is found again).
/// The centrifugal axial force is quadratic along the beam; the 2 bending modes leave it the
/// linear force of the constraint modes, and the geometric stiffening sees the difference in
/// the tip's deflection in the hub's axes: by 2.1e-3 m (0.57 %). With the correction the force
/// is in the span, and the 2-mode body follows the same body with 41 modes (all but one mode
/// of its 42 interior dofs: the FE beam) to 8e-7 m on 0.37 m.
#[test]
fn the_inertia_correction_of_a_reduction_reaches_the_reduction_the_cache_and_the_result() {
    let text = |modes: usize, correction: &str| {
        format!(
            r#"{}[[sections]]
name = "c1"
shape = "values"
A = 4e-4
Iy = 2e-7
Iz = 2e-7
J = 4e-7

[[parts]]
name = "beam"
material = "c1"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [10.0, 0.0, 0.0]
elements = 8
section = "c1"
theory = "euler-bernoulli"
[[parts.interfaces]]
name = "a"
set = "beam.start"
[[parts.interfaces]]
name = "b"
set = "beam.end"
[parts.reduction]
modes = {modes}
geometric_stiffening = true
{correction}

[[bodies]]
name = "b"
part = "beam"

[[joints]]
name = "hub"
type = "revolute"
between = ["ground", "b.a"]
axis = [0.0, 0.0, 1.0]

[[drivers]]
name = "spin-up"
joint = "hub"
function = {{ type = "spin-up", speed = 4.0, ramp_time = 15.0 }}

[[sensors]]
name = "tip"
type = "relative-position"
of = "b.b"
reference = "b.a"

[[analyses]]
type = "dynamic"
t_end = 6.0
dt = 0.02
"#,
            material("c1", 7e10, 0.3, 3000.0)
        )
    };
    // A wrong type: the file, the line of the key, the key and what it takes.
    let dir = crate::scratch("inertia-correction-type");
    let file = dir.join("wrong.toml");
    let wrong = text(2, "inertia_correction = 3");
    std::fs::write(&file, &wrong).unwrap();
    let e = study::load(&file).unwrap_err().to_string();
    let line = wrong.lines().position(|l| l.starts_with("inertia_correction")).unwrap() + 1;
    assert!(e.contains(&format!("wrong.toml:{line}:")), "{e}");
    assert!(e.contains("parts[0].reduction.inertia_correction"), "{e}");
    assert!(e.contains("expected a boolean"), "{e}");

    // One cache for all: each reduced once, then found again; the corrected body is never
    // the one reduced without the correction.
    let dir = crate::scratch("inertia-correction");
    let cache = dir.join("cache");
    let load = |name: &str, modes: usize, correction: &str| {
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, text(modes, correction)).unwrap();
        study::load(&file).unwrap()
    };
    let plain = load("plain", 2, "");
    let corrected = load("corrected", 2, "inertia_correction = true");
    let full = load("full", 41, "");
    assert!(!plain.parts[0].reduction.as_ref().unwrap().inertia_correction);
    assert!(corrected.parts[0].reduction.as_ref().unwrap().inertia_correction);
    let reduce = |study: &study::Study| study::reduce_part(study, &study.parts[0], &cache, &mut ()).unwrap();
    let (p, c) = (reduce(&plain), reduce(&corrected));
    assert!(!p.from_cache && !c.from_cache);
    assert_ne!(p.file, c.file);
    assert_eq!(p.body.n_coordinates(), 12 + 2);
    assert_eq!(c.body.n_coordinates(), p.body.n_coordinates() + 12);
    let (p2, c2) = (reduce(&plain), reduce(&corrected));
    assert!(p2.from_cache && c2.from_cache);
    assert_eq!((p2.file, c2.file), (p.file, c.file));
    assert_eq!(c2.body.n_coordinates(), c.body.n_coordinates());

    // The tip's deflection in the hub's axes.
    let deflection = |study: &study::Study, name: &str| {
        let options = Options {
            cache: Some(cache.clone()),
            ..crate::options_in(&dir.join(name), None)
        };
        let mut rec = Recorder::default();
        study::run_with(study, &options, &mut rec).unwrap();
        column(&rec, "dynamic", "tip", 1)
    };
    let (wp, wc, wf) = (
        deflection(&plain, "plain"),
        deflection(&corrected, "corrected"),
        deflection(&full, "full"),
    );
    let largest = |w: &[f64]| w.iter().zip(&wf).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let peak = wf.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let (ep, ec) = (largest(&wp), largest(&wc));
    assert!(peak > 0.3, "{peak}");
    // Measured 5.7e-3 and 2.2e-6 of the peak: the bounds leave a margin of about 1.4x and 2x
    // on either side of the 3 orders of magnitude the correction makes.
    assert!(ep > 4e-3 * peak, "without the correction {ep} m of {peak} m");
    assert!(ec < 5e-6 * peak, "with the correction {ec} m of {peak} m");
}
