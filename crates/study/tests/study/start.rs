//! The consistent start of a run: the drivers' and `[[initial]]` rates at t = 0 give every
//! body a consistent velocity (the C2 slider-crank by its driver alone against its
//! hand-computed start, the four-bar from a crank rate without a strain spike, a flexible
//! lever and a solid hex20 one on a harmonic driver without a torque jump), contradicting rates refused at the
//! `[[initial]]` entry, and `start = "at-rest"` as the explicit choice of the old impact.

use super::setup::{column, first_body, run, times};
use std::path::Path;

fn example_text(name: &str) -> String {
    let e = study::input::examples::EXAMPLES
        .iter()
        .find(|e| e.name == name)
        .unwrap();
    std::str::from_utf8(e.files[0].1).unwrap().to_string()
}

/// The C2 example (its driver alone) and the same study with the hand-computed rigid-body
/// velocities at the dead centre as five `[[initial]]` entries (tests/studies): the rod's
/// midpoint deflection agrees to 1e-6 of its peak over the whole run.
#[test]
fn c2_by_its_driver_alone_starts_as_the_hand_computed_start() {
    let example = example_text("slider_crank");
    assert!(
        !example.contains("[[initial]]"),
        "the example needs no initial conditions"
    );
    let hand = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/studies/slider_crank_hand_start.toml"),
    )
    .unwrap();
    assert_eq!(hand.matches("\n[[initial]]\n").count(), 5);
    let (a, sa, _) = run("c2-driver", &example);
    let (b, sb, _) = run("c2-hand", &hand);
    sa.unwrap();
    sb.unwrap();
    let (wa, wb) = (column(&a, "run-up", "rod-mid", 0), column(&b, "run-up", "rod-mid", 0));
    assert_eq!(wa.len(), wb.len());
    let peak = wa.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let worst = wa.iter().zip(&wb).fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(peak > 1e-3, "peak deflection {peak}");
    assert!(
        worst <= 1e-6 * peak,
        "deflections differ by {worst:e} of a peak {peak:e}"
    );
    let report = &a.analysis("run-up").unwrap().summary.as_ref().unwrap().report;
    assert!(
        report
            .iter()
            .any(|l| l.starts_with("start: set by drivers: 'crank-speed'"))
            && report
                .iter()
                .any(|l| l.starts_with("start: rates solved") && l.contains("pin-A")),
        "{report:?}"
    );
}

/// The four-bar without its motor, gravity and equilibrium, started from `initial` and run
/// for 20 steps of 0.1 ms.
fn four_bar_from(initial: &str) -> String {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/meshes/link_hex8.msh");
    let text = example_text("four_bar").replace("\"meshes/link_hex8.msh\"", &format!("{:?}", mesh.to_str().unwrap()));
    let cut = |t: &str, from: &str, to: &str| {
        let i = t.find(from).unwrap();
        let j = i + t[i..].find(to).unwrap();
        format!("{}{}", &t[..i], &t[j..])
    };
    let text = cut(&text, "[[drivers]]", "[[sensors]]");
    let text = cut(
        &text,
        "[[sensors]]\nname = \"motor-torque\"",
        "[[sensors]]\nname = \"coupler-modes\"",
    );
    let text = text[..text.find("# The equilibrium under gravity").unwrap()].to_string();
    format!(
        "{text}[[sensors]]\nname = \"crank\"\ntype = \"joint-rate\"\nof = \"crank-pivot\"\n\n{initial}\n[[analyses]]\ntype = \"dynamic\"\nt_end = 0.002\ndt = 1e-4\n"
    )
    .replace("[[loads]]\nname = \"weight\"\ntype = \"gravity\"\ng = [0.0, -9.81, 0.0]\n", "")
}

