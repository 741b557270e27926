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

/// Separate processes on one cache and one results folder, as two users or a batch script
/// would start them: four runs of one study at once, two into their own results folders and
/// two into a shared one, all on one cache. Every run into its own folder completes; of the
/// two sharing a folder, one completes and the other either completes after it or stops at
/// the lock naming the folder (never an interleaved folder); the cache holds only whole
/// bodies and no temporary.
#[test]
fn concurrent_processes_share_one_cache_and_lock_one_results_folder() {
    let dir = examples_copy("cache-concurrent");
    let cache = dir.join("shared-cache");
    let cache_arg = cache.to_string_lossy().to_string();
    let outs = ["own-a", "own-b", "shared", "shared"];
    let children: Vec<_> = outs
        .iter()
        .map(|out| {
            std::process::Command::new(env!("CARGO_BIN_EXE_flexmbs"))
                .args(["run", "solid_bar.toml", "--out", out, "--cache", &cache_arg])
                .current_dir(&dir)
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let results: Vec<(i32, String)> = children
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            (
                o.status.code().unwrap_or(-1),
                String::from_utf8_lossy(&o.stderr).into_owned(),
            )
        })
        .collect();
    for (code, stderr) in &results[..2] {
        assert_eq!(*code, 0, "{stderr}");
    }
    let shared = &results[2..];
    assert!(shared.iter().any(|(code, _)| *code == 0), "{shared:?}");
    for (code, stderr) in shared {
        assert!(
            *code == 0 || (*code == 2 && stderr.contains("in use by another flexmbs run")),
            "{code}: {stderr}"
        );
    }
    // Each folder is one run's: its summary is complete and lists files that exist.
    for out in ["own-a", "own-b", "shared"] {
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join(out).join("summary.json")).unwrap()).unwrap();
        assert_eq!(summary["status"], "complete", "{out}");
        for a in summary["analyses"].as_array().unwrap() {
            for f in a["files"].as_array().unwrap() {
                assert!(dir.join(out).join(f.as_str().unwrap()).is_file(), "{out}: {f}");
            }
        }
        let lock = std::fs::File::open(dir.join(out).join(study::output::folder::LOCK)).unwrap();
        assert!(lock.try_lock().is_ok(), "{out}: lock left");
    }
    let mut whole = 0;
    for e in std::fs::read_dir(&cache).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        assert!(!name.contains("tmp"), "temporary left in the cache: {name}");
        if name.ends_with(".rbody") {
            reduction::file::read(&e.path()).unwrap();
            whole += 1;
        }
    }
    assert_eq!(whole, 2, "one body per part");
}
