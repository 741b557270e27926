//! The study layer without the program: a study edited by key path with located errors, a
//! run observed in memory against the results folder it writes, and a simulation stepped by
//! hand against the `dynamic` analysis of a run.

use common::{dynamic, gravity, pendulum, sensor};
use std::path::{Path, PathBuf};
use study::output::observer::{Observer, Recorder};
use study::Options;
use study::{Document, Simulation};

/// Study texts built from parameters.
mod common;

/// Mechanisms set up in study files (initial states, `start`, actuators, springs, stops,
/// buckling, adaptive and retried steps, a reduction's inertia correction) against independent
/// solutions.
#[path = "study/setup.rs"]
mod setup;

/// The consistent start: the drivers' and initial rates give every body its velocity at t = 0
/// (C2 by its driver alone, the four-bar from a crank rate, a lever on a harmonic driver);
/// contradicting rates refused; the start at rest as an explicit choice.
#[path = "study/start.rs"]
mod start;

/// Planar parts and bodies: the keys reach the reduction, the cache and the bodies; a planar
/// body that could leave the plane is refused at the body; the planar slider-crank agrees
/// with its bodies evaluated in 3D.
#[path = "study/planar.rs"]
mod planar;

/// Physically wrong input refused at its entity; named pipes; validation time linear in the
/// number of entries.
#[path = "study/input_checks.rs"]
mod input_checks;

/// Stresses: loads at load points inside a reduced body against the full FE model, read by
/// `stress` sensors and the VTU stress fields.
#[path = "study/stress.rs"]
mod stress;

/// The acceleration and energy-balance sensors of a study: columns, a pendulum and a crank
/// against their analytic accelerations, an equilibrium, the balance's order in the step.
#[path = "study/sensors.rs"]
mod sensors;

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    common::scratch_dir("tests", name)
}

/// The built-in example `name` written into a scratch folder; its study file.
fn example(name: &str) -> PathBuf {
    study::input::examples::write(name, &scratch(name)).unwrap()
}

/// The built-in example `name` in a scratch folder of its own, `tag`.
fn example_as(name: &str, tag: &str) -> PathBuf {
    study::input::examples::write(name, &scratch(tag)).unwrap()
}

#[test]
fn values_are_read_and_set_by_key_path_with_located_errors() {
    let file = example("four_bar");
    let mut doc = Document::open(&file).unwrap();
    // An element of an array of tables by its name or by its index.
    assert_eq!(doc.get("parts.link.reduction.modes").unwrap(), serde_json::json!(4));
    assert_eq!(doc.get("parts[0].reduction.modes").unwrap(), serde_json::json!(4));
    assert_eq!(
        doc.resolve("parts.link.reduction.modes").unwrap().to_string(),
        "parts[0].reduction.modes"
    );
    doc.set("parts.link.reduction.modes", "6").unwrap();
    assert_eq!(doc.get("parts.link.reduction.modes").unwrap(), serde_json::json!(6));
    // The comments of the file are kept.
    assert!(doc.text().contains("# A four-bar linkage whose coupler is a solid"));
    let study = doc.study().unwrap();
    assert_eq!(study.parts[0].name, "link");

    // A value the validation refuses: file, line, column and key, and the value not kept.
    let e = doc.set("materials.aluminium.E", "-70e9").unwrap_err().to_string();
    assert!(e.contains("four_bar.toml:17:"), "{e}");
    assert!(e.contains("materials[0].E"), "{e}");
    assert_eq!(doc.get("materials.aluminium.E").unwrap(), serde_json::json!(70e9));
    // A key that is not there: the close matches.
    let e = doc.get("parts.lnk.reduction").unwrap_err().to_string();
    assert!(e.contains("did you mean 'link'"), "{e}");
    // A new key in an existing table, and a wrong type located at it.
    let e = doc
        .set("parts.link.reduction.modes", "\"four\"")
        .unwrap_err()
        .to_string();
    assert!(e.contains("modes"), "{e}");
    assert!(Document::from_text("a = [", Path::new("x.toml"))
        .unwrap_err()
        .to_string()
        .contains("x.toml:1:"));
}

#[test]
fn keys_are_removed_and_tables_replaced_by_key_path_with_located_errors() {
    let file = example("slider_crank");
    let mut doc = Document::open(&file).unwrap();
    // A table replaced as a whole: the section given by `d` switched to one given by values,
    // which `set` key by key could not do (`d` and `A` together are refused).
    let values = "{ name = \"rod\", shape = \"values\", A = 2.8e-5, Iy = 6.4e-11, Iz = 6.4e-11, J = 1.3e-10 }";
    doc.set("sections.rod", values).unwrap();
    assert_eq!(doc.get("sections.rod.A").unwrap(), serde_json::json!(2.8e-5));
    assert!(doc.get("sections.rod.d").is_err());
    assert!(doc.text().contains("# The rod, meshed where it sits"));
    doc.study().unwrap();
    // A table refused as a whole is not kept, and the error is located.
    let e = doc
        .set("sections.rod", "{ name = \"rod\", shape = \"circle\", d = -1.0 }")
        .unwrap_err()
        .to_string();
    assert!(e.contains("slider_crank.toml:"), "{e}");
    assert!(e.contains("sections[0].d"), "{e}");
    assert_eq!(doc.get("sections.rod.A").unwrap(), serde_json::json!(2.8e-5));
    // Only a table replaces a table.
    let e = doc.set("sections.rod", "3").unwrap_err().to_string();
    assert!(e.contains("a table can only be replaced by a table"), "{e}");

    // A key removed; a key the study needs is refused at its table and kept.
    let mut doc = Document::open(&file).unwrap();
    doc.remove("analyses.run-up.rho_inf").unwrap();
    assert!(doc.get("analyses.run-up.rho_inf").is_err());
    assert!(doc.text().contains("t_end = 0.126    # three revolutions"));
    let e = doc.remove("sections.rod.d").unwrap_err().to_string();
    assert!(e.contains("slider_crank.toml:"), "{e}");
    assert!(e.contains("sections[0]"), "{e}");
    assert_eq!(doc.get("sections.rod.d").unwrap(), serde_json::json!(0.006));
    // A path that leads nowhere: the close matches, as for `get` and `set`.
    let e = doc.remove("sections.rdo").unwrap_err().to_string();
    assert!(e.contains("did you mean 'rod'"), "{e}");
    // An element of an array of tables removed by name, and the names it leaves refused.
    let e = doc.remove("materials.steel").unwrap_err().to_string();
    assert!(e.contains("unknown material 'steel'"), "{e}");
    assert!(doc.get("materials.steel").is_ok());
    let sections = doc.text().matches("[[sections]]").count();
    doc.set_unchecked("sections[0].name", "\"spare\"").unwrap();
    doc.remove_unchecked("sections.spare").unwrap();
    assert_eq!(doc.text().matches("[[sections]]").count(), sections - 1);
}

