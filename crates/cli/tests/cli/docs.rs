//! The documents of the repository stand on their own: every link and every repository file
//! they name exists, every `#anchor` of a link to a Markdown file is one of its headings, and
//! nothing in the repository points to files outside it.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Component, Path, PathBuf};

/// The workspace root (this crate is `crates/cli`).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .canonicalize()
        .unwrap()
}

/// Every file under `dir` whose name ends in one of `extensions`, skipping build output,
/// version control and Python environments.
fn files(dir: &Path, extensions: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().to_string();
        if path.is_dir() {
            if !matches!(
                name.as_str(),
                "target" | ".git" | "venv" | ".venv" | "__pycache__" | "node_modules"
            ) && !name.ends_with("-results")
            {
                files(&path, extensions, out);
            }
        } else if extensions.iter().any(|e| name.ends_with(e)) {
            out.push(path);
        }
    }
}

/// The Markdown documents of the repository.
fn documents() -> Vec<PathBuf> {
    let mut docs = Vec::new();
    files(&root(), &[".md"], &mut docs);
    assert!(docs.len() >= 8, "found only {docs:?}");
    docs
}

/// GitHub's anchor of a heading: lower case, punctuation other than `-` and `_` dropped,
/// spaces to hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of the headings of a Markdown text (outside code blocks).
fn anchors(text: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
        } else if !fenced && line.starts_with('#') {
            out.insert(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// The targets of the inline links and images `[text](target)` of a Markdown text, outside
/// code blocks and code spans, with their line numbers.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        // Drop code spans: a `[x](y)` inside backticks is an example, not a link.
        let mut plain = String::new();
        for (k, part) in line.split('`').enumerate() {
            if k % 2 == 0 {
                plain.push_str(part);
            }
        }
        let mut rest = plain.as_str();
        while let Some(p) = rest.find("](") {
            let after = &rest[p + 2..];
            let Some(end) = after.find(')') else { break };
            out.push((i + 1, after[..end].trim().to_string()));
            rest = &after[end..];
        }
    }
    out
}

/// A path with `.` and `..` resolved lexically (the file need not exist).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            other => out.push(other.as_os_str()),
        }
    }
    out
}

#[test]
fn every_link_of_the_documents_exists() {
    let root = root();
    let mut broken = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = fs::read_to_string(&doc).unwrap();
        for (line, target) in links(&text) {
            if target.starts_with("http://") || target.starts_with("https://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                doc.clone()
            } else {
                normalise(&doc.parent().unwrap().join(file))
            };
            let shown = format!("{}:{line}: ({target})", doc.strip_prefix(&root).unwrap().display());
            if !path.starts_with(&root) {
                broken.push(format!("{shown} points outside the repository"));
            } else if !path.exists() {
                broken.push(format!("{shown}: no such file"));
            } else if let Some(anchor) = anchor {
                if path.extension().is_some_and(|e| e == "md") {
                    let headings = anchors(&fs::read_to_string(&path).unwrap());
                    if !headings.contains(anchor) {
                        broken.push(format!("{shown}: no heading with anchor #{anchor}"));
                    }
                }
            }
        }
    }
    assert!(checked > 50, "only {checked} links found: is the link parser broken?");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The top-level entries of the repository a path in backticks may start with.
const TOP: &[&str] = &[
    "crates/",
    "docs/",
    "examples/",
    "validation/",
    "benchmarks/",
    ".ci/",
    "README.md",
    "ARCHITECTURE.md",
    "BENCHMARKS.md",
    "Cargo.toml",
];

#[test]
fn every_repository_file_named_in_the_documents_exists() {
    let root = root();
    let mut missing = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = fs::read_to_string(&doc).unwrap();
        for (i, line) in text.lines().enumerate() {
            for (k, span) in line.split('`').enumerate() {
                // Odd pieces are code spans; a path is one word naming a repository file.
                if k % 2 == 0 || span.contains(char::is_whitespace) || span.contains(['$', '*', '{', '<']) {
                    continue;
                }
                if !TOP.iter().any(|t| span.starts_with(t)) {
                    continue;
                }
                // `file.rs::item`, `file.rs:12`: the file part.
                let file = span.split("::").next().unwrap();
                let file = file.split(':').next().unwrap().trim_end_matches(['.', ',', ')']);
                checked += 1;
                if !root.join(file).exists() {
                    missing.push(format!(
                        "{}:{}: `{span}`",
                        doc.strip_prefix(&root).unwrap().display(),
                        i + 1
                    ));
                }
            }
        }
    }
    assert!(checked > 20, "only {checked} file names found: is the parser broken?");
    assert!(
        missing.is_empty(),
        "files named in the documents that do not exist:\n{}",
        missing.join("\n")
    );
}

/// What points outside the repository: the folder beside a clone, absolute paths of a
/// particular machine, and documents that only exist there.
/// Spelled in pieces so that a plain text search of the repository for them finds none.
const OUTSIDE: &[&str] = &[
    concat!("../", "shared"),
    concat!("shared/", "brief"),
    concat!("shared/", "seed"),
    "/work/",
    concat!("bench", "marks.md"),
    concat!("formu", "lation.md"),
    concat!("sty", "le.md"),
];

#[test]
fn nothing_refers_to_files_outside_the_repository() {
    let root = root();
    let mut sources = Vec::new();
    files(
        &root,
        &[
            ".rs", ".md", ".toml", ".py", ".sh", ".txt", ".html", ".yml", ".yaml", "run",
        ],
        &mut sources,
    );
    let this_file = root.join("crates/cli/tests/cli/docs.rs");
    let mut found = Vec::new();
    for file in sources.iter().filter(|f| **f != this_file) {
        let Ok(text) = fs::read_to_string(file) else { continue };
        for (i, line) in text.lines().enumerate() {
            for pattern in OUTSIDE {
                if line.contains(pattern) {
                    found.push(format!(
                        "{}:{}: '{pattern}' in: {}",
                        file.strip_prefix(&root).unwrap().display(),
                        i + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "{} references to files outside the repository:\n{}",
        found.len(),
        found.join("\n")
    );
}

/// The text of the `### heading` section of a Markdown text, up to the next heading.
fn section<'a>(text: &'a str, heading: &str) -> &'a str {
    let start = text.find(heading).unwrap_or_else(|| panic!("no section {heading}"));
    let body = &text[start + heading.len()..];
    &body[..body.find("\n#").unwrap_or(body.len())]
}

/// Keys a user must write are documented as required, and values with units say them:
/// `name` of loads and sensors, the units of `[[initial]]` values and rates.
#[test]
fn the_study_file_guide_documents_required_names_and_initial_units() {
    let text = fs::read_to_string(root().join("docs/study-file.md")).unwrap();
    for heading in ["### `[[loads]]`", "### `[[sensors]]`"] {
        let s = section(&text, heading);
        assert!(
            s.contains("`name` (required"),
            "{heading} does not say that `name` is required:\n{s}"
        );
    }
    let initial = section(&text, "### `[[initial]]`");
    let row = initial
        .lines()
        .find(|l| l.contains("`value`"))
        .expect("a row for `value`");
    for unit in ["[rad]", "[m]", "[rad/s]", "[m/s]"] {
        assert!(
            row.contains(unit),
            "the `value`/`rate` row does not give {unit}:\n{row}"
        );
    }
}
