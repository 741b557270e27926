//! The validator against wrong study files: the corpus `tests/broken/*.toml`, each file with
//! the messages its validation must give (`# expect:` lines: file:line:col, key, close
//! matches), one wrong value reported once, and random and mutated files (fixed seeds) that
//! must give a located message, never a panic. The program's side (exit code 2, the report on
//! stderr) is tested in crates/cli.

use std::path::{Path, PathBuf};
use study::input::source::Source;

/// Broken study files made on purpose: random text and mutations of good and broken studies.
#[path = "../property/generate.rs"]
mod generate;

/// The repository's root.
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The report `flexmbs check` prints for the study file at `path` (`study::load`'s error),
/// `None` when the file is valid.
fn report(path: &Path) -> Option<String> {
    study::load(path).err().map(|e| study::error::report(&*e))
}

/// Checks one broken file's `# expect:` lines against its report. Every error must name the
/// file with a line and a column.
fn check_broken(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    let expected: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("# expect: ")).collect();
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(!expected.is_empty(), "{name} has no `# expect:` line");
    let message = report(path).unwrap_or_else(|| panic!("{name} is valid"));
    assert!(message.starts_with("flexmbs: error: "), "{name}:\n{message}");
    for e in expected {
        assert!(message.contains(e), "{name}: expected\n  {e}\nin\n{message}");
    }
    // Every error line starts with file:line:col.
    let file = path.display().to_string();
    let errors: Vec<&str> = message.lines().filter(|l| l.starts_with(&file)).collect();
    assert!(!errors.is_empty(), "{name}: no located error in\n{message}");
    for l in errors {
        let rest = &l[file.len()..];
        let mut parts = rest.splitn(4, ':');
        assert_eq!(parts.next(), Some(""), "{l}");
        let line: Option<usize> = parts.next().and_then(|s| s.parse().ok());
        let col: Option<usize> = parts.next().and_then(|s| s.parse().ok());
        assert!(line.is_some() && col.is_some(), "{name}: no line:col in '{l}'");
    }
}

#[test]
fn broken_study_files_are_reported_with_location_key_and_close_matches() {
    let files = generate::corpus(&repo());
    assert!(files.len() >= 20, "the corpus has {} files", files.len());
    for f in files {
        check_broken(&f);
    }
}

/// A material with a wrong value is one error, where it is defined: the parts made of it,
/// the bodies placed from those parts and the joints and sensors on those bodies are not
/// reported again as "unknown material" or "unknown body".
#[test]
fn a_bad_material_is_one_error_not_a_cascade() {
    let text = std::fs::read_to_string(repo().join("examples/slider_crank.toml")).unwrap();
    assert!(text.contains("\nnu = 0.3\n"));
    let source = Source::from_text(Path::new("nu.toml"), text.replace("\nnu = 0.3\n", "\nnu = 0.6\n"));
    let message = study::parse_and_validate(source).unwrap_err().to_string();
    assert!(message.contains("is not valid (1 error)"), "{message}");
    assert!(
        message.contains("materials[0].nu: nu must lie in (-1, 0.5), got 0.6"),
        "{message}"
    );
    assert!(!message.contains("unknown"), "{message}");
}

/// Validates `text` in-process; panics (failing the test) only if the validator does.
fn check_in_process(study: &Path, text: &str, case: usize) {
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        match study::parse_and_validate(Source::from_text(study, text.to_string())) {
            Ok(_) => None,
            Err(errors) => Some(errors.to_string()),
        }
    }));
    match result {
        Ok(Some(message)) => {
            assert!(
                message.contains("case.toml"),
                "case {case}: message without the file:\n{message}"
            );
        }
        Ok(None) => {}
        Err(_) => panic!("case {case} panicked on:\n{text}"),
    }
}

/// Random and mutated study files (fixed seeds): no panic; every invalid one a message that
/// names the file. The study's relative paths (meshes) are taken from the examples.
#[test]
fn random_and_mutated_study_files_fail_cleanly() {
    let study = repo().join("examples/case.toml");
    for (case, text) in generate::cases(&repo(), 1500).iter().enumerate() {
        check_in_process(&study, text, case);
    }
}
