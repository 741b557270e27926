//! Where things are in a study file: the text, a tree of the spans of every key and value,
//! key paths such as `parts[0].interfaces[1].set`, and the rendering of errors with file,
//! line, column, key and the offending line.
//!
//! The serde schema ([`crate::input::schema`]) holds no positions. An error found by the
//! validator carries the [`KeyPath`] of the value it is about; [`Source::locate`] finds that
//! path's span in a span tree built once from `toml`'s spanned document
//! ([`toml::de::DeTable`]). A parse or type error from `toml` carries a span; the tree gives
//! it back its key path. So every message names file, line, column and key either way.

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// One step of a key path.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Segment {
    Key(String),
    Index(usize),
}

/// A path to a value in the file, `parts[0].beam.elements`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct KeyPath(pub Vec<Segment>);

impl KeyPath {
    pub fn root() -> Self {
        Self(Vec::new())
    }

    /// This path followed by key `k`.
    pub fn key(&self, k: &str) -> Self {
        let mut p = self.clone();
        p.0.push(Segment::Key(k.to_string()));
        p
    }

    /// This path followed by index `i`.
    pub fn index(&self, i: usize) -> Self {
        let mut p = self.clone();
        p.0.push(Segment::Index(i));
        p
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_empty() {
            return f.write_str("(top level)");
        }
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Segment::Key(k) if i == 0 => write!(f, "{k}")?,
                Segment::Key(k) => write!(f, ".{k}")?,
                Segment::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// The spans of a parsed TOML value and of everything inside it.
#[derive(Clone, Debug)]
enum SpanTree {
    Table(Vec<(String, Range<usize>, Node)>),
    Array(Vec<Node>),
    Scalar,
}

#[derive(Clone, Debug)]
struct Node {
    span: Range<usize>,
    tree: SpanTree,
}

impl Node {
    fn from_value(v: &toml::Spanned<toml::de::DeValue<'_>>) -> Self {
        let tree = match v.get_ref() {
            toml::de::DeValue::Table(t) => SpanTree::Table(
                t.iter()
                    .map(|(k, v)| (k.get_ref().to_string(), k.span(), Node::from_value(v)))
                    .collect(),
            ),
            toml::de::DeValue::Array(a) => SpanTree::Array(a.iter().map(Node::from_value).collect()),
            _ => SpanTree::Scalar,
        };
        Node { span: v.span(), tree }
    }
}

/// A study file's name, text and span tree.
#[derive(Clone, Debug)]
pub struct Source {
    pub path: PathBuf,
    pub text: String,
    root: Option<Node>,
}

/// Where an error points: the value at a path, the key of that value, or a byte range.
#[derive(Clone, Debug)]
pub enum Anchor {
    Value(KeyPath),
    Key(KeyPath),
    Span(Range<usize>),
    /// The file as a whole (a section that is missing).
    File,
}

/// One error in a study file.
#[derive(Clone, Debug)]
pub struct StudyError {
    pub anchor: Anchor,
    /// The key path shown to the user (for `Anchor::Span`, found from the span).
    pub path: KeyPath,
    pub message: String,
}

impl StudyError {
    /// An error about the value at `path`.
    pub fn at(path: &KeyPath, message: impl Into<String>) -> Self {
        Self {
            anchor: Anchor::Value(path.clone()),
            path: path.clone(),
            message: message.into(),
        }
    }

    /// An error about the key at the end of `path` (an unknown or misplaced key).
    pub fn at_key(path: &KeyPath, message: impl Into<String>) -> Self {
        Self {
            anchor: Anchor::Key(path.clone()),
            path: path.clone(),
            message: message.into(),
        }
    }

    /// An error about the file as a whole.
    pub fn file(message: impl Into<String>) -> Self {
        Self {
            anchor: Anchor::File,
            path: KeyPath::root(),
            message: message.into(),
        }
    }
}

/// Line and column (1-based, columns in characters) of byte `offset` of `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, text[line_start..offset].chars().count() + 1)
}

impl Source {
    /// Reads `path`. The span tree is built when the text parses as TOML; otherwise errors
    /// point at the spans `toml` reports.
    pub fn read(path: &Path) -> Result<Self, std::io::Error> {
        let bytes = fe_model::input::read(path)?;
        let text = match String::from_utf8(bytes) {
            Ok(t) => t,
            Err(e) => {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!(
                        "the file is not UTF-8 text (invalid byte at offset {})",
                        e.utf8_error().valid_up_to()
                    ),
                ))
            }
        };
        Ok(Self::from_text(path, text))
    }

    /// A source from text; `path` only names it.
    pub fn from_text(path: &Path, text: String) -> Self {
        let root = toml::de::DeTable::parse(&text).ok().map(|t| {
            let span = t.span();
            let table = t.into_inner();
            Node {
                span,
                tree: SpanTree::Table(
                    table
                        .iter()
                        .map(|(k, v)| (k.get_ref().to_string(), k.span(), Node::from_value(v)))
                        .collect(),
                ),
            }
        });
        Self {
            path: path.to_path_buf(),
            text,
            root,
        }
    }

    /// The directory that relative paths in the file are relative to.
    pub fn dir(&self) -> PathBuf {
        // An empty path (a file in the working folder) joins to the bare relative name.
        self.path.parent().map(Path::to_path_buf).unwrap_or_default()
    }

    fn node(&self, path: &KeyPath) -> Option<(&Node, Option<Range<usize>>)> {
        let mut node = self.root.as_ref()?;
        let mut key_span = None;
        for s in &path.0 {
            match (s, &node.tree) {
                (Segment::Key(k), SpanTree::Table(entries)) => {
                    let (_, ks, n) = entries.iter().find(|(name, _, _)| name == k)?;
                    key_span = Some(ks.clone());
                    node = n;
                }
                (Segment::Index(i), SpanTree::Array(items)) => {
                    node = items.get(*i)?;
                    key_span = None;
                }
                _ => return None,
            }
        }
        Some((node, key_span))
    }

    /// Whether the file has a value at `path`.
    pub fn has(&self, path: &KeyPath) -> bool {
        self.node(path).is_some()
    }

    /// The keys of the table at `path`, in file order, with the path of each.
    pub fn keys(&self, path: &KeyPath) -> Vec<String> {
        match self.node(path) {
            Some((
                Node {
                    tree: SpanTree::Table(entries),
                    ..
                },
                _,
            )) => entries.iter().map(|(k, _, _)| k.clone()).collect(),
            _ => Vec::new(),
        }
    }

    /// The span of the value at `path`, falling back to the nearest enclosing value that
    /// exists.
    pub fn locate(&self, path: &KeyPath) -> Option<Range<usize>> {
        self.locate_span(path, false)
    }

    /// The span of the key of the value at `path` (of the value, for an array item, which
    /// has no key), falling back to the nearest enclosing value that exists.
    pub fn locate_key(&self, path: &KeyPath) -> Option<Range<usize>> {
        self.locate_span(path, true)
    }

    /// [`Source::locate`], or with `key` [`Source::locate_key`].
    fn locate_span(&self, path: &KeyPath, key: bool) -> Option<Range<usize>> {
        let mut p = path.clone();
        loop {
            if let Some((node, key_span)) = self.node(&p) {
                let span = if key {
                    key_span.unwrap_or(node.span.clone())
                } else {
                    node.span.clone()
                };
                // An array of tables spans from its first header; point at that header's line.
                return Some(span);
            }
            p.0.pop()?;
        }
    }

    /// The key path of the innermost key or value whose span holds `offset`.
    ///
    /// `toml` gives a table only the span of its header (`[[parts]]`), not of its
    /// contents, so the search looks at every key and value rather than descending into the
    /// spans that hold the offset; the shortest span that holds it wins.
    pub fn path_at(&self, offset: usize) -> KeyPath {
        fn consider(span: &Range<usize>, path: &KeyPath, offset: usize, best: &mut Option<(usize, KeyPath)>) {
            let holds = span.contains(&offset) || (span.is_empty() && span.start == offset);
            if holds && best.as_ref().is_none_or(|(len, _)| span.len() <= *len) {
                *best = Some((span.len(), path.clone()));
            }
        }
        fn visit(node: &Node, path: &mut KeyPath, offset: usize, best: &mut Option<(usize, KeyPath)>) {
            match &node.tree {
                SpanTree::Table(entries) => {
                    for (k, ks, n) in entries {
                        path.0.push(Segment::Key(k.clone()));
                        consider(ks, path, offset, best);
                        consider(&n.span, path, offset, best);
                        visit(n, path, offset, best);
                        path.0.pop();
                    }
                }
                SpanTree::Array(items) => {
                    for (i, n) in items.iter().enumerate() {
                        path.0.push(Segment::Index(i));
                        consider(&n.span, path, offset, best);
                        visit(n, path, offset, best);
                        path.0.pop();
                    }
                }
                SpanTree::Scalar => {}
            }
        }
        let mut best = None;
        if let Some(root) = &self.root {
            visit(root, &mut KeyPath::root(), offset, &mut best);
        }
        best.map(|(_, p)| p).unwrap_or_default()
    }

    /// Converts a `toml` parse or type error, with its key path and, for an unknown key or
    /// variant, the closest known names.
    pub fn toml_error(&self, e: &toml::de::Error) -> StudyError {
        let mut message = plain_types(e.message().trim());
        if let Some(hint) = unknown_name_hint(&message) {
            message.push_str(&hint);
        }
        match e.span() {
            Some(span) => {
                let mut path = self.path_at(span.start);
                // For "unknown field" the span is the key itself; the path then ends in it.
                let mut span = span;
                if let Some(field) = quoted_after(&message, "unknown field `") {
                    let keys = self.keys(&path);
                    if keys.contains(&field) {
                        path = path.key(&field);
                        if let Some(s) = self.locate_key(&path) {
                            span = s;
                        }
                    }
                }
                StudyError {
                    anchor: Anchor::Span(span),
                    path,
                    message,
                }
            }
            None => StudyError::file(message),
        }
    }

    /// `file:line:col: key: message` and the line with a caret under the span.
    pub fn render(&self, e: &StudyError) -> String {
        let span = match &e.anchor {
            Anchor::Value(p) => self.locate(p),
            Anchor::Key(p) => self.locate_key(p),
            Anchor::Span(s) => Some(s.clone()),
            Anchor::File => None,
        };
        let file = self.path.display();
        let key = if e.path.0.is_empty() {
            String::new()
        } else {
            format!("{}: ", e.path)
        };
        let Some(span) = span else {
            return format!("{file}: {key}{}", e.message);
        };
        let (line, col) = line_column(&self.text, span.start);
        let mut out = format!("{file}:{line}:{col}: {key}{}", e.message);
        if let Some(full) = self.text.lines().nth(line - 1) {
            // Show at most 160 characters of a long line, from 60 before the column.
            let skip = (col - 1).saturating_sub(60);
            let text: String = full.chars().skip(skip).take(160).collect();
            let col = col - skip;
            // Underline the span on its first line only, at most to the end of that line.
            let width = self
                .text
                .get(span.start..span.end)
                .and_then(|s| s.lines().next())
                .map_or(1, |s| s.chars().count().max(1));
            let width = width.min(text.chars().count().saturating_sub(col - 1).max(1));
            let gutter = line.to_string().len();
            out.push_str(&format!(
                "\n{:gutter$} |\n{line} | {text}\n{:gutter$} | {}{}",
                "",
                "",
                " ".repeat(col - 1),
                "^".repeat(width)
            ));
        }
        out
    }
}

