//! Input that parses but is physically wrong, refused with an error that names the entity and
//! where it is in the file; input files that are not regular files; validation time that grows
//! linearly with the number of entries.

use crate::common::{material, pendulum, rigid_body, sensor, Text};
use std::path::Path;
use study::output::observer::Recorder;
use study::Options;

/// The rigid pendulum of `common::pendulum` with points `P` and `Q` at its centre of mass.
const PENDULUM: Text = Text(|| pendulum(&[("P", [0.0, -1.0, 0.0]), ("Q", [0.0, -1.0, 0.0])]));

const DYNAMIC: &str = "
[[analyses]]
type = \"dynamic\"
t_end = 0.01
dt = 0.01
";

/// The validation errors of `text` (written as `<name>.toml`), rendered.
fn check(name: &str, text: &str) -> String {
    let dir = crate::scratch(name);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    match study::load(&file) {
        Ok(_) => String::new(),
        Err(e) => e.to_string(),
    }
}

/// `text` validated and run in memory; the error of the run.
fn run_error(name: &str, text: &str) -> String {
    let dir = crate::scratch(name);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, text).unwrap();
    let study = study::load(&file).unwrap();
    let options = crate::options_in(&dir, None);
    match study::run_with(&study, &options, &mut Recorder::default()) {
        Ok(_) => String::new(),
        Err(e) => study::error::chain(&*e),
    }
}

/// A spring whose ends coincide has no direction; with a rest length its force would point
/// along the round-off of the positions. Refused at the spring; a rest length of 0 (a linear
/// spring k (x_b - x_a)) is accepted.
#[test]
fn a_zero_length_spring_with_a_rest_length_is_refused() {
    let spring = |rest: f64| {
        format!("{PENDULUM}[[springs]]\nname = \"s\"\nbetween = [\"bob.P\", \"ground\"]\nground_point = [0.0, -1.0, 0.0]\nstiffness = 100.0\nrest_length = {rest:?}\n{DYNAMIC}")
    };
    let e = run_error("spring-zero-length", &spring(0.5));
    assert!(e.contains("springs[0]"), "{e}");
    assert!(e.contains("spring-zero-length.toml:"), "{e}");
    assert!(e.contains("spring 's'") && e.contains("ends coincide"), "{e}");
    assert_eq!(run_error("spring-zero-rest", &spring(0.0)), "");
}

/// The velocity of a point that follows a joint is the joint's rate: a velocity given to it
/// would be ignored, so it is refused, at the `[[initial]]` line.
#[test]
fn an_initial_velocity_on_a_point_a_joint_moves_is_refused() {
    let text = format!("{PENDULUM}[[initial]]\nat = \"bob.P\"\nvelocity = [1.0, 0.0, 0.0]\n{DYNAMIC}");
    let e = run_error("initial-on-joint", &text);
    assert!(e.contains("initial[0]"), "{e}");
    assert!(e.contains("follows a joint"), "{e}");
    // The joint's rate is the way to give it.
    let text = format!("{PENDULUM}[[initial]]\njoint = \"pivot\"\nrate = 1.0\n{DYNAMIC}");
    assert_eq!(run_error("initial-rate", &text), "");
}

/// A deflection sensor measures from the line through its chord's points: the same point
/// twice is refused by the validator, two points at one place when the mechanism is built.
#[test]
fn a_deflection_sensor_with_coincident_chord_points_is_refused() {
    let sensor = |a: &str, b: &str| {
        format!("{PENDULUM}[[sensors]]\nname = \"d\"\ntype = \"deflection\"\nof = \"bob.O\"\nchord = [\"{a}\", \"{b}\"]\n{DYNAMIC}")
    };
    let e = check("chord-same", &sensor("bob.P", "bob.P"));
    assert!(e.contains("sensors[0].chord[1]") && e.contains("both 'bob.P'"), "{e}");
    let e = run_error("chord-coincident", &sensor("bob.P", "bob.Q"));
    assert!(e.contains("sensors[0].chord") && e.contains("coincide"), "{e}");
}