#[test]
fn a_run_observed_in_memory_matches_its_results_folder() {
    let file = example("cantilever");
    let study = study::load(&file).unwrap();
    let out = file.parent().unwrap().join("results");
    let options = Options {
        out: Some(out.clone()),
        cache: Some(file.parent().unwrap().join("cache")),
        t_end: None,
        ..Options::default()
    };
    let mut rec = Recorder::default();
    let summary = study::run(&study, &options, &mut rec).unwrap();
    assert_eq!(summary.status, "complete");
    assert_eq!(rec.analyses.len(), study.analyses.len());
    for a in &rec.analyses {
        for t in &a.tables {
            // Every table is a CSV file of the same numbers (written as the shortest decimal
            // that reads back to the same f64, so equal to the bit).
            let text = std::fs::read_to_string(out.join(&a.name).join(format!("{}.csv", t.name))).unwrap();
            let rows: Vec<Vec<&str>> = text.lines().skip(1).map(|l| l.split(',').collect()).collect();
            assert_eq!(rows.len(), t.rows.len(), "{}/{}", a.name, t.name);
            for (r, row) in t.rows.iter().zip(&rows) {
                for (c, cell) in r.iter().zip(row) {
                    if let Some(x) = c.as_f64() {
                        assert_eq!(cell.parse::<f64>().unwrap(), x, "{}/{}", a.name, t.name);
                    }
                }
            }
        }
        let s = a.summary.as_ref().unwrap();
        assert!(s.error.is_none());
    }
}

/// The files below `dir`, by their path relative to it.
fn files_below(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// The name of the first dynamic analysis of `study`.
fn dynamic_analysis(study: &study::input::validate::Study) -> String {
    let a = study.analyses.iter().find(|a| a.kind_name() == "dynamic").unwrap();
    a.name.clone()
}

#[test]
fn a_simulation_stepped_to_its_end_writes_the_results_folder_of_the_run() {
    let file = example_as("slider_crank", "stepped-results");
    let study = study::load(&file).unwrap();
    let name = dynamic_analysis(&study);
    let dir = file.parent().unwrap();
    let options = |out: &str| Options {
        out: Some(dir.join(out)),
        cache: Some(dir.join("cache")),
        t_end: None,
        ..Options::default()
    };
    let run = study::run(&study, &options("run"), &mut ()).unwrap();
    let mut sim = Simulation::writing_results(&study, &name, &options("stepped")).unwrap();
    // Until the results end, the summary says the analysis is running.
    let summary = std::fs::read_to_string(dir.join("stepped/summary.json")).unwrap();
    assert!(summary.contains("\"running\""), "{summary}");
    sim.advance_to(sim.end_time()).unwrap();
    let stepped = sim.finish_results().unwrap().unwrap();
    assert_eq!(stepped.status, "complete");
    let (a, b) = (
        run.analyses.iter().find(|a| a.name == name).unwrap(),
        stepped.analyses.iter().find(|a| a.name == name).unwrap(),
    );
    assert_eq!(a.status, b.status);
    assert_eq!(a.report, b.report);
    assert_eq!(a.files, b.files);
    assert!(!b.files.is_empty());
    // Every file of the analysis (sensor CSVs and plots, meshes) is the run's, to the byte.
    let (ra, rb) = (dir.join("run").join(&name), dir.join("stepped").join(&name));
    let files = files_below(&ra);
    assert_eq!(files, files_below(&rb));
    assert!(
        files.iter().any(|f| f.extension().is_some_and(|e| e == "vtu")),
        "{files:?}"
    );
    for f in &files {
        assert!(
            std::fs::read(ra.join(f)).unwrap() == std::fs::read(rb.join(f)).unwrap(),
            "{}",
            f.display()
        );
    }
    // Finished once: the simulation steps on without results.
    assert!(sim.finish_results().unwrap().is_none());
    sim.step().unwrap();
}

#[test]
fn a_simulation_dropped_mid_way_leaves_a_summary_that_says_how_far_it_got() {
    let file = example_as("four_bar", "stepped-dropped");
    let study = study::load(&file).unwrap();
    let name = dynamic_analysis(&study);
    let dir = file.parent().unwrap();
    let options = options_in(dir, None);
    let mut sim = Simulation::writing_results(&study, &name, &options).unwrap();
    for _ in 0..7 {
        sim.step().unwrap();
    }
    let t = sim.time();
    drop(sim);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("results/summary.json")).unwrap()).unwrap();
    let entry = summary["analyses"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == name.as_str())
        .unwrap();
    assert_eq!(entry["status"], "done", "{entry}");
    assert_eq!(entry["results"]["steps"], 7, "{entry}");
    assert_eq!(entry["results"]["t_reached"].as_f64().unwrap(), t, "{entry}");
}

#[test]
fn a_simulation_stepped_by_hand_gives_the_numbers_of_the_run() {
    let file = example("four_bar");
    let study = study::load(&file).unwrap();
    let dynamic = study.analyses.iter().find(|a| a.kind_name() == "dynamic").unwrap();
    let dir = file.parent().unwrap();
    let options = Options {
        out: Some(dir.join("results")),
        cache: Some(dir.join("cache")),
        t_end: Some(0.02),
        ..Options::default()
    };
    let mut rec = Recorder::default();
    study::run_with(&study, &options, &mut rec).unwrap();
    let run = rec.analysis(&dynamic.name).unwrap().sensors.clone().unwrap();

    let mut sim = Simulation::new(&study, &dynamic.name, &options).unwrap();
    let names: Vec<&str> = sim.sensors().iter().map(|g| g.name.as_str()).collect();
    assert_eq!(names, run.groups.iter().map(|g| g.name.as_str()).collect::<Vec<_>>());
    // The same integrator on the same system: the same numbers to the bit.
    for (k, t) in run.x.iter().enumerate() {
        sim.advance_to(*t).unwrap();
        assert!((sim.time() - t).abs() < 1e-12);
        let values = sim.read().unwrap();
        for (g, v) in values.iter().enumerate() {
            assert_eq!(v, &run.rows[g][k], "sensor {} at t = {t}", run.groups[g].name);
        }
    }
    let motions = sim.node_motions();
    assert_eq!(motions.len(), sim.system().model().nodes.len());
    assert_eq!(sim.state().velocity().len(), sim.system().n_dof());
}