/// The text between `prefix` and the next backquote.
fn quoted_after(message: &str, prefix: &str) -> Option<String> {
    let start = message.find(prefix)? + prefix.len();
    let len = message[start..].find('`')?;
    Some(message[start..start + len].to_string())
}

/// Serde's message with the study file's words for its Rust types: "expected f64" is
/// "expected a number", "expected usize" "expected a whole number >= 0", a sequence an array,
/// a map or struct a table.
pub fn plain_types(message: &str) -> String {
    const WORDS: &[(&str, &str)] = &[
        ("expected f64", "expected a number"),
        ("expected f32", "expected a number"),
        ("expected usize", "expected a whole number >= 0"),
        ("expected u64", "expected a whole number >= 0"),
        ("expected u32", "expected a whole number >= 0"),
        ("expected u16", "expected a whole number >= 0"),
        ("expected u8", "expected a whole number >= 0"),
        ("expected i64", "expected a whole number"),
        ("expected i32", "expected a whole number"),
        ("expected a sequence", "expected an array"),
        ("expected a map", "expected a table"),
        ("invalid type: sequence", "invalid type: array"),
        ("invalid type: map", "invalid type: table"),
        ("invalid type: floating point", "invalid type: number"),
        ("invalid value: floating point", "invalid value: number"),
        ("invalid type: integer", "invalid type: whole number"),
        ("invalid value: integer", "invalid value: whole number"),
    ];
    let mut out = message.to_string();
    for (rust, study) in WORDS {
        out = out.replace(rust, study);
    }
    // "expected struct BeamFile" (a table in the file), "expected enum Kind".
    for what in ["expected struct ", "expected enum "] {
        while let Some(at) = out.find(what) {
            let name_end = out[at + what.len()..]
                .find(|c: char| !c.is_ascii_alphanumeric() && c != '_')
                .map_or(out.len(), |e| at + what.len() + e);
            let word = if what.contains("struct") {
                "expected a table"
            } else {
                "expected one of its names"
            };
            out.replace_range(at..name_end, word);
        }
    }
    out
}

