//! A study as an editable document: loaded from a file or from TOML text, read and changed
//! value by value through key paths, and validated with the same checks and located errors
//! as `flexmbs check`. The text keeps its comments and layout (`toml_edit`), so an error
//! points at the line the user wrote.
//!
//! Key paths are keys joined by dots. An element of an array of tables is picked by its
//! index, `parts[0].reduction.modes`, or by its `name`, `parts.rod.reduction.modes`;
//! `analyses.run.t_end`, `joints[2].kind`.

use crate::error::BoxError;
use crate::input::source::{KeyPath, Segment, Source, StudyErrors};
use crate::input::validate::{parse_and_validate, Study};
use std::path::{Path, PathBuf};

/// A key path that does not lead to a value, or a value that cannot be written there.
#[derive(Debug, thiserror::Error)]
pub enum PathError {
    #[error("{path}: malformed key path ({why})")]
    Malformed { path: String, why: String },
    #[error("{path}: there is no '{key}' here{hint}")]
    Missing { path: String, key: String, hint: String },
    #[error("{path}: index {index} is out of range (the array has {len} elements)")]
    Index { path: String, index: usize, len: usize },
    #[error("{path}: '{key}' is a {found}, not a table or an array of tables")]
    NotTable { path: String, key: String, found: String },
    #[error("{path}: '{text}' is not a TOML value ({why})")]
    Value { path: String, text: String, why: String },
}

/// A study file held in memory (module docs).
#[derive(Clone, Debug)]
pub struct Document {
    /// The file it came from, or the name it is known by; relative paths in the study
    /// (meshes, reduced bodies, the results folder) are taken from its folder.
    pub path: PathBuf,
    doc: toml_edit::DocumentMut,
}

/// One step of a key path as written: a key, a key with indices (`parts[0]`).
fn parse_path(path: &str) -> Result<Vec<(String, Vec<usize>)>, PathError> {
    let malformed = |why: &str| PathError::Malformed {
        path: path.to_string(),
        why: why.to_string(),
    };
    if path.trim().is_empty() {
        return Err(malformed("it is empty"));
    }
    let mut out = Vec::new();
    for part in path.split('.') {
        let (key, rest) = match part.find('[') {
            Some(i) => (&part[..i], &part[i..]),
            None => (part, ""),
        };
        if key.is_empty() {
            return Err(malformed("an empty key"));
        }
        let mut indices = Vec::new();
        let mut rest = rest;
        while !rest.is_empty() {
            let Some(close) = rest.find(']') else {
                return Err(malformed("a '[' without ']'"));
            };
            let n = rest[1..close]
                .trim()
                .parse::<usize>()
                .map_err(|_| malformed("an index that is not a whole number"))?;
            indices.push(n);
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(malformed("text after ']'"));
            }
        }
        out.push((key.to_string(), indices));
    }
    Ok(out)
}

/// What an item is, for messages.
fn kind_of(item: &toml_edit::Item) -> String {
    match item {
        toml_edit::Item::None => "nothing".into(),
        toml_edit::Item::Table(_) => "table".into(),
        toml_edit::Item::ArrayOfTables(_) => "array of tables".into(),
        toml_edit::Item::Value(v) => v.type_name().into(),
    }
}

/// The element of an array of tables called `name`.
fn by_name(array: &toml_edit::ArrayOfTables, name: &str) -> Option<usize> {
    array
        .iter()
        .position(|t| t.get("name").and_then(|n| n.as_str()) == Some(name))
}

impl Document {
    /// Reads the study file at `path`; a file that is not TOML is an error located in it.
    pub fn open(path: &Path) -> Result<Self, BoxError> {
        let source = Source::read(path).map_err(|e| format!("cannot read study file {}: {e}", path.display()))?;
        Self::from_source(source)
    }

    /// A study from TOML `text`; `path` names it and anchors its relative paths.
    pub fn from_text(text: &str, path: &Path) -> Result<Self, BoxError> {
        Self::from_source(Source::from_text(path, text.to_string()))
    }

    fn from_source(source: Source) -> Result<Self, BoxError> {
        match source.text.parse::<toml_edit::DocumentMut>() {
            Ok(doc) => Ok(Self {
                path: source.path.clone(),
                doc,
            }),
            // The syntax error as `flexmbs check` reports it: file, line, column.
            Err(_) => match toml::from_str::<toml::Table>(&source.text) {
                Err(e) => {
                    let error = source.toml_error(&e);
                    Err(Box::new(StudyErrors {
                        source,
                        errors: vec![error],
                    }))
                }
                Ok(_) => Err(format!("{}: the study is not valid TOML", source.path.display()).into()),
            },
        }
    }

