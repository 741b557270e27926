use std::path::{Path, PathBuf};
use std::process::Command;

/// What a run of the binary printed and returned.
pub struct Output {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// Runs `flexmbs` with `args` in the folder `dir`.
pub fn flexmbs(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_flexmbs"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the flexmbs binary runs");
    Output {
        // A signal (no code) counts as a failure distinct from every exit code we use.
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A fresh, empty scratch folder for test `name`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("flexmbs-cli-tests")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The repository's `examples/` folder.
pub fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples")
}

/// Copies `from` into `to`, recursively, skipping results and caches of earlier runs.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let name = entry.file_name().to_string_lossy().to_string();
        if name.starts_with('.') || name.ends_with("-results") {
            continue;
        }
        let path = entry.path();
        if path.is_dir() {
            copy_dir(&path, &to.join(&name));
        } else {
            std::fs::copy(&path, to.join(&name)).unwrap();
        }
    }
}

/// The examples copied into a scratch folder.
pub fn examples_copy(name: &str) -> PathBuf {
    let dir = scratch(name);
    copy_dir(&examples_dir(), &dir);
    dir
}

/// A CSV file as its header and rows of cells.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(str::to_string).collect();
    let rows = lines.map(|l| l.split(',').map(str::to_string).collect()).collect();
    (header, rows)
}

/// The cell in column `column` of the row whose first cell is `key`, as a number.
pub fn csv_value(path: &Path, key: &str, column: &str) -> f64 {
    let (header, rows) = read_csv(path);
    let c = header
        .iter()
        .position(|h| h == column)
        .unwrap_or_else(|| panic!("{}: no column {column} in {header:?}", path.display()));
    let row = rows
        .iter()
        .find(|r| r[0] == key)
        .unwrap_or_else(|| panic!("{}: no row {key}", path.display()));
    row[c].parse().unwrap()
}

/// `|a - b| <= tol |b|`, with a message.
pub fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!(
        (a - b).abs() <= tol * b.abs(),
        "{what}: {a} vs {b} (relative tolerance {tol})"
    );
}