/// For serde's "unknown field `x`, expected one of `a`, `b`" and "unknown variant ..."
/// messages: the closest of the expected names.
fn unknown_name_hint(message: &str) -> Option<String> {
    let name = quoted_after(message, "unknown field `").or_else(|| quoted_after(message, "unknown variant `"))?;
    let expected_at = message.find("expected")?;
    let expected: Vec<String> = message[expected_at..]
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect();
    let close = close_matches(&name, expected.iter().map(String::as_str));
    (!close.is_empty()).then(|| format!("; did you mean {}?", quote_list(&close, "or")))
}

/// The names among `candidates` close to `name`: by edit distance with transpositions (at
/// most a third of the longer name, and at least 1), ignoring case, `-` and `_`, closest first, at most three.
pub fn close_matches<'a>(name: &str, candidates: impl IntoIterator<Item = &'a str>) -> Vec<String> {
    let norm = |s: &str| s.to_lowercase().replace(['-', '_'], "");
    let n = norm(name);
    let mut scored: Vec<(usize, String)> = candidates
        .into_iter()
        .filter(|c| *c != name)
        .filter_map(|c| {
            let d = strsim::osa_distance(&n, &norm(c));
            let limit = (n.chars().count().max(c.chars().count()) / 3).max(1);
            (d <= limit).then(|| (d, c.to_string()))
        })
        .collect();
    scored.sort();
    scored.dedup();
    scored.into_iter().take(3).map(|(_, c)| c).collect()
}

