//! What a results folder guarantees (docs/study-file.md): a user's file under one of our names
//! is never overwritten nor deleted, nothing is written through a symbolic link, a failed
//! write leaves whole rows and a truthful summary, SIGTERM ends a run with an `interrupted`
//! summary, and the operating-system lock keeps a second run out while the first runs.

use crate::support::{examples_copy, flexmbs, read_csv};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

/// The double pendulum (one dynamic analysis, `dynamic`, with an `energy` sensor) in a
/// scratch folder, run once to 0.05 s into `res`: the folder of an earlier run.
fn pendulum_run(name: &str) -> PathBuf {
    let dir = examples_copy(name);
    let out = flexmbs(
        &dir,
        &["run", "double_pendulum.toml", "--t-end", "0.05", "--out", "res"],
    );
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(dir.join("res/dynamic/energy.csv").is_file());
    dir
}

fn summary(res: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(res.join("summary.json")).unwrap()).unwrap()
}

/// Every file the summary lists exists.
fn assert_listed_files_exist(res: &Path) {
    for a in summary(res)["analyses"].as_array().unwrap() {
        for f in a["files"].as_array().unwrap() {
            assert!(res.join(f.as_str().unwrap()).is_file(), "listed but absent: {f}");
        }
    }
}

const MINE: &str = "my own energy balance\n0,1\n";

/// A short run of the pendulum into `res` that keeps the user's files there.
const KEEP: [&str; 8] = [
    "run",
    "double_pendulum.toml",
    "--t-end",
    "0.05",
    "--out",
    "res",
    "--foreign-files",
    "keep",
];
#[test]
fn a_users_summary_md_and_energy_csv_are_kept_under_foreign_files_keep() {
    let dir = pendulum_run("folder-keep");
    let res = dir.join("res");
    // The user replaces two of our files with their own, under our names.
    std::fs::write(res.join("dynamic/energy.csv"), MINE).unwrap();
    std::fs::write(res.join("summary.md"), "# my notes\n").unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["run", "double_pendulum.toml", "--t-end", "0.05", "--out", "res"];
        args.extend(extra);
        flexmbs(&dir, &args)
    };
    // The default refuses, naming both.
    let out = run(&[]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("did not write"), "{}", out.stderr);
    assert!(
        out.stderr.contains("energy.csv") && out.stderr.contains("summary.md"),
        "{}",
        out.stderr
    );
    // Beside them: the run stops at the first one it would replace, naming it, and keeps it.
    let out = run(&["--foreign-files", "keep"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("refusing to write res/summary.md"),
        "{}",
        out.stderr
    );
    assert_eq!(std::fs::read_to_string(res.join("summary.md")).unwrap(), "# my notes\n");
    // The user moves their notes away: the run goes on to the energy file and stops there.
    std::fs::rename(res.join("summary.md"), dir.join("notes.md")).unwrap();
    let out = run(&["--foreign-files", "keep"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("refusing to write res/dynamic/energy.csv"),
        "{}",
        out.stderr
    );
    assert_eq!(std::fs::read_to_string(res.join("dynamic/energy.csv")).unwrap(), MINE);
    let s = summary(&res);
    assert_eq!(s["status"], "failed");
    assert!(s["reason"].as_str().unwrap().contains("energy.csv"), "{s}");
    assert_listed_files_exist(&res);
}

#[test]
fn a_users_file_in_a_recreated_analysis_folder_is_kept() {
    let dir = pendulum_run("folder-recreated");
    let res = dir.join("res");
    // The user deletes the analysis folder and makes it again with files of their own, one
    // under a name the run writes.
    std::fs::remove_dir_all(res.join("dynamic")).unwrap();
    std::fs::create_dir(res.join("dynamic")).unwrap();
    std::fs::write(res.join("dynamic/tip.csv"), MINE).unwrap();
    std::fs::write(res.join("dynamic/notes.txt"), "notes\n").unwrap();
    let out = flexmbs(
        &dir,
        &["run", "double_pendulum.toml", "--t-end", "0.05", "--out", "res"],
    );
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("tip.csv") && out.stderr.contains("notes.txt"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &KEEP);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("refusing to write res/dynamic/tip.csv"),
        "{}",
        out.stderr
    );
    assert_eq!(std::fs::read_to_string(res.join("dynamic/tip.csv")).unwrap(), MINE);
    assert_eq!(
        std::fs::read_to_string(res.join("dynamic/notes.txt")).unwrap(),
        "notes\n"
    );
    assert_listed_files_exist(&res);
    // Without the clash, the run writes beside the user's file and keeps it.
    std::fs::remove_file(res.join("dynamic/tip.csv")).unwrap();
    let out = flexmbs(&dir, &KEEP);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert_eq!(
        std::fs::read_to_string(res.join("dynamic/notes.txt")).unwrap(),
        "notes\n"
    );
    assert_eq!(summary(&res)["status"], "complete");
}

