//! The rough edges of the command line a new user meets: `--help` of every command, the
//! validation command's ids and report folder, an empty study, a closed pipe, the progress
//! display.

use super::support::{examples_copy, flexmbs, scratch};
use std::io::Read;
use std::process::{Command, Stdio};

#[test]
fn every_command_has_help_that_exits_0() {
    let dir = scratch("command-help");
    for command in ["run", "check", "reduce", "inspect", "example", "export-fmu"] {
        for flag in ["--help", "-h"] {
            let out = flexmbs(&dir, &[command, flag]);
            assert_eq!(out.code, 0, "{command} {flag}: {}", out.stderr);
            assert!(
                out.stdout.starts_with(&format!("usage: flexmbs {command}")),
                "{command} {flag}: {}",
                out.stdout
            );
        }
    }
    // `help COMMAND` too, and the run option --t-end is listed for run only.
    let out = flexmbs(&dir, &["help", "reduce"]);
    assert_eq!(out.code, 0);
    assert!(!out.stdout.contains("--t-end"), "{}", out.stdout);
    let out = flexmbs(&dir, &["run", "--help"]);
    assert!(out.stdout.contains("--t-end"), "{}", out.stdout);
    let out = flexmbs(&dir, &["--help"]);
    let general = out.stdout;
    let run_only = general
        .split("options of run:")
        .nth(1)
        .expect("an 'options of run' block");
    assert!(run_only.contains("--t-end"), "{general}");
    let both = general.split("options of run and reduce:").nth(1).unwrap();
    let both = both.split("options of run:").next().unwrap();
    assert!(!both.contains("--t-end"), "{general}");
}

/// `validate` calls itself by the name it was run as.
#[cfg(feature = "validate")]
#[test]
fn validate_has_help_under_its_own_name() {
    let dir = scratch("validate-help");
    let out = flexmbs(&dir, &["validate", "--help"]);
    assert_eq!(out.code, 0);
    assert!(out.stdout.starts_with("usage: flexmbs validate"), "{}", out.stdout);
}

/// Without the `validate` feature the program does not carry the suite, and says how to run it.
#[cfg(not(feature = "validate"))]
#[test]
fn validate_without_the_suite_says_how_to_get_it() {
    let dir = scratch("validate-not-built");
    for args in [&["validate"][..], &["validate", "--quick"][..]] {
        let out = flexmbs(&dir, args);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert!(out.stdout.is_empty(), "{}", out.stdout);
        assert!(out.stderr.starts_with("flexmbs: error: "), "{}", out.stderr);
        assert!(
            out.stderr.contains("cargo run --release -p validation"),
            "{}",
            out.stderr
        );
        assert!(out.stderr.contains("--features validate"), "{}", out.stderr);
    }
    assert!(!dir.join("validation-report").exists());
}

#[cfg(feature = "validate")]
#[test]
fn validate_refuses_an_unknown_id_and_writes_nothing() {
    let dir = scratch("validate-unknown");
    let out = flexmbs(&dir, &["validate", "--only", "Z", "--report-dir", "report"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("unknown benchmark id 'Z'"), "{}", out.stderr);
    assert!(out.stderr.contains("B1"), "{}", out.stderr);
    assert!(!dir.join("report").exists());
    assert!(!dir.join("validation-report").exists());
}

#[test]
fn running_a_study_without_analyses_exits_2() {
    let dir = scratch("empty-study");
    std::fs::write(dir.join("empty.toml"), "[study]\ntitle = \"nothing\"\n").unwrap();
    let out = flexmbs(&dir, &["run", "empty.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("no [[analyses]]"), "{}", out.stderr);
    // Nothing is created for it.
    assert!(!dir.join("empty-results").exists());
    // `check` refuses it too: a study that runs nothing is not a valid study.
    let out = flexmbs(&dir, &["check", "empty.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("empty.toml: the study has no [[analyses]]"),
        "{}",
        out.stderr
    );
}

/// `flexmbs ... | head` closes the pipe early: the program must not panic (exit 101).
#[test]
fn a_closed_stdout_is_not_a_panic() {
    let dir = scratch("closed-pipe");
    for args in [
        &["--help"][..],
        &["example"][..],
        &["run", "--help"][..],
        &["validate", "--help"][..],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_flexmbs"))
            .args(args)
            .current_dir(&dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Close the reading end before the program writes: every write gets EPIPE.
        drop(child.stdout.take());
        let mut stderr = String::new();
        child.stderr.take().unwrap().read_to_string(&mut stderr).unwrap();
        let status = child.wait().unwrap();
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert_ne!(status.code(), Some(101), "{args:?}: {stderr}");
    }
}

/// A stage shows its text in a spinner (no empty `0/0` bar), and a counted computation after
/// it gets a real bar of its length.
#[test]
fn progress_shows_the_stage_text_and_real_bars() {
    use study::output::observer::{Observer, Progress};
    let mut console = flexmbs::console::Console::with_target(indicatif::ProgressDrawTarget::hidden);
    console.progress(&Progress::Stage("part 'rod': factorising K_ii (1200 dofs)".into()));
    assert_eq!(
        console.shown(),
        Some((None, "part 'rod': factorising K_ii (1200 dofs)".to_string()))
    );
    console.progress(&Progress::Stage("part 'rod': 12 constraint modes".into()));
    assert_eq!(console.shown().unwrap().1, "part 'rod': 12 constraint modes");
    console.progress(&Progress::Steps {
        what: "time integration".into(),
        done: 3,
        total: 500,
    });
    assert_eq!(console.shown(), Some((Some(500), "time integration".to_string())));
    console.progress(&Progress::Finished);
    assert_eq!(console.shown(), None);
}

/// `export-fmu` without the FMU library says how to build it; with a library named by
/// `FLEXMBS_FMU_LIBRARY` it writes the FMU (its contents are checked by the study crate's
/// tests and, with FMPy, by the Python package's).
#[test]
fn export_fmu_needs_the_library_and_says_how_to_build_it() {
    let dir = scratch("export-fmu");
    let study = examples_copy("export-fmu-examples").join("slider_crank.toml");
    let missing = dir.join("no-such-library.so");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_flexmbs"))
        .args([
            "export-fmu",
            study.to_str().unwrap(),
            "-o",
            dir.join("a.fmu").to_str().unwrap(),
        ])
        .env("FLEXMBS_FMU_LIBRARY", &missing)
        .current_dir(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("cargo build --release -p flexmbs-fmu"), "{stderr}");
    assert!(!dir.join("a.fmu").exists());
    let library = dir.join("lib.so");
    std::fs::write(&library, b"a library").unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_flexmbs"))
        .args([
            "export-fmu",
            study.to_str().unwrap(),
            "-o",
            dir.join("a.fmu").to_str().unwrap(),
        ])
        .env("FLEXMBS_FMU_LIBRARY", &library)
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        stdout.contains("analysis 'run-up'") && stdout.contains("0 inputs"),
        "{stdout}"
    );
    assert!(dir.join("a.fmu").is_file());
    // Without a study file.
    let out = flexmbs(&dir, &["export-fmu"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("needs a study file"), "{}", out.stderr);
}