/// Values in range for their type but outside what the physics or double precision allow:
/// a negative `at_time`, a Newton tolerance below round-off or of 1 and more, a modal damping
/// ratio of 500 % (a ratio above 1, critical, is refused; 20 % and more warns), more modes
/// than the part has dofs, each located at its key.
#[test]
fn values_outside_their_physical_range_are_refused_at_their_key() {
    let e = check(
        "at-time",
        &format!("{PENDULUM}[[analyses]]\ntype = \"equilibrium\"\nat_time = -1.0\n"),
    );
    assert!(e.contains("analyses[0].at_time") && e.contains("non-negative"), "{e}");
    for (tol, ok) in [
        ("1e-300", false),
        ("1e-15", false),
        ("1.0", false),
        ("1e-14", true),
        ("1e-6", true),
    ] {
        let e = check(
            "tolerance",
            &format!("{PENDULUM}[[analyses]]\ntype = \"equilibrium\"\ntolerance = {tol}\n"),
        );
        assert_eq!(e.is_empty(), ok, "tolerance {tol}: {e}");
        if !ok {
            assert!(
                e.contains("analyses[0].tolerance") && e.contains("must lie in [1e-14, 1)"),
                "{e}"
            );
        }
    }
    let cantilever =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cantilever.toml")).unwrap();
    // 20 beam elements on a clamped root: 20 x 6 = 120 free dofs.
    let modal = cantilever.replace("modes = 6", "modes = 121");
    assert_ne!(modal, cantilever, "the example's modal analysis asks for 6 modes");
    let e = check("modes", &modal);
    assert!(e.contains(".modes") && e.contains("120 free dofs"), "{e}");
    let ok = check("modes-ok", &cantilever.replace("modes = 6", "modes = 120"));
    assert!(ok.is_empty(), "{ok}");
}

/// A modal damping ratio is a fraction of critical damping: 5 (500 %) is refused, 0.3 warns.
#[test]
fn a_modal_damping_ratio_above_critical_is_refused() {
    let four_bar = study::input::examples::write("four_bar", &crate::scratch("ratio-example")).unwrap();
    let text = std::fs::read_to_string(&four_bar).unwrap();
    let mut doc = study::Document::from_text(&text, &four_bar).unwrap();
    let e = doc
        .set("bodies[0].damping", "{ modal_ratio = 5.0 }")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bodies[0].damping.modal_ratio") && e.contains("must lie in [0, 1], got 5"),
        "{e}"
    );
    doc.set("bodies[0].damping", "{ modal_ratio = 0.3 }").unwrap();
    let w = doc.study().unwrap().warnings.join("\n");
    assert!(w.contains("modal_ratio") && w.contains("30 %"), "{w}");
}

/// A named pipe as a study or mesh file would block the reader until something writes into
/// it: both are refused before they are opened.
#[cfg(unix)]
#[test]
fn a_named_pipe_as_study_or_mesh_file_is_refused() {
    let dir = crate::scratch("fifo");
    let fifo = dir.join("pipe.toml");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let e = study::load(&fifo).unwrap_err().to_string();
    assert!(e.contains("named pipe") && e.contains("pipe.toml"), "{e}");
    let mesh = dir.join("pipe.msh");
    assert!(std::process::Command::new("mkfifo")
        .arg(&mesh)
        .status()
        .unwrap()
        .success());
    let e = fe_model::mesh::gmsh::read(&mesh).unwrap_err().to_string();
    assert!(e.contains("named pipe") && e.contains("pipe.msh"), "{e}");
    let text = "[[materials]]\nname = \"steel\"\nE = 210e9\nnu = 0.3\nrho = 7850.0\n[[parts]]\nname = \"p\"\nmaterial = \"steel\"\n[parts.mesh]\nfile = \"pipe.msh\"\n";
    std::fs::write(dir.join("uses-pipe.toml"), text).unwrap();
    let e = study::load(&dir.join("uses-pipe.toml")).unwrap_err().to_string();
    assert!(e.contains("named pipe") && e.contains("parts[0]"), "{e}");
}