/// The four-bar started from a crank rate of 20 rad/s: the crank keeps the rate (the loop's
/// other rates are solved, the coupler moves rigidly) and the strain energy stays at the small
/// value of the centrifugal and inertial loads (1.4e-5 J against 0.42 J of kinetic energy).
/// Given to the crank alone, the rate struck the coupler: the crank dropped to 1.4 rad/s
/// within 1 ms.
#[test]
fn the_four_bar_from_a_crank_rate_starts_without_a_strain_spike() {
    let rate = "[[initial]]\njoint = \"crank-pivot\"\nrate = 20.0\n";
    let (rec, summary, _) = run("four-bar-rate", &four_bar_from(rate));
    summary.unwrap();
    let crank = column(&rec, "dynamic", "crank", 0);
    let strain = column(&rec, "dynamic", "energy", 1);
    let kinetic = column(&rec, "dynamic", "energy", 0);
    assert!((crank[0] - 20.0).abs() < 1e-9, "crank rate at t = 0: {}", crank[0]);
    assert!(
        (crank[1] - 20.0).abs() < 0.01 * 20.0,
        "crank rate at t = 0+: {}",
        crank[1]
    );
    let peak = strain.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    // Strain from the smooth loads of the moving four-bar: below 1e-4 of the kinetic energy (a
    // strike puts a sizeable part of it into the coupler).
    assert!(
        peak < 1e-4 * kinetic[0],
        "strain {peak:e} J against kinetic {:e} J",
        kinetic[0]
    );
}

/// Rates for two joints of the four-bar's one-dof loop that contradict are refused at the
/// `[[initial]]` entry, naming both; a consistent pair is accepted.
#[test]
fn contradicting_initial_rates_are_refused_naming_the_joints() {
    let two = "[[initial]]\njoint = \"crank-pivot\"\nrate = 20.0\n[[initial]]\njoint = \"rocker-pivot\"\nrate = 5.0\n";
    let (_, summary, _) = run("four-bar-contradicting", &four_bar_from(two));
    let e = summary.unwrap_err();
    assert!(
        e.contains("initial[")
            && e.contains("joint 'crank-pivot'")
            && e.contains("joint 'rocker-pivot'")
            && e.contains("over-determined"),
        "{e}"
    );
}

/// A flexible steel lever (0.5 m, 20 mm round, four beam elements) on a harmonic driver
/// θ = A sin(2πft), no gravity: the start gives the lever the driver's rate Aω, so the
/// driver's torque follows the rigid lever's I_O θ'' from the first step (within 5 % of its
/// amplitude I_O A ω²: the lever's bending). At rest it starts with an impact.
#[test]
fn a_lever_on_a_harmonic_driver_starts_without_a_torque_jump() {
    let (amplitude, f) = (0.2, 2.0);
    let lever = |extra: &str| {
        format!(
            r#"[[materials]]
name = "steel"
E = 200e9
nu = 0.3
rho = 7870.0

[[sections]]
name = "round"
shape = "circle"
d = 0.02

[[parts]]
name = "lever"
material = "steel"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [0.5, 0.0, 0.0]
elements = 4
section = "round"
[[parts.interfaces]]
name = "O"
set = "lever.start"
[[parts.interfaces]]
name = "T"
set = "lever.end"
[parts.reduction]
modes = 2

[[bodies]]
name = "lever"
part = "lever"

[[joints]]
name = "pivot"
type = "revolute"
between = ["ground", "lever.O"]
axis = [0.0, 0.0, 1.0]

[[drivers]]
name = "motor"
joint = "pivot"
function = {{ type = "harmonic", amplitude = {amplitude}, frequency_hz = {f} }}

[[sensors]]
name = "torque"
type = "driver-effort"
of = "motor"
{extra}
[[analyses]]
type = "dynamic"
t_end = 0.02
dt = 1e-3
"#
        )
    };
    let (rec, summary, file) = run("lever-harmonic", &lever(""));
    summary.unwrap();
    let (body, _) = first_body(&file);
    let m = body.inertia.mass;
    let c = body.inertia.center_of_mass;
    let i_o = body.inertia.inertia_com[2][2] + m * (c[0] * c[0] + c[1] * c[1]);
    let w = 2.0 * std::f64::consts::PI * f;
    let torque = column(&rec, "dynamic", "torque", 0);
    let t = times(&rec, "dynamic");
    let scale = i_o * amplitude * w * w;
    for (k, (tk, q)) in t.iter().zip(&torque).enumerate().skip(1).take(10) {
        let rigid = -i_o * amplitude * w * w * (w * tk).sin();
        // The lever's bending under the growing angular acceleration: a few per cent.
        assert!(
            (q - rigid).abs() < 0.05 * scale,
            "step {k}: torque {q} against I_O θ'' = {rigid} (scale {scale})"
        );
    }
    let (rec, summary, _) = run("lever-harmonic-at-rest", &lever("\n[[initial]]\nstart = \"at-rest\"\n"));
    summary.unwrap();
    let jump = column(&rec, "dynamic", "torque", 0)[1];
    assert!(
        jump.abs() > 5.0 * scale,
        "the start at rest strikes: {jump} N m (scale {scale})"
    );
}

