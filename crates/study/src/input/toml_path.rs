//! Key paths into a study's TOML text: `parts[0].reduction.modes`, or an element of an array
//! of tables by its `name`, `parts.rod.reduction.modes`. A leaf of the input wing: the
//! editable [`crate::input::document::Document`] and the validation of `[fmu] parameters`
//! both resolve paths here, so neither imports the other for it.

use crate::error::BoxError;
use crate::input::source::{close_matches, KeyPath, Segment};

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
pub(crate) fn kind_of(item: &toml_edit::Item) -> String {
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

/// The key path with every element of an array of tables given by its index, as the
/// validation's errors name it (`parts[0].reduction.modes`).
pub(crate) fn resolve(doc: &toml_edit::DocumentMut, path: &str) -> Result<KeyPath, PathError> {
    resolve_in(doc, path, false)
}

/// As [`resolve`], for a value about to be written: keys that are missing are accepted (they
/// will be created), but not missing elements.
pub(crate) fn resolve_for_writing(doc: &toml_edit::DocumentMut, path: &str) -> Result<KeyPath, PathError> {
    resolve_in(doc, path, true)
}

fn resolve_in(doc: &toml_edit::DocumentMut, path: &str, create: bool) -> Result<KeyPath, PathError> {
    let steps = parse_path(path)?;
    let mut resolved = KeyPath::root();
    let mut item = Some(doc.as_item());
    for (key, indices) in &steps {
        let at = resolved.to_string();
        let next = match item {
            None => None,
            Some(toml_edit::Item::ArrayOfTables(a)) => {
                // A name picks the element.
                let Some(i) = by_name(a, key) else {
                    return Err(missing(item, &at, key));
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
            return Err(missing(item, &at, key));
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
pub(crate) fn value_at(doc: &toml_edit::DocumentMut, path: &str) -> Result<serde_json::Value, BoxError> {
    let resolved = resolve(doc, path)?;
    let table: toml::Table = toml::from_str(&doc.to_string())?;
    let mut value = toml::Value::Table(table);
    for s in &resolved.0 {
        value = match (s, value) {
            (Segment::Key(k), toml::Value::Table(mut t)) => t.remove(k).ok_or_else(|| format!("{path}: no value"))?,
            (Segment::Index(i), toml::Value::Array(mut a)) if *i < a.len() => a.swap_remove(*i),
            _ => return Err(format!("{path}: no value").into()),
        };
    }
    Ok(serde_json::to_value(value)?)
}

/// The error for a key that is not there, with the keys that are.
fn missing(item: Option<&toml_edit::Item>, at: &str, key: &str) -> PathError {
    let keys: Vec<String> = match item {
        Some(toml_edit::Item::Table(t)) => t.iter().map(|(k, _)| k.to_string()).collect(),
        Some(toml_edit::Item::ArrayOfTables(a)) => a
            .iter()
            .filter_map(|t| t.get("name").and_then(|n| n.as_str()).map(str::to_string))
            .collect(),
        _ => Vec::new(),
    };
    let close = close_matches(key, keys.iter().map(String::as_str));
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
