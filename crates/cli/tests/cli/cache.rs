use crate::support::*;

/// The reduced bodies in the cache (each has a `.key` file beside it).
fn bodies(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    std::fs::read_dir(dir.join(".flexmbs-cache"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "rbody"))
        .collect()
}

/// The second run of a study finds its reduced bodies in the cache and says so; a setting
/// that changes the body makes it reduce again; a comment does not.
#[test]
fn second_run_does_not_reduce_again() {
    let dir = examples_copy("cache");
    let first = flexmbs(&dir, &["run", "solid_bar.toml"]);
    assert_eq!(first.code, 0, "{}", first.stderr);
    assert_eq!(first.stderr.matches("': reducing").count(), 2, "{}", first.stderr);
    assert_eq!(bodies(&dir).len(), 2);
    let body = std::fs::read(dir.join("solid_bar-results/reduce-bar/bar.rbody")).unwrap();

    let second = flexmbs(&dir, &["run", "solid_bar.toml"]);
    assert_eq!(second.code, 0, "{}", second.stderr);
    assert!(!second.stderr.contains("': reducing"), "{}", second.stderr);
    assert_eq!(
        second.stderr.matches("found in the cache").count(),
        2,
        "{}",
        second.stderr
    );
    assert!(second.stderr.contains("not reducing again"));
    assert!(second.stdout.contains("(from the cache)"), "{}", second.stdout);
    assert_eq!(
        std::fs::read(dir.join("solid_bar-results/reduce-bar/bar.rbody")).unwrap(),
        body
    );

    // A comment and a reordering change nothing that produced the body.
    let text = std::fs::read_to_string(dir.join("solid_bar.toml")).unwrap();
    std::fs::write(dir.join("solid_bar.toml"), format!("# a new comment\n{text}")).unwrap();
    let third = flexmbs(&dir, &["reduce", "solid_bar.toml", "--part", "bar"]);
    assert_eq!(third.code, 0, "{}", third.stderr);
    assert!(third.stderr.contains("found in the cache"), "{}", third.stderr);

    // Another mode count is another body.
    let changed = text.replacen("modes = 6", "modes = 5", 1);
    assert_ne!(changed, text);
    std::fs::write(dir.join("solid_bar.toml"), changed).unwrap();
    let fourth = flexmbs(&dir, &["reduce", "solid_bar.toml", "--part", "bar"]);
    assert_eq!(fourth.code, 0, "{}", fourth.stderr);
    assert!(fourth.stderr.contains("part 'bar': reducing"), "{}", fourth.stderr);
    assert_eq!(bodies(&dir).len(), 3);

    // So is a changed mesh file, even with the same study file.
    let mesh = dir.join("meshes/bar_tet10.msh");
    let m = std::fs::read_to_string(&mesh).unwrap();
    std::fs::write(&mesh, m + "\n").unwrap();
    let fifth = flexmbs(&dir, &["reduce", "solid_bar.toml", "--part", "bar"]);
    assert_eq!(fifth.code, 0, "{}", fifth.stderr);
    assert!(fifth.stderr.contains("part 'bar': reducing"), "{}", fifth.stderr);
}

/// A damaged cache file is not trusted: the part is reduced again.
#[test]
fn damaged_cache_file_is_replaced() {
    let dir = examples_copy("cache-damaged");
    assert_eq!(flexmbs(&dir, &["reduce", "cantilever.toml"]).code, 0);
    let file = bodies(&dir).remove(0);
    let mut bytes = std::fs::read(&file).unwrap();
    let n = bytes.len();
    bytes[n - 3] ^= 0xff;
    std::fs::write(&file, bytes).unwrap();
    let out = flexmbs(&dir, &["reduce", "cantilever.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stderr.contains("was changed); reducing again"), "{}", out.stderr);
    assert!(out.stderr.contains("': reducing"), "{}", out.stderr);
    let again = flexmbs(&dir, &["reduce", "cantilever.toml"]);
    assert!(again.stderr.contains("found in the cache"), "{}", again.stderr);
}
