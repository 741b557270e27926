//! The study layer without the program: a study edited by key path with located errors, a
//! run observed in memory against the results folder it writes, and a simulation stepped by
//! hand against the `dynamic` analysis of a run.

use std::path::{Path, PathBuf};
use study::observer::{Observer, Recorder};
use study::run::Options;
use study::{Document, Simulation};

/// Mechanisms set up in study files (initial states, `start`, actuators, springs, stops,
/// buckling, adaptive and retried steps) against independent solutions.
#[path = "study/setup.rs"]
mod setup;

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("study-tests-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The built-in example `name` written into a scratch folder; its study file.
fn example(name: &str) -> PathBuf {
    study::examples::write(name, &scratch(name)).unwrap()
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
fn a_run_observed_in_memory_matches_its_results_folder() {
    let file = example("cantilever");
    let study = study::load(&file).unwrap();
    let out = file.parent().unwrap().join("results");
    let options = Options {
        out: Some(out.clone()),
        cache: Some(file.parent().unwrap().join("cache")),
        t_end: None,
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