/// Every name is looked up in a hash table, so validation grows linearly with the number of
/// entries: 80,000 materials (each name checked against all before it, the last a duplicate
/// of the first) and a part that refers to the last of them. Before, each entry searched the
/// list of those before it (80,000^2 / 2 = 3.2e9 comparisons, 13.5 s); the time is not
/// asserted here (a benchmark's job), the test keeps the case that was quadratic.
#[test]
fn eighty_thousand_materials_validate_and_a_duplicate_is_found() {
    let n = 80_000;
    let mut text = String::with_capacity(n * 60);
    for i in 0..n {
        text.push_str(&format!(
            "[[materials]]\nname = \"m{i}\"\nE = 210e9\nnu = 0.3\nrho = 7850.0\n"
        ));
    }
    text.push_str("[[materials]]\nname = \"m0\"\nE = 210e9\nnu = 0.3\nrho = 7850.0\n");
    let e = check("many-materials", &text);
    assert!(
        e.contains(&format!("materials[{n}].name")) && e.contains("'m0' is already defined"),
        "{e}"
    );
    assert!(e.contains("(1 error)"), "{e}");
}

/// A PID law measures the joint sensor it names, found in a hash table built once, so that
/// validation grows linearly with the number of actuators: 20,000 PID actuators each
/// measuring a sensor of its own (before, each searched the list of sensors: 2e8
/// comparisons; the time is not asserted, the test keeps the case). An unknown name is
/// refused at `pid.sensor` with the close matches, and so is a sensor of another kind.
#[test]
fn twenty_thousand_pid_sensors_are_found_and_unknown_or_wrong_ones_refused() {
    let n = 20_000;
    let mut text = String::with_capacity(n * 200);
    text.push_str(&PENDULUM.to_string());
    text.push_str(&sensor("rate", "joint-rate", "pivot"));
    let pid = |i: usize, measured: &str| {
        format!(
            "[[actuators]]\nname = \"a{i}\"\njoint = \"pivot\"\n\
             pid = {{ kp = 1.0, sensor = \"{measured}\", setpoint = {{ type = \"ramp\", t_end = 1.0, to = 0.1 }} }}\n"
        )
    };
    for i in 0..n {
        text.push_str(&sensor(&format!("s{i}"), "joint", "pivot"));
        text.push_str(&pid(i, &format!("s{i}")));
    }
    text.push_str(&pid(n, "s1999x"));
    text.push_str(&pid(n + 1, "rate"));
    let e = check("many-pid-sensors", &text);
    assert!(
        e.contains(&format!(
            "actuators[{n}].pid.sensor: unknown joint sensor 's1999x'; did you mean"
        )),
        "{e}"
    );
    assert!(
        e.contains(&format!(
            "actuators[{}].pid.sensor: sensor 'rate' is not a 'joint' sensor",
            n + 1
        )),
        "{e}"
    );
    assert!(e.contains("(2 errors)"), "{e}");
}

/// `translations = "body"` in a dynamic analysis reaches the integrator (the free nodes'
/// translations in body axes, for long runs of fast steady rotation); `fixed` is the default and
/// any other value is refused at its key.
#[test]
fn the_translation_axes_of_a_dynamic_analysis_reach_the_integrator() {
    let settings = |name: &str, key: &str| {
        let dir = crate::scratch(name);
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, format!("{PENDULUM}{DYNAMIC}{key}")).unwrap();
        let study = study::load(&file).unwrap();
        let study::input::validate::AnalysisSpec::Mbs(spec) = &study.analyses[0].spec else {
            panic!("a dynamic analysis")
        };
        study::dynamic_settings(spec, 1).unwrap()
    };
    assert!(!settings("axes-default", "").body_axis_translations);
    assert!(!settings("axes-fixed", "translations = \"fixed\"\n").body_axis_translations);
    assert!(settings("axes-body", "translations = \"body\"\n").body_axis_translations);
    let e = check("axes-bad", &format!("{PENDULUM}{DYNAMIC}translations = \"sideways\"\n"));
    assert!(
        e.contains("analyses[0].translations") && e.contains("unknown translation axes 'sideways'"),
        "{e}"
    );
}