    /// The study text as it is now.
    pub fn text(&self) -> String {
        self.doc.to_string()
    }

    /// Validates the study as it is now (every check of `flexmbs check`).
    pub fn study(&self) -> Result<Study, StudyErrors> {
        parse_and_validate(Source::from_text(&self.path, self.text()))
    }

    /// The key path with every element of an array of tables given by its index, as the
    /// validation's errors name it (`parts[0].reduction.modes`). With `create`, keys that
    /// are missing are accepted (they will be created), but not missing elements.
    pub fn resolve(&self, path: &str) -> Result<KeyPath, PathError> {
        self.resolve_with(path, false)
    }

    fn resolve_with(&self, path: &str, create: bool) -> Result<KeyPath, PathError> {
        let steps = parse_path(path)?;
        let mut resolved = KeyPath::root();
        let mut item = Some(self.doc.as_item());
        for (key, indices) in &steps {
            let at = resolved.to_string();
            let next = match item {
                None => None,
                Some(toml_edit::Item::ArrayOfTables(a)) => {
                    // A name picks the element.
                    let Some(i) = by_name(a, key) else {
                        return Err(self.missing(item, &at, key));
                    };
                    if !indices.is_empty() {
                        return Err(PathError::Malformed {
                            path: path.to_string(),
                            why: format!("'{key}' names an element; it takes no index"),
                        });
                    }
                    resolved = resolved.index(i);
                    item = a.get(i).map(|_| &item.unwrap_or(&toml_edit::Item::None)[i]);
                    continue;
                }
                Some(i @ (toml_edit::Item::Table(_) | toml_edit::Item::Value(toml_edit::Value::InlineTable(_)))) => {
                    i.get(key.as_str())
                }
                Some(other) => {
                    return Err(PathError::NotTable {
                        path: at,
                        key: key.clone(),
                        found: kind_of(other),
                    })
                }
            };
            if next.is_none() && (!create || !indices.is_empty()) {
                return Err(self.missing(item, &at, key));
            }
            resolved = resolved.key(key);
            item = next;
            for &i in indices {
                let len = match item {
                    Some(toml_edit::Item::ArrayOfTables(a)) => a.len(),
                    Some(toml_edit::Item::Value(toml_edit::Value::Array(a))) => a.len(),
                    _ => 0,
                };
                if i >= len {
                    return Err(PathError::Index {
                        path: resolved.to_string(),
                        index: i,
                        len,
                    });
                }
                resolved = resolved.index(i);
                item = item.and_then(|it| it.get(i));
            }
        }
        Ok(resolved)
    }

    /// The value at `path` as JSON-like data (tables become objects).
    pub fn get(&self, path: &str) -> Result<serde_json::Value, BoxError> {
        let resolved = self.resolve(path)?;
        let table: toml::Table = toml::from_str(&self.text())?;
        let mut value = toml::Value::Table(table);
        for s in &resolved.0 {
            value = match (s, value) {
                (Segment::Key(k), toml::Value::Table(mut t)) => {
                    t.remove(k).ok_or_else(|| format!("{path}: no value"))?
                }
                (Segment::Index(i), toml::Value::Array(mut a)) if *i < a.len() => a.swap_remove(*i),
                _ => return Err(format!("{path}: no value").into()),
            };
        }
        Ok(serde_json::to_value(value)?)
    }

    /// Sets the value at `path` to `value`, a TOML value as text (`12`, `"steel"`,
    /// `[0.0, 0.0, -9.81]`, `{ modes = 4 }`), and validates the study. A value the study
    /// refuses is not kept: the errors name the file, line, column and key, as
    /// `flexmbs check` does. Missing tables on the way are created. A table given an inline
    /// table (`{ name = "rod", shape = "general", A = 1e-4, ... }`) is replaced as a whole.
    pub fn set(&mut self, path: &str, value: &str) -> Result<(), BoxError> {
        let before = self.doc.clone();
        self.set_unchecked(path, value)?;
        if let Err(e) = self.study() {
            self.doc = before;
            return Err(Box::new(e));
        }
        Ok(())
    }

