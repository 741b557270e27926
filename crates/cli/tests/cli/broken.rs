use crate::support::*;
use std::path::Path;

/// Runs `flexmbs check` on one broken file and checks its `# expect:` lines. Every error
/// must name the file with a line and a column.
fn check_broken(path: &Path) {
    let text = std::fs::read_to_string(path).unwrap();
    let expected: Vec<&str> = text.lines().filter_map(|l| l.strip_prefix("# expect: ")).collect();
    let name = path.file_name().unwrap().to_string_lossy().to_string();
    assert!(!expected.is_empty(), "{name} has no `# expect:` line");
    let out = flexmbs(path.parent().unwrap(), &["check", &name]);
    assert_eq!(out.code, 2, "{name}: exit code\n{}", out.stderr);
    assert!(out.stdout.is_empty(), "{name}: nothing on stdout");
    assert!(out.stderr.starts_with("flexmbs: error: "), "{name}:\n{}", out.stderr);
    for e in expected {
        assert!(out.stderr.contains(e), "{name}: expected\n  {e}\nin\n{}", out.stderr);
    }
    // Every error line starts with file:line:col.
    let errors: Vec<&str> = out.stderr.lines().filter(|l| l.starts_with(&name)).collect();
    assert!(!errors.is_empty(), "{name}: no located error in\n{}", out.stderr);
    for l in errors {
        let rest = &l[name.len()..];
        let mut parts = rest.splitn(4, ':');
        assert_eq!(parts.next(), Some(""), "{l}");
        let line: Option<usize> = parts.next().and_then(|s| s.parse().ok());
        let col: Option<usize> = parts.next().and_then(|s| s.parse().ok());
        assert!(line.is_some() && col.is_some(), "{name}: no line:col in '{l}'");
    }
}

#[test]
fn broken_study_files_are_reported_with_location_key_and_close_matches() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/broken");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
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
    let dir = scratch("cascade");
    let text = std::fs::read_to_string(examples_dir().join("slider_crank.toml")).unwrap();
    assert!(text.contains("\nnu = 0.3\n"));
    std::fs::write(dir.join("nu.toml"), text.replace("\nnu = 0.3\n", "\nnu = 0.6\n")).unwrap();
    let out = flexmbs(&dir, &["check", "nu.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(out.stderr.contains("is not valid (1 error)"), "{}", out.stderr);
    assert!(
        out.stderr.contains("Poisson's ratio nu must lie in (-1, 0.5), got 0.6"),
        "{}",
        out.stderr
    );
    assert!(!out.stderr.contains("unknown"), "{}", out.stderr);
}