/// `'a', 'b' or 'c'`.
pub fn quote_list(names: &[String], conjunction: &str) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("'{n}'")).collect();
    match quoted.len() {
        0 => String::new(),
        1 => quoted[0].clone(),
        k => format!("{} {conjunction} {}", quoted[..k - 1].join(", "), quoted[k - 1]),
    }
}

/// "unknown material 'stel'; did you mean 'steel'? (defined: steel, aluminium)".
pub fn unknown_reference(what: &str, name: &str, defined: &[String]) -> String {
    format!("unknown {what} '{name}'{}", suggestions(name, defined, what))
}

/// "; did you mean 'steel'? (defined: steel, aluminium)": the close matches of `name` among
/// `defined`, then the defined names (at most twelve). `what` names them when there are none.
pub fn suggestions(name: &str, defined: &[String], what: &str) -> String {
    let close = close_matches(name, defined.iter().map(String::as_str));
    let mut m = String::new();
    if !close.is_empty() {
        m.push_str(&format!("; did you mean {}?", quote_list(&close, "or")));
    }
    if defined.is_empty() {
        m.push_str(&format!(" (no {what} is defined)"));
    } else {
        let shown: Vec<&str> = defined.iter().take(12).map(String::as_str).collect();
        let more = if defined.len() > shown.len() {
            format!(", and {} more", defined.len() - shown.len())
        } else {
            String::new()
        };
        m.push_str(&format!(" (defined: {}{more})", shown.join(", ")));
    }
    m
}

/// All errors of one study file, rendered with its text.
#[derive(Debug)]
pub struct StudyErrors {
    pub source: Source,
    pub errors: Vec<StudyError>,
}

impl fmt::Display for StudyErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.errors.len();
        write!(
            f,
            "study file {} is not valid ({n} error{}):",
            self.source.path.display(),
            if n == 1 { "" } else { "s" }
        )?;
        for e in &self.errors {
            write!(f, "\n{}", self.source.render(e))?;
        }
        Ok(())
    }
}

impl std::error::Error for StudyErrors {}
