//! The study layer without the program: a study edited by key path with located errors, a
//! run observed in memory against the results folder it writes, and a simulation stepped by
//! hand against the `dynamic` analysis of a run.

use std::path::{Path, PathBuf};
use study::observer::{Observer, Recorder};
use study::run::Options;
use study::{Document, Simulation};

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

/// The built-in example `name` in a scratch folder of its own, `tag`.
fn example_as(name: &str, tag: &str) -> PathBuf {
    study::examples::write(name, &scratch(tag)).unwrap()
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
    assert!(e.contains("four_bar.toml:13:"), "{e}");
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
    use study::folder::{ForeignFiles, MANIFEST};
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
fn a_results_folder_in_use_is_refused_and_a_dead_runs_lock_taken_over() {
    use study::folder::LOCK;
    let file = example_as("cantilever", "lock-cantilever");
    let study = study::load(&file).unwrap();
    let options = into_results(&file);
    let out = options.out.clone().unwrap();
    std::fs::create_dir_all(&out).unwrap();
    // A live process holds it (this one).
    std::fs::write(out.join(LOCK), format!("{}\n", std::process::id())).unwrap();
    let e = study::run(&study, &options, &mut Recorder::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("in use by another flexmbs run"), "{e}");
    assert!(!out.join("summary.json").exists(), "the refused run wrote nothing");
    // A process that does not exist (above Linux's largest pid, 2^22): taken over, released.
    std::fs::write(out.join(LOCK), "4294967295\n").unwrap();
    study::run(&study, &options, &mut Recorder::default()).unwrap();
    assert!(!out.join(LOCK).exists());
}

#[test]
fn a_failed_write_names_its_file_and_leaves_no_temporary() {
    let dir = scratch("failed-write");
    // The target is a folder holding a file: the rename fails after the write.
    std::fs::create_dir_all(dir.join("summary.json/x")).unwrap();
    let e = study::output::write_atomic(&dir.join("summary.json"), b"{}").unwrap_err();
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
    // A full disk (/dev/full) under a sensor file: the error names that file, not the summary.
    let file = example_as("four_bar", "full-four-bar");
    let study = study::load(&file).unwrap();
    let options = Options {
        t_end: Some(0.01),
        foreign: study::folder::ForeignFiles::Keep,
        ..into_results(&file)
    };
    let dynamic = study.analyses.iter().find(|a| a.kind_name() == "dynamic").unwrap();
    let sensor = &study.mechanism.sensors[0].name;
    let target = options.out.clone().unwrap().join(&dynamic.name);
    std::fs::create_dir_all(&target).unwrap();
    std::os::unix::fs::symlink("/dev/full", target.join(format!("{sensor}.csv"))).unwrap();
    let e = study::error::report(&*study::run(&study, &options, &mut Recorder::default()).unwrap_err());
    assert!(
        e.contains(&format!("{sensor}.csv")) && e.contains("No space left"),
        "{e}"
    );
    assert!(!e.contains("cannot write the summary"), "{e}");
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