/// Checking a study builds each part's spiders on the part's own model and restores it: no
/// copy of the mesh per analysis (a generated box may have 2,000,000 cells), and the model a
/// run starts from is the generated one, whatever the checks added. A run copies once per
/// analysis that builds a model.
#[test]
fn checking_a_study_copies_no_model_and_leaves_each_part_as_generated() {
    let text = material("steel", 210e9, 0.3, 7850.0)
        + r#"
[[parts]]
name = "block"
material = "steel"
box = { size = [1.0, 0.2, 0.2], divisions = [6, 2, 2], element = "hex8" }
interfaces = [
    { name = "root", set = "x0", spider = "rbe2" },
    { name = "end", set = "x1", spider = "rbe3" },
]
reduction = { modes = 4, auxiliary_node = true }

[[analyses]]
type = "static"
name = "bend"
part = "block"
supports = [{ at = "root" }]
loads = [{ at = "end", force = [0.0, 0.0, -1000.0] }]

[[analyses]]
type = "modal"
name = "free"
part = "block"
modes = 8

[[analyses]]
type = "modal"
name = "clamped"
part = "block"
modes = 4
supports = [{ at = "end" }]

[[analyses]]
type = "reduce"
part = "block"
"#;
    let dir = crate::scratch("no-model-copies");
    let file = dir.join("block.toml");
    std::fs::write(&file, &text).unwrap();
    let copies = study::input::part::model_copies();
    let study = study::load(&file).unwrap();
    assert_eq!(
        study::input::part::model_copies() - copies,
        0,
        "validation copied a model"
    );
    // The spiders, supports and the auxiliary node of the checks are gone again.
    let base = &study.parts[0].base;
    let generated = fe_model::box_mesh(fe_model::CellKind::Hex8, [1.0, 0.2, 0.2], [6, 2, 2]).unwrap();
    assert_eq!(base.mesh, generated);
    assert!(base.supports.is_empty() && base.constraints.is_empty());
    // A run copies the model once per analysis on a part (static, two modal, reduce).
    let copies = study::input::part::model_copies();
    let options = crate::options_in(&dir, None);
    let summary = study::run_with(&study, &options, &mut Recorder::default()).unwrap();
    assert_eq!(summary.status, "complete");
    assert_eq!(study::input::part::model_copies() - copies, 4);
}

/// The pendulum (which keeps an unknown) and a cart driven along a rail at 10 m/s from 1 m
/// before a clamped post: the cart's point `P` reaches the post's point `Q` at t = 0.1 s, step
/// 10, where the deflection of `post.R` from the line through them is 0/0. A study the
/// Python package's tests read too.
fn pendulum_cart() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/studies/pendulum_cart.toml")).unwrap()
}

/// A sensor whose value stops being finite stops the run at the sensor's `[[sensors]]` entry
/// (`file:line:col: sensors[i]: ...`), as a failure at a body is located at the body, and the
/// message names the sensor, the time and the step.
#[test]
fn a_sensor_that_is_not_finite_is_located_at_the_sensor_in_the_study_file() {
    let text = pendulum_cart();

    let e = run_error("sensor-not-finite", &text);
    let line = text.lines().position(|l| l == "name = \"gap\"").unwrap() + 1;
    assert!(
        e.contains(&format!("sensor-not-finite.toml:{line}:"))
            || e.contains(&format!("sensor-not-finite.toml:{}:", line - 1)),
        "line {line}: {e}"
    );
    assert!(e.contains("sensors[1]: time integration stopped"), "{e}");
    assert!(
        e.contains("sensor 'gap' component 0 is NaN at t = 0.100000 (step 10)"),
        "{e}"
    );
}

