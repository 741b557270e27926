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
pub use crate::input::toml_path::PathError;
use crate::input::toml_path::{self, kind_of};
use crate::input::validate::{parse_and_validate, Study};
use std::path::{Path, PathBuf};

/// A study file held in memory (module docs).
#[derive(Clone, Debug)]
pub struct Document {
    /// The file it came from, or the name it is known by; relative paths in the study
    /// (meshes, reduced bodies, the results folder) are taken from its folder.
    pub path: PathBuf,
    doc: toml_edit::DocumentMut,
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
    /// validation's errors name it (`parts[0].reduction.modes`).
    pub fn resolve(&self, path: &str) -> Result<KeyPath, PathError> {
        toml_path::resolve(&self.doc, path)
    }

    /// The value at `path` as JSON-like data (tables become objects).
    pub fn get(&self, path: &str) -> Result<serde_json::Value, BoxError> {
        toml_path::value_at(&self.doc, path)
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
        let resolved = toml_path::resolve_for_writing(&self.doc, path)?;
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
}