/// The solid lever of `tests/studies/solid_lever_harmonic.toml` (hex20 bricks) with step `dt`
/// and the start `start` (`None`: the file's, the consistent one): the driver's torque at
/// t = 1 ms, the first step of the file's run.
fn solid_lever_torque_at_1ms(dt: f64, start: Option<&str>) -> f64 {
    let text = include_str!("../studies/solid_lever_harmonic.toml");
    let mut text = text.replace("dt = 1e-3", &format!("dt = {dt:e}"));
    assert!(text.contains(&format!("dt = {dt:e}")));
    if let Some(start) = start {
        text.push_str(&format!("\n[[initial]]\nstart = \"{start}\"\n"));
    }
    let tag = format!("solid-lever-{}-{dt:e}", start.unwrap_or("consistent"));
    let (rec, summary, _) = run(&tag, &text);
    summary.unwrap_or_else(|e| panic!("{tag}: {e}"));
    let t = times(&rec, "swing");
    let k = t
        .iter()
        .position(|t| (t - 1e-3).abs() < 1e-9 * 1e-3)
        .expect("a step ends at 1 ms");
    column(&rec, "swing", "torque", 0)[k]
}

/// A solid lever (0.4 m x 40 mm x 40 mm steel, hex20 bricks, pivot and tip interfaces) on a
/// harmonic driver θ = A sin(2πft): the consistent start gives it the driver's rate Aω, so
/// the torque at the first step (1 ms) is continuous: below a hundredth of the motion's
/// torque scale I_O A ω², and the runs with half and a quarter of the step agree with it to
/// 2e-3 of that scale with differences that shrink with the step (the integrator's error, no
/// jump). At rest the tip interface stays behind the driven pivot: the lever is struck and
/// the first step's torque is over 50 times the scale whatever the step.
#[test]
fn a_solid_lever_on_a_harmonic_driver_starts_without_a_torque_jump() {
    // The file's lever: density, length, side, amplitude, frequency; I_O about z through the
    // pivot face's centre.
    let (rho, l, b, amplitude, f) = (7870.0, 0.4, 0.04, 0.2, 2.0);
    let m = rho * l * b * b;
    let i_o = m * (l * l / 3.0 + b * b / 12.0);
    let w = 2.0 * std::f64::consts::PI * f;
    let scale = i_o * amplitude * w * w;
    let steps = [1e-3, 5e-4, 2.5e-4];
    let consistent: Vec<f64> = steps.iter().map(|&dt| solid_lever_torque_at_1ms(dt, None)).collect();
    let at_rest: Vec<f64> = steps
        .iter()
        .map(|&dt| solid_lever_torque_at_1ms(dt, Some("at-rest")))
        .collect();
    eprintln!("torque at 1 ms, steps {steps:?}: consistent {consistent:?}, at rest {at_rest:?} (scale {scale} N m)");
    for q in &consistent {
        assert!(q.abs() < 0.01 * scale, "consistent: {q} N m (scale {scale})");
    }
    let (d_half, d_quarter) = (
        (consistent[0] - consistent[1]).abs(),
        (consistent[1] - consistent[2]).abs(),
    );
    assert!(
        d_half < 2e-3 * scale,
        "consistent: h {} vs h/2 {} (scale {scale})",
        consistent[0],
        consistent[1]
    );
    assert!(d_quarter < 0.5 * d_half, "consistent, no jump: {consistent:?}");
    for q in &at_rest {
        assert!(q.abs() > 50.0 * scale, "at rest: {q} N m (scale {scale})");
    }
    assert!(
        at_rest[2].abs() > 0.9 * at_rest[0].abs(),
        "at rest, a strike: {at_rest:?}"
    );
}