/// A reaction is the force a support applies: a sensor on a point no support holds is refused
/// at the sensor, naming the point.
#[test]
fn a_reaction_sensor_at_a_point_without_a_support_is_refused() {
    let text = format!("{PENDULUM}[[sensors]]\nname = \"r\"\ntype = \"reaction\"\nof = \"bob.P\"\n{DYNAMIC}");
    let e = check("reaction-unsupported", &text);
    assert!(
        e.contains("sensors[0].of") && e.contains("point 'bob.P' has no [[supports]]"),
        "{e}"
    );
    // At the joint to the ground it is the pivot's force.
    let text = format!("{PENDULUM}[[sensors]]\nname = \"r\"\ntype = \"reaction\"\nof = \"pivot\"\n{DYNAMIC}");
    assert_eq!(run_error("reaction-pivot", &text), "");
}

/// An initial velocity at a point is set on the point's free components; a component that is
/// not zero along a direction its support holds would be dropped without a word, so it is
/// refused at the `[[initial]]` line with the component named. Zero there is fine.
#[test]
fn an_initial_velocity_along_a_held_direction_is_refused() {
    let wheel = |velocity: &str| {
        format!(
            r#"
{}[[supports]]
at = "wheel.C"
type = "pin"
[[initial]]
at = "wheel.C"
velocity = {velocity}
angular_velocity = [0.0, 0.0, 2.0]
{DYNAMIC}"#,
            rigid_body("wheel", 1.0, [0.0; 3], [0.01, 0.01, 0.02], &[("C", [0.0; 3])])
        )
    };
    let e = run_error("initial-held", &wheel("[0.0, 0.5, 0.0]"));
    assert!(e.contains("initial[0]") && e.contains("initial-held.toml:"), "{e}");
    assert!(
        e.contains("velocity component y is 0.5 m/s, but its support holds it"),
        "{e}"
    );
    assert_eq!(run_error("initial-held-zero", &wheel("[0.0, 0.0, 0.0]")), "");
}

/// A reduction keeps fixed-interface modes of the interior (the dofs that are not on an
/// interface): asking for as many as the interior has or more is refused by `check`, before
/// anything runs, located at the part's `reduction.modes`, naming the part and both counts.
#[test]
fn more_reduction_modes_than_interior_dofs_are_refused_with_the_part_named() {
    let cantilever =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cantilever.toml")).unwrap();
    // 21 beam nodes, the two ends interfaces: 19 x 6 = 114 interior dofs.
    let text = cantilever.replace("[parts.reduction]\nmodes = 4", "[parts.reduction]\nmodes = 500");
    assert_ne!(text, cantilever, "the example reduces with 4 modes");
    let e = check("reduction-modes", &text);
    // Located at the key, `file:line:col: parts[0].reduction.modes: ...`, the only error.
    let line = text.lines().position(|l| l == "modes = 500").unwrap() + 1;
    assert!(
        e.contains(&format!("reduction-modes.toml:{line}:")) && e.contains("parts[0].reduction.modes: 500"),
        "line {line}: {e}"
    );
    assert!(e.contains("(1 error)"), "{e}");
    assert!(
        e.contains("500 fixed-interface modes requested of 'beam', but its interior (the free dofs not on an interface) has 114 dofs, so at most 113 modes"),
        "{e}"
    );
    let e = run_error("reduction-modes-113", &text.replace("modes = 500", "modes = 113"));
    assert!(!e.contains("fixed-interface modes requested"), "{e}");
}