    /// Sets the value at `path` without validating the study (for changes that are only
    /// valid together; call [`Document::study`] after the last).
    pub fn set_unchecked(&mut self, path: &str, value: &str) -> Result<(), BoxError> {
        let parsed: toml_edit::Value = value
            .trim()
            .parse()
            .map_err(|e: toml_edit::TomlError| PathError::Value {
                path: path.to_string(),
                text: value.to_string(),
                why: e.message().trim().to_string(),
            })?;
        let resolved = self.resolve_with(path, true)?;
        // Every step was checked above: `IndexMut` creates missing tables and the last key.
        let mut item = self.doc.as_item_mut();
        for step in &resolved.0 {
            item = match step {
                Segment::Key(k) => &mut item[k.as_str()],
                Segment::Index(i) => &mut item[*i],
            };
        }
        if let toml_edit::Item::Table(old) = item {
            // A table given as an inline table replaces the whole table (its keys, and the
            // tables under it), where it stands in the file and with the comments above it.
            let toml_edit::Value::InlineTable(t) = parsed else {
                return Err(PathError::Malformed {
                    path: resolved.to_string(),
                    why: format!(
                        "a table can only be replaced by a table, not by a {}",
                        parsed.type_name()
                    ),
                }
                .into());
            };
            let mut table = t.into_table();
            table.set_implicit(false);
            *table.decor_mut() = old.decor().clone();
            if let Some(p) = old.position() {
                table.set_position(p);
            }
            *old = table;
            return Ok(());
        }
        if item.is_array_of_tables() {
            return Err(PathError::Malformed {
                path: resolved.to_string(),
                why: "an array of tables cannot be replaced by a value; set its elements one by one".into(),
            }
            .into());
        }
        // Keep the comment after the old value.
        let decor = item.as_value().map(|v| v.decor().clone());
        let mut v = parsed;
        if let Some(d) = decor {
            *v.decor_mut() = d;
        }
        *item = toml_edit::Item::Value(v);
        Ok(())
    }

    /// Removes the value or table at `path` (a key, an element of an array, or an element of
    /// an array of tables by its index or name) and validates the study. A removal the study
    /// refuses (a required key, a name still referred to) is not kept: the errors name the
    /// file, line, column and key, as [`Document::set`]'s do.
    pub fn remove(&mut self, path: &str) -> Result<(), BoxError> {
        let before = self.doc.clone();
        self.remove_unchecked(path)?;
        if let Err(e) = self.study() {
            self.doc = before;
            return Err(Box::new(e));
        }
        Ok(())
    }

    /// Removes the value or table at `path` without validating the study (see
    /// [`Document::set_unchecked`]).
    pub fn remove_unchecked(&mut self, path: &str) -> Result<(), BoxError> {
        let resolved = self.resolve(path)?;
        let Some((last, parent)) = resolved.0.split_last() else {
            return Err(PathError::Malformed {
                path: path.to_string(),
                why: "the whole study cannot be removed".into(),
            }
            .into());
        };
        let mut item = self.doc.as_item_mut();
        for step in parent {
            item = match step {
                Segment::Key(k) => &mut item[k.as_str()],
                Segment::Index(i) => &mut item[*i],
            };
        }
        // `resolve` found the value, so its parent holds it.
        match (last, item) {
            (Segment::Key(k), parent) => {
                parent.as_table_like_mut().and_then(|t| t.remove(k));
            }
            (Segment::Index(i), toml_edit::Item::ArrayOfTables(a)) => {
                a.remove(*i);
            }
            (Segment::Index(i), toml_edit::Item::Value(toml_edit::Value::Array(a))) => {
                a.remove(*i);
            }
            (Segment::Index(_), other) => {
                return Err(PathError::NotTable {
                    path: resolved.to_string(),
                    key: path.to_string(),
                    found: kind_of(other),
                }
                .into())
            }
        }
        Ok(())
    }

    /// The error for a key that is not there, with the keys that are.
    fn missing(&self, item: Option<&toml_edit::Item>, at: &str, key: &str) -> PathError {
        let keys: Vec<String> = match item {
            Some(toml_edit::Item::Table(t)) => t.iter().map(|(k, _)| k.to_string()).collect(),
            Some(toml_edit::Item::ArrayOfTables(a)) => a
                .iter()
                .filter_map(|t| t.get("name").and_then(|n| n.as_str()).map(str::to_string))
                .collect(),
            _ => Vec::new(),
        };
        let close = crate::input::source::close_matches(key, keys.iter().map(String::as_str));
        let hint = match close.first() {
            Some(c) => format!("; did you mean '{c}'?"),
            None if keys.is_empty() => String::new(),
            None => format!(" (there are: {})", keys.join(", ")),
        };
        PathError::Missing {
            path: at.to_string(),
            key: key.to_string(),
            hint,
        }
    }
}