#[test]
fn a_named_load_changed_between_steps_acts_from_the_next_step() {
    let file = example("four_bar");
    // A point load on the rocker pin, zero in the file.
    let mut text = std::fs::read_to_string(&file).unwrap();
    text.push_str("\n[[loads]]\nname = \"push\"\ntype = \"point\"\nat = \"rocker.C\"\nforce = [0.0, 0.0, 0.0]\n");
    let doc = Document::from_text(&text, &file).unwrap();
    let study = doc.study().unwrap();
    let dynamic = study.analyses.iter().find(|a| a.kind_name() == "dynamic").unwrap();
    let options = Options {
        out: None,
        cache: Some(file.parent().unwrap().join("cache")),
        t_end: None,
        ..Options::default()
    };
    let mut a = Simulation::new(&study, &dynamic.name, &options).unwrap();
    let mut b = Simulation::new(&study, &dynamic.name, &options).unwrap();
    assert_eq!(a.load_names(), vec!["push"]);
    for _ in 0..5 {
        a.step().unwrap();
        b.step().unwrap();
    }
    assert_eq!(a.read().unwrap(), b.read().unwrap());
    // Setting the value the file gives changes nothing; a real push does.
    a.set_load("push", mbs::LoadKind::Force, [0.0, 0.0, 0.0]).unwrap();
    b.set_load("push", mbs::LoadKind::Force, [50.0, 0.0, 0.0]).unwrap();
    let before = a.sensor("rocker-angle").unwrap();
    assert_eq!(before, b.sensor("rocker-angle").unwrap());
    for _ in 0..5 {
        a.step().unwrap();
        b.step().unwrap();
    }
    let (qa, qb) = (a.sensor("rocker-angle").unwrap(), b.sensor("rocker-angle").unwrap());
    // 50 N on a 0.1 kg rocker for 5 ms moves it visibly: far above round-off (1e-12 rad).
    assert!((qa[0] - qb[0]).abs() > 1e-9, "{qa:?} {qb:?}");
    let e = a.set_load("pull", mbs::LoadKind::Force, [1.0, 0.0, 0.0]).unwrap_err();
    assert!(e.to_string().contains("push"), "{e}");
    let e = a.set_load("push", mbs::LoadKind::Moment, [1.0, 0.0, 0.0]).unwrap_err();
    assert!(e.to_string().contains("no moment"), "{e}");
    let _ = <() as Observer>::take_files(&mut ());
}

/// The rigid pendulum of `common::pendulum` under gravity `g` (m/s^2, along -y), with two
/// actuators on its pivot for a controller outside the study: `motor` (`motor`, its law) and
/// `servo` (a PID law).
fn servo_pendulum_text(g: f64, motor: &str) -> String {
    [
        pendulum(&[]),
        gravity("weight", [0.0, -g, 0.0]),
        format!(
            r#"[[actuators]]
name = "motor"
joint = "pivot"
{motor}
[[actuators]]
name = "servo"
joint = "pivot"
pid = {{ kp = 50.0, ki = 20.0, kd = 10.0, setpoint = {{ type = "ramp", t_end = 1.0, to = 0.3 }} }}
"#
        ),
        sensor("angle", "joint", "pivot"),
        sensor("rate", "joint-rate", "pivot"),
        sensor("torque", "actuator-effort", "motor"),
        dynamic("20.0", "0.01"),
    ]
    .concat()
}