/// A simulation's `sensor(name)` evaluates that sensor alone: when the cart's point reaches
/// the post (t = 0.1 s) the deflection `gap` is 0/0, so reading every sensor fails, naming
/// `gap` at its `[[sensors]]` entry, while `travel` (the rail coordinate, 10 m/s x 0.1 s) is
/// still read. Before, `sensor` read them all and failed too.
#[test]
fn a_simulation_reads_one_sensor_without_evaluating_the_others() {
    let dir = crate::scratch("sensor-alone");
    let file = dir.join("sensor-alone.toml");
    std::fs::write(&file, pendulum_cart()).unwrap();
    let study = study::load(&file).unwrap();
    let options = Options {
        out: None,
        ..crate::options_in(&dir, None)
    };
    let mut sim = study::Simulation::new(&study, "dynamic", &options).unwrap();
    sim.step().unwrap();
    assert_eq!(sim.sensor("gap").unwrap(), sim.read().unwrap()[1]);
    assert_eq!(sim.sensor("travel").unwrap(), sim.read().unwrap()[0]);
    sim.advance_to(0.1).unwrap();
    // 10 m/s for 0.1 s, to the round-off of the time.
    let travel = sim.sensor("travel").unwrap()[0];
    assert!((travel - 1.0).abs() < 1e-12, "{travel}");
    let e = sim.read().unwrap_err();
    assert!(e.to_string().contains("sensor 'gap'"), "{e}");
    let e = sim.sensor("gap").unwrap_err();
    let solve = e.downcast_ref::<mbs::SolveError>().expect("a solver error");
    let at = sim.locate(solve).expect("located at the sensor");
    assert_eq!(at.key.to_string(), "sensors[1]");
}

/// `[parts.reduction] factor`: a value that is not a precision is refused at its key;
/// `"single"` reaches the reduction (its progress names the single-precision factor and the
/// refined solves) and gives the default run's fixed-interface frequencies.
#[test]
fn the_factor_precision_of_a_reduction_is_checked_and_reaches_the_reduction() {
    use study::output::observer::{Observer, Progress};
    let text = |factor: &str| {
        format!(
            r#"
[[materials]]
name = "steel"
E = 210e9
nu = 0.3
rho = 7850.0

[[parts]]
name = "block"
material = "steel"
box = {{ size = [1.0, 0.2, 0.2], divisions = [12, 3, 3], element = "hex8" }}
interfaces = [{{ name = "root", set = "x0", spider = "rbe2" }}]
reduction = {{ modes = 4{factor} }}

[[analyses]]
type = "reduce"
part = "block"
"#
        )
    };
    let err = check("factor-half", &text(", factor = \"half\""));
    assert!(
        err.contains("reduction.factor") && err.contains("'half'") && err.contains("\"single\""),
        "{err}"
    );
    /// The stage and information lines (the refined solves are reported as information, so
    /// that a log keeps them).
    #[derive(Default)]
    struct Stages(Vec<String>);
    impl Observer for Stages {
        fn progress(&mut self, p: &Progress) {
            if let Progress::Stage(s) | Progress::Info(s) = p {
                self.0.push(s.clone());
            }
        }
    }
    let mut omega = Vec::new();
    for (name, factor) in [("factor-auto", ""), ("factor-single", ", factor = \"single\"")] {
        let dir = crate::scratch(name);
        let file = dir.join("block.toml");
        std::fs::write(&file, text(factor)).unwrap();
        let study = study::load(&file).unwrap();
        assert_eq!(
            study.parts[0].reduction.as_ref().unwrap().factor,
            if factor.is_empty() {
                reduction::FactorPrecision::Auto
            } else {
                reduction::FactorPrecision::Single
            }
        );
        let cache = dir.join("cache");
        let mut stages = Stages::default();
        let reduced = study::reduce_part(&study, &study.parts[0], &cache, &mut stages).unwrap();
        let precision = if factor.is_empty() { "double" } else { "single" };
        assert!(
            stages
                .0
                .iter()
                .any(|s| s.contains(&format!("in {precision} precision"))),
            "{:?}",
            stages.0
        );
        assert_eq!(
            stages.0.iter().any(|s| s.contains("refined solves")),
            !factor.is_empty(),
            "{:?}",
            stages.0
        );
        omega.push(reduced.body.fixed_interface_omega.clone());
    }
    for (a, b) in omega[0].iter().zip(&omega[1]) {
        // omega^2 to 1e-10, as the reduction's own test of the two precisions.
        assert!((a * a - b * b).abs() <= 1e-10 * a * a, "double {a}, single {b}");
    }
}