#[test]
fn a_symlinked_analysis_folder_is_refused() {
    let dir = pendulum_run("folder-symlink");
    let res = dir.join("res");
    let elsewhere = dir.join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    std::fs::write(elsewhere.join("energy.csv"), MINE).unwrap();
    std::fs::remove_dir_all(res.join("dynamic")).unwrap();
    std::os::unix::fs::symlink(&elsewhere, res.join("dynamic")).unwrap();
    let link = "res/dynamic";
    let out = flexmbs(
        &dir,
        &["run", "double_pendulum.toml", "--t-end", "0.05", "--out", "res"],
    );
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains(link), "{}", out.stderr);
    let out = flexmbs(&dir, &KEEP);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr
            .contains(&format!("refusing to write into {link}: it is a symbolic link")),
        "{}",
        out.stderr
    );
    // Nothing written through it, nothing deleted behind it.
    let behind: Vec<_> = std::fs::read_dir(&elsewhere)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(behind, ["energy.csv"]);
    assert_eq!(std::fs::read_to_string(elsewhere.join("energy.csv")).unwrap(), MINE);
    assert_eq!(summary(&res)["status"], "failed");
}

/// A disk that fills mid-run, as the system's file-size limit (`ulimit -f`, which holds for
/// every user; SIGXFSZ ignored so the write fails with EFBIG instead) makes it: a sensor file
/// reaches the limit within a row.
#[test]
fn a_full_disk_mid_run_leaves_whole_rows_and_a_failed_summary_listing_existing_files() {
    let dir = pendulum_run("folder-full-disk");
    let res = dir.join("res");
    // 40 KiB: the cached body (32 KB), the meshes and the summary fit; the sensor files of a
    // 2 s run (about 140 KB each) do not. Rows are written in blocks of at most
    // `study::output::folder::FLUSH_BYTES` (16 KiB), so the third block of a file fails,
    // whatever the machine's speed.
    let script = format!(
        "trap '' XFSZ; ulimit -f 40; exec '{}' run double_pendulum.toml --out res",
        env!("CARGO_BIN_EXE_flexmbs")
    );
    let out = Command::new("bash")
        .args(["-c", &script])
        .current_dir(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cannot write") && stderr.contains(".csv"), "{stderr}");
    assert!(stderr.contains("last whole row"), "{stderr}");
    let s = summary(&res);
    assert_eq!(s["status"], "failed", "{s}");
    let reason = s["reason"].as_str().unwrap();
    assert!(reason.contains("time integration stopped at t = "), "{reason}");
    assert_listed_files_exist(&res);
    // Every sensor file ends with a whole row, every cell a number, all at one length.
    let mut lengths = Vec::new();
    for name in ["shoulder", "elbow", "tip", "energy"] {
        let path = res.join(format!("dynamic/{name}.csv"));
        assert!(
            std::fs::read_to_string(&path).unwrap().ends_with('\n'),
            "{name}: a cut row"
        );
        let (header, rows) = read_csv(&path);
        for r in &rows {
            assert_eq!(r.len(), header.len(), "{name}: {r:?}");
            assert!(r.iter().all(|c| c.parse::<f64>().is_ok()), "{name}: {r:?}");
        }
        lengths.push(rows.len());
    }
    assert!(
        lengths[0] > 10 && lengths.iter().all(|n| *n == lengths[0]),
        "{lengths:?}"
    );
    let leftovers: Vec<_> = std::fs::read_dir(res.join("dynamic"))
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// The slider-crank for far longer than a test waits, started in `dir`; returns once its
/// sensor file has a few rows (the run is then mid-integration).
fn long_run(dir: &Path) -> Child {
    let text = std::fs::read_to_string(dir.join("slider_crank.toml"))
        .unwrap()
        .replace("t_end = 0.126", "t_end = 1000.0");
    std::fs::write(dir.join("long.toml"), text).unwrap();
    let mut child = Command::new(env!("CARGO_BIN_EXE_flexmbs"))
        .args(["run", "long.toml"])
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let csv = dir.join("long-results/run-up/rod-mid.csv");
    let rows = |p: &Path| std::fs::read_to_string(p).map(|t| t.lines().count()).unwrap_or(0);
    let start = std::time::Instant::now();
    while rows(&csv) < 5 {
        assert!(child.try_wait().unwrap().is_none(), "the run ended by itself");
        assert!(start.elapsed().as_secs() < 300, "no rows after five minutes");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child
}

fn signal(child: &Child, name: &str) {
    let kill = Command::new("kill")
        .args([name, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
}

#[test]
fn sigterm_ends_a_run_with_an_interrupted_summary() {
    let dir = examples_copy("folder-sigterm");
    let child = long_run(&dir);
    signal(&child, "-TERM");
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("interrupted by SIGTERM"), "{stderr}");
    let res = dir.join("long-results");
    let s = summary(&res);
    assert_eq!(s["status"], "interrupted", "{s}");
    let reason = s["reason"].as_str().unwrap();
    assert!(
        reason.contains("SIGTERM") && reason.contains("stopped at t = "),
        "{reason}"
    );
    assert_listed_files_exist(&res);
    let (header, kept) = read_csv(&res.join("run-up/rod-mid.csv"));
    assert!(kept.len() >= 4 && kept.iter().all(|r| r.len() == header.len()));
}

#[test]
fn a_second_run_is_refused_while_the_first_holds_the_lock() {
    let dir = examples_copy("folder-lock");
    let first = long_run(&dir);
    let res = dir.join("long-results");
    let before = std::fs::read_to_string(res.join("run-up/rod-mid.csv")).unwrap();
    let out = flexmbs(&dir, &["run", "long.toml", "--t-end", "0.01"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr
            .contains(&format!("in use by another flexmbs run (process {})", first.id())),
        "{}",
        out.stderr
    );
    assert!(out.stderr.contains(".flexmbs-lock"), "{}", out.stderr);
    // The first run's files are untouched by the refused one.
    let now = std::fs::read_to_string(res.join("run-up/rod-mid.csv")).unwrap();
    assert!(now.starts_with(&before), "the refused run touched the first run's rows");
    assert_eq!(summary(&res)["status"], "running");
    // The first is killed hard: the system drops its lock, and the folder is free at once.
    signal(&first, "-KILL");
    let _ = first.wait_with_output().unwrap();
    let out = flexmbs(&dir, &["run", "long.toml", "--t-end", "0.01"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert_eq!(summary(&res)["status"], "complete");
}

/// Every run writes the results page `view.html` (its data inside it); `flexmbs view` writes
/// it again from those data and prints its path, and the next run finds the page its own; a
/// page the user put there is refused, and a folder without a page is named.
#[test]
fn the_results_page_is_written_by_every_run_and_again_by_flexmbs_view() {
    let dir = pendulum_run("view-page");
    let res = dir.join("res");
    let page = std::fs::read_to_string(res.join("view.html")).unwrap();
    assert!(page.contains("id=\"flexmbs-data\""), "no data in the page");
    let scene = viewer::data_of_page(&page).unwrap();
    let names: Vec<&str> = scene.analyses.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["dynamic"]);
    let a = &scene.analyses[0];
    assert!(a.frames.len() > 1 && !a.bodies.is_empty() && !a.sensors.is_empty());
    assert!(a.sensors.iter().any(|s| s.name == "energy"));
    assert!(
        std::fs::read_to_string(res.join(".flexmbs-manifest"))
            .unwrap()
            .contains(" view.html\n"),
        "the page is recorded as the run's own"
    );
    let out = flexmbs(&dir, &["view", "res"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert_eq!(
        out.stdout.trim(),
        Path::new("res").join("view.html").display().to_string()
    );
    assert_eq!(std::fs::read_to_string(res.join("view.html")).unwrap(), page);
    let again = flexmbs(
        &dir,
        &["run", "double_pendulum.toml", "--t-end", "0.05", "--out", "res"],
    );
    assert_eq!(again.code, 0, "{}", again.stderr);
    std::fs::write(res.join("view.html"), "<html>my page</html>").unwrap();
    let out = flexmbs(&dir, &["view", "res"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("refusing to rewrite") && out.stderr.contains("view.html"),
        "{}",
        out.stderr
    );
    assert_eq!(
        std::fs::read_to_string(res.join("view.html")).unwrap(),
        "<html>my page</html>"
    );
    let out = flexmbs(&dir, &["view", "nowhere"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("nowhere: no such results folder or study file"),
        "{}",
        out.stderr
    );
    std::fs::create_dir(dir.join("empty")).unwrap();
    let out = flexmbs(&dir, &["view", "empty"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("view.html not found"), "{}", out.stderr);
}

#[test]
fn flexmbs_view_of_a_study_writes_the_model_before_it_runs_and_keeps_a_users_file() {
    let dir = examples_copy("view-model");
    std::fs::copy(dir.join("double_pendulum.toml"), dir.join("pendulum.toml")).unwrap();
    let out = flexmbs(&dir, &["view", "pendulum.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert_eq!(out.stdout.trim(), "pendulum-model.html");
    let page = std::fs::read_to_string(dir.join("pendulum-model.html")).unwrap();
    assert!(page.contains("the model before it runs"), "{}", &page[..200]);
    // Written again over its own page; a user's file of that name is refused and kept.
    assert_eq!(flexmbs(&dir, &["view", "pendulum.toml"]).code, 0);
    std::fs::write(dir.join("pendulum-model.html"), "my notes").unwrap();
    let out = flexmbs(&dir, &["view", "pendulum.toml"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("refusing to overwrite"), "{}", out.stderr);
    assert_eq!(
        std::fs::read_to_string(dir.join("pendulum-model.html")).unwrap(),
        "my notes"
    );
}
