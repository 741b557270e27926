//! Invalid study files through the program: exit code 2, nothing on stdout and the study
//! crate's report on stderr, never a panic. What the validation says about each file is
//! tested in crates/study (`tests/study/broken_files.rs`: the corpus `tests/broken`, random and
//! mutated files); here, that the program prints it and exits as it should.

use crate::support::*;
use std::path::{Path, PathBuf};

/// Broken study files made on purpose: the study crate's generator.
#[path = "../../../study/tests/property/generate.rs"]
mod generate;

/// The repository's root.
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `flexmbs check FILE` prints exactly the study crate's report of the file (exit code 2,
/// nothing on stdout).
#[test]
fn check_prints_the_study_report_of_every_broken_file() {
    let dir = repo().join("crates/study/tests/broken");
    let files = generate::corpus(&repo());
    assert!(files.len() >= 20, "the corpus has {} files", files.len());
    for f in files {
        let report = study::error::report(&*study::load(&f).unwrap_err());
        let out = flexmbs(&dir, &["check", &f.display().to_string()]);
        assert_eq!(out.code, 2, "{}: exit code\n{}", f.display(), out.stderr);
        assert!(out.stdout.is_empty(), "{}: nothing on stdout", f.display());
        assert_eq!(out.stderr, format!("{report}\n"), "{}", f.display());
    }
}

/// A sample of the study crate's random and mutated files through the binary: exit code 0
/// (still valid) or 2 with a located message, never a panic (101) or a signal.
#[test]
fn random_and_mutated_study_files_fail_cleanly() {
    let dir = examples_copy("property");
    let study = dir.join("case.toml");
    let cases: Vec<String> = generate::cases(&repo(), 1500).into_iter().step_by(30).collect();
    let mut invalid = 0;
    for (k, text) in cases.iter().enumerate() {
        std::fs::write(&study, text).unwrap();
        let out = flexmbs(&dir, &["check", "case.toml"]);
        match out.code {
            0 => {}
            2 => {
                invalid += 1;
                assert!(
                    out.stderr.starts_with("flexmbs: error: "),
                    "sample {k}:\n{}",
                    out.stderr
                );
                assert!(out.stderr.contains("case.toml"), "sample {k}:\n{}", out.stderr);
            }
            code => panic!("sample {k}: exit code {code}\n{}\non:\n{text}", out.stderr),
        }
    }
    assert!(
        invalid > cases.len() / 2,
        "the mutations should mostly break the files ({invalid} of {})",
        cases.len()
    );
}

/// Inputs that are not text, and nesting deep enough to overflow a recursive parser.
#[test]
fn binary_and_deeply_nested_files_fail_cleanly() {
    let dir = scratch("property-special");
    std::fs::write(dir.join("binary.toml"), [0xff, 0xfe, 0x00, 0x41, 0x80]).unwrap();
    let out = flexmbs(&dir, &["check", "binary.toml"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("not UTF-8"), "{}", out.stderr);
    for text in [
        format!("a = {}", "[".repeat(100_000)),
        format!("a = {}", "{ b = ".repeat(50_000)),
    ] {
        std::fs::write(dir.join("deep.toml"), text).unwrap();
        let out = flexmbs(&dir, &["check", "deep.toml"]);
        assert_eq!(out.code, 2, "{}", out.stderr);
        assert!(out.stderr.contains("deep.toml"), "{}", out.stderr);
    }
    std::fs::write(dir.join("empty.toml"), "").unwrap();
    // An empty study parses, and is refused for having nothing to run.
    let out = flexmbs(&dir, &["check", "empty.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("no [[analyses]]"), "{}", out.stderr);
}