/// The servo pendulum with gravity `g` (m/s^2, along -y) and the `motor`'s `function`
/// (`None`: zero), its PID servo held at zero effort; a simulation of it. Both actuators give
/// no effort at the start (the servo's set-point starts at zero with zero rate), so the
/// initial accelerations agree with the held values.
fn servo_pendulum(tag: &str, g: f64, motor: Option<&str>) -> Simulation {
    let dir = scratch(tag);
    let text = servo_pendulum_text(
        g,
        motor.unwrap_or(r#"function = { type = "constant-speed", speed = 0.0 }"#),
    );
    let doc = Document::from_text(&text, &dir.join("servo.toml")).unwrap();
    let study = doc.study().unwrap();
    let options = Options {
        out: None,
        cache: Some(dir.join("cache")),
        t_end: None,
        ..Options::default()
    };
    let mut sim = Simulation::new(&study, "dynamic", &options).unwrap();
    assert_eq!(sim.actuator_names(), vec!["motor", "servo"]);
    sim.set_actuator("servo", Some(0.0)).unwrap();
    sim
}

#[test]
fn a_held_actuator_effort_acts_from_the_next_step_until_released() {
    // An effort set between steps is the actuator's value at the end of the next step: the
    // integrator sees it as a study-file function that changes within that step (here a
    // linear ramp over the first step, 0 to M), to round-off.
    let (m, inertia, h) = (0.2, 1.01, 0.01);
    let mut file = servo_pendulum(
        "ramped-actuator",
        0.0,
        Some(r#"function = { type = "ramp", t_end = 0.01, to = 0.2, smooth = false }"#),
    );
    file.advance_to(0.5).unwrap();
    let mut sim = servo_pendulum("held-actuator", 0.0, None);
    assert_eq!(sim.held_actuator("motor").unwrap(), None);
    sim.set_actuator("motor", Some(m)).unwrap();
    assert_eq!(sim.held_actuator("motor").unwrap(), Some(m));
    // The actuator-effort sensor writes the held value.
    assert_eq!(sim.sensor("torque").unwrap(), vec![m]);
    assert_eq!(sim.actuator_effort("motor").unwrap(), m);
    sim.advance_to(0.5).unwrap();
    let theta = sim.sensor("angle").unwrap()[0];
    let reference = file.sensor("angle").unwrap()[0];
    // The same values at every step end; the Newton iterates may differ in the last bits.
    assert!((theta - reference).abs() < 1e-12, "{theta} against {reference}");
    // Without gravity the pendulum turns as a rigid rotor under the torque's ramp over the
    // first step and M after it: theta = M (t - h/2)^2 / (2 I) + M h^2 / (24 I). The
    // integrator sees the ramp at its ends only: an error of order M h^2 / I = 2e-5 rad.
    let t = sim.time();
    let expected = m * (t - h / 2.0).powi(2) / (2.0 * inertia) + m * h * h / (24.0 * inertia);
    assert!((theta - expected).abs() < 2e-5, "{theta} against {expected}");
    // Released: its law (zero) acts again. (The release is stepped in the PD test below.)
    sim.set_actuator("motor", None).unwrap();
    assert_eq!(sim.held_actuator("motor").unwrap(), None);
    assert_eq!(sim.actuator_effort("motor").unwrap(), 0.0);
    assert_eq!(sim.sensor("torque").unwrap(), vec![0.0]);
    // An unknown actuator is named with the close matches; a non-finite effort is refused.
    let e = sim.set_actuator("motr", Some(1.0)).unwrap_err().to_string();
    assert!(e.contains("motor"), "{e}");
    let e = sim.set_actuator("motor", Some(f64::NAN)).unwrap_err().to_string();
    assert!(e.contains("actuator 'motor'") && e.contains("finite"), "{e}");
}

#[test]
fn a_pd_loop_closed_outside_the_study_reaches_its_equilibrium_under_gravity() {
    // A PD law computed between steps from the sensors and held on `motor` for the next step:
    // u = kp (r - theta) - kd theta_dot. Under gravity the loop settles where the torque
    // balances the weight, kp (r - theta) = m g L sin(theta), with an offset a PD cannot
    // remove (solved here by Newton, independently of the simulation).
    let (kp, kd, r, g) = (30.0, 8.0, 0.5, 9.81);
    let mut sim = servo_pendulum("pd-actuator", g, None);
    let mut torque = 0.0;
    while sim.time() < 15.0 {
        let theta = sim.sensor("angle").unwrap()[0];
        let rate = sim.sensor("rate").unwrap()[0];
        torque = kp * (r - theta) - kd * rate;
        sim.set_actuator("motor", Some(torque)).unwrap();
        sim.step().unwrap();
    }
    let mut expected: f64 = r;
    for _ in 0..50 {
        let f = kp * (r - expected) - g * expected.sin();
        expected += f / (kp + g * expected.cos());
    }
    let theta = sim.sensor("angle").unwrap()[0];
    // Closed-loop poles: I s^2 + kd s + kp + m g L cos(theta) = 0, decay rate kd / (2 I) =
    // 4 1/s: after 15 s e^-60 of the start's error is left; the one-step delay of the loop
    // (0.01 s against a period of 1.2 s) changes the damping, not the equilibrium.
    assert!((theta - expected).abs() < 1e-8, "{theta} against {expected}");
    assert!((torque - g * expected.sin()).abs() < 1e-6, "{torque}");
    // The servo was held at zero all along: released, its PID (set-point 0.3 rad since t = 1
    // s, an integral frozen at zero while held) pulls the pendulum to 0.3 rad.
    sim.set_actuator("motor", Some(0.0)).unwrap();
    sim.set_actuator("servo", None).unwrap();
    sim.advance_to(40.0).unwrap();
    let theta = sim.sensor("angle").unwrap()[0];
    // The integral removes the steady error under gravity (closed-loop poles of I s^3 + kd
    // s^2 + (kp + m g L cos 0.3) s + ki: the slowest near -0.34 1/s, so e^-8 of the 0.2 rad
    // error is left after 25 s).
    assert!((theta - 0.3).abs() < 1e-3, "{theta}");
}

/// A controller reads sensors by name between steps: each sensor's columns are those of the
/// full row (`read`), found through the index built when the simulation is set up. An
/// unknown name is refused with the close matches; a sensor whose model sensor the system
/// lacks is refused at set-up, naming both.
#[test]
fn sensors_read_by_name_are_the_columns_of_the_full_row() {
    let mut sim = servo_pendulum(
        "sensor-index",
        9.81,
        Some(r#"function = { type = "ramp", t_end = 0.01, to = 0.2, smooth = false }"#),
    );
    for _ in 0..3 {
        sim.step().unwrap();
    }
    let row = sim.read().unwrap();
    for (g, v) in sim.sensors().iter().zip(&row) {
        assert_eq!(&sim.sensor(&g.name).unwrap(), v, "sensor {}", g.name);
    }
    assert!(row[0][0] != 0.0, "the pendulum has moved");
    let e = sim.sensor("angel").unwrap_err().to_string();
    assert!(e.contains("angle"), "{e}");

    let mut groups = sim.sensors().to_vec();
    groups[1].mbs_names.push("nowhere".into());
    let record = sim.system().sensor_record();
    let e = study::sensor_columns(&groups, &record).unwrap_err().to_string();
    assert!(e.contains("sensor 'rate'") && e.contains("no sensor 'nowhere'"), "{e}");
}

/// An observer that keeps the stages of long computations only.
#[derive(Default)]
struct Stages(Vec<String>);

impl Observer for Stages {
    fn progress(&mut self, p: &study::output::observer::Progress) {
        if let study::output::observer::Progress::Stage(s) = p {
            self.0.push(s.clone());
        }
    }
}

fn options_in(dir: &Path, t_end: Option<f64>) -> Options {
    Options {
        out: Some(dir.join("results")),
        cache: Some(dir.join("cache")),
        t_end,
        ..Options::default()
    }
}

/// Every study in `examples/` is a built-in example, and each runs to completion through the
/// library, whatever is added later: every analysis of the file is recorded, done, with its
/// summary (dynamic analyses shortened to 10 ms, as `--t-end 0.01` does).
#[test]
fn every_example_runs_through_the_library() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut on_disk: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    on_disk.sort();
    let mut built_in: Vec<String> = study::input::examples::EXAMPLES
        .iter()
        .map(|e| e.name.to_string())
        .collect();
    built_in.sort();
    assert_eq!(on_disk, built_in, "examples/ and the built-in examples differ");
    for name in &built_in {
        let file = example_as(name, &format!("every-{name}"));
        let study = study::load(&file).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mut seen = Recorder::default();
        study::run_with(&study, &options_in(file.parent().unwrap(), Some(0.01)), &mut seen)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(seen.analyses.len(), study.analyses.len(), "{name}: analyses recorded");
        for a in &seen.analyses {
            let summary = a
                .summary
                .as_ref()
                .unwrap_or_else(|| panic!("{name}/{}: no summary", a.name));
            assert_eq!(
                summary.status,
                study::output::summary::Status::Done,
                "{name}/{}",
                a.name
            );
        }
    }
}

/// Static and modal analyses of a part say what they are doing, as the reduction does.
#[test]
fn static_and_modal_analyses_report_their_stages() {
    let file = example_as("cantilever", "stages");
    let study = study::load(&file).unwrap();
    let mut obs = Stages::default();
    study::run_with(&study, &options_in(file.parent().unwrap(), None), &mut obs).unwrap();
    assert!(obs.0.iter().any(|s| s.contains("factorising K")), "{:?}", obs.0);
    assert!(obs.0.iter().any(|s| s.contains("6 modes of")), "{:?}", obs.0);
}

/// A study without analyses is an error (exit code 2 in the program), not a silent success.
#[test]
fn a_study_without_analyses_is_an_error() {
    let dir = scratch("empty");
    let file = dir.join("empty.toml");
    std::fs::write(&file, "[study]\ntitle = \"nothing to do\"\n").unwrap();
    let study = study::load(&file).unwrap();
    let e = study::run_with(&study, &options_in(&dir, None), &mut Recorder::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("no [[analyses]]") && e.contains("empty.toml"), "{e}");
}

/// `--t-end` that shortens a dynamic analysis says so in the report and the summary; fixed
/// joints are counted among the joints.
#[test]
fn the_summary_says_when_t_end_shortened_the_run_and_counts_fixed_joints() {
    let file = example_as("spin_up", "t-end-spin-up");
    let study = study::load(&file).unwrap();
    let mut rec = Recorder::default();
    study::run_with(&study, &options_in(file.parent().unwrap(), Some(0.02)), &mut rec).unwrap();
    let s = rec.analyses[0].summary.as_ref().unwrap();
    assert!(
        s.report[0].contains("shortened by --t-end") && s.report[0].contains("t_end = 30"),
        "{:?}",
        s.report
    );
    assert_eq!(s.results["t_end_study"], serde_json::json!(30.0));
    assert_eq!(s.results["t_end_option"], serde_json::json!(0.02));
    // Three welds between the four segments and the hub's revolute joint.
    assert!(
        s.report.iter().any(|l| l.contains("4 joints (3 fixed)")),
        "{:?}",
        s.report
    );
    // A --t-end beyond the study's end shortens nothing and says nothing.
    let mut rec = Recorder::default();
    let file = example_as("four_bar", "t-end-four-bar");
    let study = study::load(&file).unwrap();
    study::run_with(&study, &options_in(file.parent().unwrap(), Some(100.0)), &mut rec).ok();
    for a in &rec.analyses {
        if let Some(s) = &a.summary {
            assert!(!s.report.iter().any(|l| l.contains("shortened")), "{:?}", s.report);
        }
    }
}

/// The numbers of a `DataArray` named `name` in a VTU text.
fn vtu_array(text: &str, name: &str) -> Option<Vec<f64>> {
    let start = text.find(&format!("Name=\"{name}\""))?;
    let body = &text[start..];
    let open = body.find('>')? + 1;
    let close = body.find("</DataArray>")?;
    Some(
        body[open..close]
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect(),
    )
}

/// The mechanism's VTU files carry displacement, rotation, velocity and the body of each
/// point, and every point belongs to a cell (the spiders' interface nodes included).
#[test]
fn mechanism_vtu_has_rotation_velocity_body_and_no_orphan_points() {
    let file = example_as("four_bar", "vtu-four-bar");
    let dir = file.parent().unwrap();
    let study = study::load(&file).unwrap();
    let mut rec = Recorder::default();
    study::run(&study, &options_in(dir, Some(0.02)), &mut rec).unwrap();
    let vtu = dir.join("results/dynamic/mechanism_00002.vtu");
    let text = std::fs::read_to_string(&vtu).unwrap();
    let n_points = vtu_array(&text, "displacement").unwrap().len() / 3;
    for (name, width) in [("rotation", 3), ("velocity", 3), ("body", 1)] {
        let values = vtu_array(&text, name).unwrap_or_else(|| panic!("no point field {name}"));
        assert_eq!(values.len(), width * n_points, "{name}");
    }
    // Three bodies (the coupler, then the crank and the rocker): every index is used.
    let body = vtu_array(&text, "body").unwrap();
    for b in [0.0, 1.0, 2.0] {
        assert!(body.contains(&b), "body {b} missing");
    }
    // The crank turns at up to 20 rad/s: its points move, and rotate about z only.
    let velocity = vtu_array(&text, "velocity").unwrap();
    assert!(velocity.iter().any(|v| v.abs() > 1e-6));
    let connectivity = vtu_array(&text, "connectivity").unwrap();
    let mut used = vec![false; n_points];
    for i in connectivity {
        used[i as usize] = true;
    }
    let orphans: Vec<usize> = (0..n_points).filter(|i| !used[*i]).collect();
    assert!(orphans.is_empty(), "points in no cell: {orphans:?}");
}

/// A sensor's columns share a plot axis only when they share a unit and a size.
#[test]
fn plot_panels_separate_units_and_sizes() {
    let h = |s: &[&str]| s.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    // The spin-up tip in the hub's axes: x near 10 m, y a deflection of decimetres, z zero to
    // round-off (drawn with y, not on an axis of its own).
    let tip = h(&[
        "relative_position_x [m]",
        "relative_position_y [m]",
        "relative_position_z [m]",
    ]);
    let panels = study::output::folder::plot_panels(&tip, &[vec![10.0, 10.0], vec![0.0, -0.4], vec![0.0, 1e-20]]);
    assert_eq!(panels, vec![vec![0], vec![1, 2]]);
    // A reaction: forces and moments never share an axis.
    let reaction = h(&["Fx [N]", "Fy [N]", "Fz [N]", "Mx [N m]", "My [N m]", "Mz [N m]"]);
    let c = vec![vec![1.0, 2.0]; 6];
    assert_eq!(
        study::output::folder::plot_panels(&reaction, &c),
        vec![vec![0, 1, 2], vec![3, 4, 5]]
    );
    // Energies of one size: one axis.
    let energy = h(&["kinetic [J]", "strain [J]", "gravity potential [J]"]);
    let c = vec![vec![0.2, 0.3], vec![0.0, 0.1], vec![0.2, 0.25]];
    assert_eq!(study::output::folder::plot_panels(&energy, &c), vec![vec![0, 1, 2]]);
}

/// Options writing into `<study dir>/results` with the cache in `<study dir>/cache`.
fn into_results(file: &Path) -> Options {
    let dir = file.parent().unwrap();
    Options {
        out: Some(dir.join("results")),
        cache: Some(dir.join("cache")),
        ..Options::default()
    }
}

#[test]
fn a_results_folder_deletes_only_what_flexmbs_wrote() {
    use study::output::folder::{ForeignFiles, MANIFEST};
    let file = example_as("cantilever", "folder-cantilever");
    let study = study::load(&file).unwrap();
    let options = into_results(&file);
    let out = options.out.clone().unwrap();
    let a = study.analyses[0].name.clone();
    // A user's own file where an analysis writes: refused, and left alone.
    std::fs::create_dir_all(out.join(&a)).unwrap();
    let mine = out.join(&a).join("measurements.csv");
    std::fs::write(&mine, "t,x\n0,1\n").unwrap();
    let e = study::run(&study, &options, &mut Recorder::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("measurements.csv") && e.contains("did not write"), "{e}");
    assert!(e.contains("--foreign-files keep"), "{e}");
    // Asked to write beside it: it is kept, through two runs.
    let keep = Options {
        foreign: ForeignFiles::Keep,
        ..options.clone()
    };
    for _ in 0..2 {
        study::run(&study, &keep, &mut Recorder::default()).unwrap();
        assert_eq!(std::fs::read_to_string(&mine).unwrap(), "t,x\n0,1\n");
    }
    // Files of an earlier run that this one does not write (a stale plot, the folder of an
    // analysis removed from the study) go; the manifest knows them.
    let manifest = out.join(MANIFEST);
    std::fs::create_dir_all(out.join("removed")).unwrap();
    std::fs::write(out.join("removed/old.csv"), "x\n").unwrap();
    std::fs::write(out.join(&a).join("stale.png"), "png").unwrap();
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text.push_str(&format!("removed/old.csv\n{a}/stale.png\n"));
    std::fs::write(&manifest, text).unwrap();
    study::run(&study, &keep, &mut Recorder::default()).unwrap();
    assert!(!out.join("removed").exists());
    assert!(!out.join(&a).join("stale.png").exists());
    assert!(mine.is_file());
    // Without the user's file, the default refuses nothing: every other file is listed.
    std::fs::remove_file(&mine).unwrap();
    let summary = study::run(&study, &options, &mut Recorder::default()).unwrap();
    assert_eq!(summary.status, "complete");
    // An empty results path is an error, not the current folder.
    let empty = Options {
        out: Some(PathBuf::new()),
        ..options.clone()
    };
    let e = study::run(&study, &empty, &mut Recorder::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("''"), "{e}");
}

#[test]
fn a_results_folder_in_use_is_refused_and_a_killed_runs_folder_is_free() {
    use study::output::folder::LOCK;
    let file = example_as("cantilever", "lock-cantilever");
    let study = study::load(&file).unwrap();
    let options = into_results(&file);
    let out = options.out.clone().unwrap();
    std::fs::create_dir_all(&out).unwrap();
    // Another run holds the operating-system lock (here this process, through its own open
    // file: such locks conflict between open files, even of one process).
    std::fs::write(out.join(LOCK), format!("{}\n", std::process::id())).unwrap();
    let held = std::fs::File::open(out.join(LOCK)).unwrap();
    held.try_lock().unwrap();
    let e = study::run(&study, &options, &mut Recorder::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("in use by another flexmbs run"), "{e}");
    assert!(
        e.contains(&format!("(process {})", std::process::id())) && e.contains(LOCK),
        "{e}"
    );
    assert!(!out.join("summary.json").exists(), "the refused run wrote nothing");
    // The holder ends (a run killed hard: the system drops its lock): the folder is free,
    // whatever its lock file says.
    drop(held);
    std::fs::write(out.join(LOCK), "4294967295\n").unwrap();
    study::run(&study, &options, &mut Recorder::default()).unwrap();
    // The lock file stays, unlocked.
    let after = std::fs::File::open(out.join(LOCK)).unwrap();
    after.try_lock().unwrap();
}

#[test]
fn a_failed_write_names_its_file_and_leaves_no_temporary() {
    let dir = scratch("failed-write");
    // The target is a folder holding a file: the rename fails after the write.
    std::fs::create_dir_all(dir.join("summary.json/x")).unwrap();
    let e = study::output::summary::write_atomic(&dir.join("summary.json"), b"{}").unwrap_err();
    assert!(e.to_string().contains("summary.json"), "{e}");
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(
        left,
        vec![std::ffi::OsString::from("summary.json")],
        "temporaries left: {left:?}"
    );
    // A symbolic link (to /dev/full) under a sensor file's name: nothing is written through
    // it; the error names that file, not the summary, and the link stays. (A full disk itself:
    // the program's tests under a file-size limit, crates/cli/tests/cli/results_folder.rs.)
    let file = example_as("four_bar", "full-four-bar");
    let study = study::load(&file).unwrap();
    let options = Options {
        t_end: Some(0.01),
        foreign: study::output::folder::ForeignFiles::Keep,
        ..into_results(&file)
    };
    let dynamic = study.analyses.iter().find(|a| a.kind_name() == "dynamic").unwrap();
    let sensor = &study.mechanism.sensors[0].name;
    let target = options.out.clone().unwrap().join(&dynamic.name);
    std::fs::create_dir_all(&target).unwrap();
    std::os::unix::fs::symlink("/dev/full", target.join(format!("{sensor}.csv"))).unwrap();
    let e = study::error::report(&*study::run(&study, &options, &mut Recorder::default()).unwrap_err());
    assert!(
        e.contains(&format!("{sensor}.csv")) && e.contains("is a symbolic link"),
        "{e}"
    );
    assert!(!e.contains("cannot write the summary"), "{e}");
    let link = target.join(format!("{sensor}.csv"));
    assert_eq!(std::fs::read_link(&link).unwrap(), Path::new("/dev/full"));
}

#[test]
fn two_studies_run_concurrently_on_one_cache() {
    // Two copies of one study in two folders, one cache: both reduce the same parts at the
    // same time, and both complete with sound cache files.
    let cache = scratch("shared-cache");
    let files = [
        example_as("cantilever", "concurrent-a"),
        example_as("cantilever", "concurrent-b"),
    ];
    let runs: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = files
            .iter()
            .map(|file| {
                let cache = cache.clone();
                s.spawn(move || {
                    let study = study::load(file).unwrap();
                    let options = Options {
                        cache: Some(cache),
                        ..into_results(file)
                    };
                    study::run(&study, &options, &mut Recorder::default()).map(|s| s.status)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for r in &runs {
        assert_eq!(r.as_deref().map_err(|e| e.to_string()), Ok("complete"));
    }
    for e in std::fs::read_dir(&cache).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        assert!(!name.contains("tmp"), "temporary left in the cache: {name}");
        if name.ends_with(".rbody") {
            reduction::file::read(&e.path()).unwrap();
        }
    }
    // Rerun: found in the cache (the key files match).
    let study = study::load(&files[0]).unwrap();
    let mut rec = Recorder::default();
    let options = Options {
        cache: Some(cache.clone()),
        ..into_results(&files[0])
    };
    study::run(&study, &options, &mut rec).unwrap();
    assert!(
        rec.progress.iter().any(|p| p.contains("found in the cache")),
        "{:?}",
        rec.progress
    );
    // One study twice at once into one results folder: one of them stops at the lock.
    let runs: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|_| {
                let (study, options) = (&study, &options);
                s.spawn(move || study::run(study, options, &mut Recorder::default()).map_err(|e| e.to_string()))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let refused = runs
        .iter()
        .filter(|r| r.as_ref().is_err_and(|e| e.contains("in use")))
        .count();
    assert!(
        refused <= 1 && runs.iter().filter(|r| r.is_ok()).count() >= 1,
        "{runs:?}"
    );
}

#[test]
fn a_cached_body_is_never_trusted_by_its_name() {
    let file = example_as("cantilever", "cache-trust");
    let study = study::load(&file).unwrap();
    let options = into_results(&file);
    study::run(&study, &options, &mut Recorder::default()).unwrap();
    let cache = options.cache.clone().unwrap();
    let body_file = std::fs::read_dir(&cache)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|e| e == "rbody"))
        .unwrap();
    // A different, sound body under the cached name (here: the same one without its mesh
    // shapes): its bytes no longer match the recorded hash, so the part is reduced again.
    let mut body = reduction::file::read(&body_file).unwrap();
    body.mesh = None;
    reduction::file::write(&body, &body_file).unwrap();
    let mut rec = Recorder::default();
    study::run(&study, &options, &mut rec).unwrap();
    assert!(
        rec.progress.iter().any(|p| p.contains("does not record the inputs")),
        "{:?}",
        rec.progress
    );
}

/// Fuzzing of the study parser and validator with the shared seeded mutator
/// (`fe_model::fuzz`: numbers replaced by extreme ones, lines moved or cut), a fixed budget per
/// built-in example: every mutant is a study or an error, never a panic.
#[test]
fn study_file_mutants_never_panic() {
    let mut m = fe_model::fuzz::Mutator::new(0x7374_7564_7966_7a01);
    for example in study::input::examples::EXAMPLES {
        let file = study::input::examples::write(example.name, &scratch(&format!("fuzz-{}", example.name))).unwrap();
        let text = std::fs::read(&file).unwrap();
        for case in 0..fe_model::fuzz::budget(150) {
            let mutant = String::from_utf8_lossy(&m.mutate(&text)).into_owned();
            let r = std::panic::catch_unwind(|| match Document::from_text(&mutant, &file) {
                Ok(doc) => doc.study().map(|_| ()).map_err(|e| e.to_string()),
                Err(e) => Err(e.to_string()),
            });
            assert!(r.is_ok(), "{} mutant {case} panicked:\n{mutant}", example.name);
        }
    }
}

/// A model error found when the mechanism is assembled points at the study-file line of the
/// entity its ids name (`mbs::ModelError::entities`): the closed loop at its first body, the
/// coordinate held by nothing at its joint.
#[test]
fn model_errors_point_at_the_line_of_their_entity() {
    let dir = scratch("model-errors");
    let body = |name: &str, points: &str| {
        format!(
            "[[rigid_bodies]]\nname = \"{name}\"\nmass = 0.1\ncenter_of_mass = [0.05, 0.0, 0.0]\n\
             inertia = [[1e-5, 0.0, 0.0], [0.0, 1e-4, 0.0], [0.0, 0.0, 1e-4]]\npoints = {{ {points} }}\n\n"
        )
    };
    let joint = |name: &str, a: &str, b: &str| {
        format!("[[joints]]\nname = \"{name}\"\ntype = \"revolute\"\nbetween = [\"{a}\", \"{b}\"]\naxis = [0.0, 0.0, 1.0]\n\n")
    };
    let error = |name: &str, text: String| -> String {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        let st = study::load(&file).unwrap();
        let b = study::build_mechanism(&st, &dir.join("cache"), &mut ()).unwrap();
        match b.system(&st) {
            Ok(_) => panic!("{name}: assembled"),
            Err(e) => e.to_string(),
        }
    };
    // Crank (line 3), coupler (line 10) and a hinge support close a loop of rigid bodies.
    let text = "# a four-bar without its flexible rocker\n\n".to_string()
        + &body("crank", "O = [0.0, 0.0, 0.0], A = [0.1, 0.0, 0.0]")
        + &body("coupler", "A = [0.1, 0.0, 0.0], B = [0.1, 0.2, 0.0]")
        + "[[supports]]\nat = \"coupler.B\"\ntype = \"hinge\"\naxis = [0.0, 0.0, 1.0]\n\n"
        + &joint("pivot", "ground", "crank.O")
        + &joint("elbow", "crank.A", "coupler.A")
        + "[[analyses]]\ntype = \"equilibrium\"\n";
    let e = error("rigid_loop.toml", text);
    assert!(
        e.contains("rigid_loop.toml:3:1: rigid_bodies[0]: the mechanism cannot be assembled: closed loop"),
        "{e}"
    );
    // A point mass on its pivot: the pivot's angle (joint on line 10) is held by nothing.
    let text = "# no inertia about the pivot\n\n[[rigid_bodies]]\nname = \"arm\"\nmass = 0.1\n\
                center_of_mass = [0.0, 0.0, 0.0]\ninertia = [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]\n\
                points = { O = [0.0, 0.0, 0.0] }\n\n"
        .to_string()
        + &joint("pivot", "ground", "arm.O")
        + "[[analyses]]\ntype = \"dynamic\"\nt_end = 0.01\ndt = 0.001\n";
    let e = error("unheld.toml", text);
    assert!(
        e.contains(
            "unheld.toml:10:1: joints[0]: the mechanism cannot be assembled: joint 'pivot' angle is held by nothing"
        ),
        "{e}"
    );
}

/// One reduced body per part, shared, not copied, by the bodies made of it, the model and the
/// system's superelements: the elastica's four segments are one part.
#[test]
fn reduced_bodies_are_shared_not_copied() {
    use std::sync::Arc;
    let file = example("elastica");
    let st = study::load(&file).unwrap();
    let b = study::build_mechanism(&st, &file.parent().unwrap().join("cache"), &mut ()).unwrap();
    assert_eq!(b.bodies.len(), 4);
    let first = Arc::clone(&b.bodies[0].reduced);
    let sys = b.system(&st).unwrap();
    for body in &b.bodies {
        assert!(Arc::ptr_eq(&body.reduced, &first), "{}", body.name);
        let mbs::Body::Flexible(f) = &b.model.bodies[body.id.index()] else {
            panic!("{} is not flexible", body.name)
        };
        assert!(Arc::ptr_eq(&f.reduced, &first), "{}", body.name);
        let se = sys.superelement(body.id).unwrap();
        assert!(Arc::ptr_eq(se.reduced_body(), &first), "{}", body.name);
    }
    // The holders: `first` here, per body its output entry, its model body, the system's copy
    // of the model and its superelement; nothing holds a copy of the data.
    assert_eq!(Arc::strong_count(&first), 1 + 4 * 4);
}

/// The elastica example under a tip load 1e10 times its own: Newton's first correction bends
/// the clamped segment so far that its interfaces no longer fix a floating frame, and the
/// load stepping gives up at its smallest increment. (Under 1e6 times the load the frame
/// solve follows the segments and the equilibrium converges, stretched 24-fold.) The solver's error names the body
/// (`mbs::SolveError::entity`); the run's error is located at that body's `[[bodies]]` entry.
#[test]
fn a_solver_failure_at_a_body_is_located_at_the_body_in_the_study_file() {
    let file = example_as("elastica", "located-solver-failure");
    let text = std::fs::read_to_string(&file)
        .unwrap()
        .replace("force = [0.0, 3.0, 0.0]", "force = [0.0, 3.0e10, 0.0]");
    std::fs::write(&file, &text).unwrap();
    let study = study::load(&file).unwrap();
    let options = Options {
        out: Some(file.parent().unwrap().join("results")),
        cache: Some(file.parent().unwrap().join("cache")),
        ..Options::default()
    };
    let e = study::run_with(&study, &options, &mut Recorder::default()).unwrap_err();
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(&*e);
    let stopped = loop {
        let c = cause.expect("a SolverStopped in the chain");
        if let Some(s) = c.downcast_ref::<study::error::SolverStopped>() {
            break s;
        }
        cause = c.source();
    };
    let mbs::SolveError::Body { body, at, step, .. } = &stopped.source else {
        panic!("expected a body's frame to fail: {}", study::error::chain(&*e));
    };
    // An equilibrium stops at a load factor in a load step, not at a time.
    let (mbs::At::LoadFactor(lambda), Some(step)) = (at, step) else {
        panic!("a load factor and step: {at:?} {step:?}");
    };
    assert_eq!(Some(*step), stopped.step);
    let said = format!("body '{body}' at load factor {lambda:.6} (step {step})");
    assert!(
        study::error::chain(&*e).contains(&said),
        "{said}: {}",
        study::error::chain(&*e)
    );
    assert!(
        !study::error::chain(&*e).contains("t = "),
        "{}",
        study::error::chain(&*e)
    );
    let index = study.mechanism.bodies.iter().position(|b| &b.name == body).unwrap();
    let at = stopped.location.as_ref().expect("the body is located");
    assert_eq!(at.key.to_string(), format!("bodies[{index}]"));
    assert_eq!(at.file, file);
    // The line is the body's entry: its table starts there or its `name` is on it.
    let (line, _) = at.line_column.unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let entry = lines
        .iter()
        .enumerate()
        .filter(|(_, l)| l.trim() == "[[bodies]]")
        .nth(index)
        .unwrap()
        .0
        + 1;
    assert!(line == entry || line == entry + 1, "line {line}, entry at {entry}");
    assert_eq!(lines[entry].trim(), format!("name = \"{body}\""));
    // The message says where, in front of what stopped: `file:line:col: bodies[i]: ...`.
    let message = study::error::chain(&*e);
    assert!(
        message.contains(&format!("{at}: bodies[{index}]: equilibrium stopped")),
        "{message}"
    );
}

/// A simulation stepped by hand locates a solver error at the body it names
/// (`Simulation::locate`), as the Python package reports it; an error about no entity has no
/// location.
#[test]
fn a_simulation_locates_a_solver_error_at_its_body() {
    let file = example_as("four_bar", "simulation-locate");
    let study = study::load(&file).unwrap();
    let dynamic = study.analyses.iter().find(|a| a.kind_name() == "dynamic").unwrap();
    let options = Options {
        out: None,
        cache: Some(file.parent().unwrap().join("cache")),
        ..Options::default()
    };
    let sim = Simulation::new(&study, &dynamic.name, &options).unwrap();
    let error = |id: u32| mbs::SolveError::Body {
        body: "link".into(),
        id: mbs::BodyId(id),
        at: mbs::At::Time(0.0),
        step: None,
        source: Box::new(superelement::SuperelementError::SingularFrame { rcond: 0.0 }),
    };
    let at = sim.locate(&error(0)).expect("body 0 is in the study");
    assert_eq!(at.key.to_string(), "bodies[0]");
    assert!(at.line_column.is_some());
    let not_converged = mbs::SolveError::NotConverged {
        at: mbs::At::Time(0.0),
        step: 1,
        residual: 1.0,
        iterations: 20,
    };
    assert!(sim.locate(&not_converged).is_none());
}

/// Linearised verdicts at every size and in any units (steel cantilevers of 20 mm, 2 m, 200 m
/// and in mm-t-s units against the clamped part's FE modes); sensors that are not finite stop
/// the equilibrium, buckling and linearised analyses.
#[path = "study/stability.rs"]
mod stability;

/// The validator against the corpus of broken study files and random and mutated files: located
/// messages, never a panic.
#[path = "study/broken_files.rs"]
mod broken_files;

/// Models from other codes: Abaqus and Nastran meshes, MBDyn bodies, Matrix Market matrices.
#[path = "study/import.rs"]
mod import;

/// Our node orders mapped into VTK's, against VTK's cell definitions.
#[path = "study/vtu.rs"]
mod vtu;

/// A force law of a run: an elbow damper written as a law gives the motion of the study's PID,
/// in a run and in a stepped simulation; unknown names refused with those there are.
#[path = "study/force_law.rs"]
mod force_law;

/// A dynamic analysis as an FMU: the archive read back, its instance stepped against the
/// simulation it wraps, bit for bit; states saved and restored; parameters and inputs checked.
#[path = "study/fmu.rs"]
mod fmu;
