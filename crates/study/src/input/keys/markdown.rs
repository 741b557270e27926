//! The key tables of the docs, rendered from the registry.
//!
//! A document marks each generated table with a pair of comments naming a table of the
//! registry and, for a table with kinds, optionally the kinds it shows:
//!
//! ```text
//! <!-- keys:joints begin -->
//! ...generated...
//! <!-- keys:joints end -->
//! <!-- keys:analyses:equilibrium,dynamic begin -->
//! ...the keys that only these kinds take...
//! <!-- keys:analyses:equilibrium,dynamic end -->
//! ```
//!
//! [`render_doc`] rewrites what lies between every such pair and keeps the rest of the text.

use super::{Key, Table, TABLES};
use std::fmt;

const PREFIX: &str = "<!-- keys:";
const BEGIN: &str = " begin -->";
const END: &str = " end -->";

/// A marker of a document that [`render_doc`] cannot render.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MarkerError {
    /// 1-based line of the marker.
    pub line: usize,
    pub message: String,
}

impl fmt::Display for MarkerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for MarkerError {}

/// The Markdown table of the keys of `table`. With `kinds`, only the keys that some of these
/// kinds take and not every kind (the keys common to all kinds, such as `type` and `name`, are
/// the prose's), with a `kinds` column when more than one kind is shown; without, every key, with
/// a `kinds` column when the table has kinds.
pub fn markdown_table(table: &Table, kinds: Option<&[&str]>) -> String {
    let keys: Vec<&Key> = table
        .keys
        .iter()
        .filter(|k| match kinds {
            None => true,
            Some(shown) => k.kinds.iter().any(|kind| shown.contains(kind)),
        })
        .collect();
    let kinds_column = match kinds {
        None => !table.kinds.is_empty(),
        Some(shown) => shown.len() > 1,
    };
    let mut out = String::new();
    if kinds_column {
        out.push_str("| key | kinds | value | default | meaning |\n|---|---|---|---|---|\n");
    } else {
        out.push_str("| key | value | default | meaning |\n|---|---|---|---|\n");
    }
    for k in keys {
        out.push_str(&format!("| `{}` |", k.name));
        if kinds_column {
            let of: Vec<&str> = k
                .kinds
                .iter()
                .copied()
                .filter(|kind| kinds.is_none_or(|shown| shown.contains(kind)))
                .collect();
            let text = if of.is_empty() {
                "all".to_string()
            } else {
                of.join(", ")
            };
            out.push_str(&format!(" {} |", cell(&text)));
        }
        out.push_str(&format!(
            " {} | {} | {} |\n",
            cell(&value(k)),
            cell(k.presence.text()),
            cell(k.doc)
        ));
    }
    out
}

/// The value column: type, unit and range (`number [Pa]; > 0`).
fn value(k: &Key) -> String {
    let mut text = k.ty.to_string();
    if !k.unit.is_empty() {
        text.push_str(&format!(" [{}]", k.unit));
    }
    if !k.range.is_empty() {
        text.push_str(&format!("; {}", k.range));
    }
    text
}

/// Text made safe for a table cell: a `|` would end the cell.
fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}

/// The table and kinds a marker names: `joints`, or `analyses:static` / `analyses:a,b`.
fn parse_spec(spec: &str, line: usize) -> Result<(&'static Table, Option<Vec<&'static str>>), MarkerError> {
    let error = |message: String| MarkerError { line, message };
    let (path, kinds) = match spec.split_once(':') {
        Some((path, kinds)) => (path, Some(kinds)),
        None => (spec, None),
    };
    let table = TABLES
        .iter()
        .find(|t| t.path == path)
        .ok_or_else(|| error(format!("the key registry has no table `{path}`")))?;
    let Some(kinds) = kinds else {
        return Ok((table, None));
    };
    let mut shown = Vec::new();
    for kind in kinds.split(',') {
        let Some(known) = table.kinds.iter().find(|k| **k == kind) else {
            return Err(error(format!(
                "table `{path}` has no kind '{kind}' (its kinds: {})",
                table.kinds.join(", ")
            )));
        };
        shown.push(*known);
    }
    Ok((table, Some(shown)))
}

/// `text` with the content between every pair of key markers rendered anew from the registry
/// (line endings `\n`). Errors: a marker naming no table or kind of the registry, a `begin`
/// without its `end`, an `end` without a `begin`.
pub fn render_doc(text: &str) -> Result<String, MarkerError> {
    let mut out = String::with_capacity(text.len());
    let mut open: Option<(usize, &str)> = None;
    for (i, line) in text.lines().enumerate() {
        let marker = line
            .trim()
            .strip_prefix(PREFIX)
            .map(|rest| (rest.strip_suffix(BEGIN), rest.strip_suffix(END)));
        match (open, marker) {
            (None, Some((Some(spec), _))) => {
                let (table, kinds) = parse_spec(spec, i + 1)?;
                out.push_str(line);
                out.push('\n');
                out.push_str(&markdown_table(table, kinds.as_deref()));
                open = Some((i + 1, spec));
            }
            (Some((_, spec)), Some((_, Some(end)))) if end == spec => {
                out.push_str(line);
                out.push('\n');
                open = None;
            }
            (Some((begun, spec)), Some(_)) => {
                return Err(MarkerError {
                    line: i + 1,
                    message: format!("a key marker inside the table `{spec}` begun at line {begun}"),
                })
            }
            (None, Some((None, Some(spec)))) => {
                return Err(MarkerError {
                    line: i + 1,
                    message: format!("`{spec} end` without its begin"),
                })
            }
            (Some(_), None) => {}
            (None, _) => {
                out.push_str(line);
                out.push('\n');
            }
        }
    }
    if let Some((begun, spec)) = open {
        return Err(MarkerError {
            line: begun,
            message: format!("`{spec} begin` without its end"),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_between_markers_and_keeps_the_rest() {
        let doc = "intro\n<!-- keys:output begin -->\nold\n<!-- keys:output end -->\nafter\n";
        let out = render_doc(doc).unwrap();
        assert!(out.starts_with("intro\n<!-- keys:output begin -->\n| key | value | default | meaning |\n"));
        assert!(out.contains("| `vtu_every` | integer; >= 1 | never | write the deformed meshes"));
        assert!(out.ends_with("<!-- keys:output end -->\nafter\n"));
        assert!(!out.contains("old"));
        assert_eq!(render_doc(&out).unwrap(), out);
    }

    #[test]
    fn a_kind_filter_shows_the_keys_of_those_kinds() {
        let out = markdown_table(super::super::table("analyses"), Some(&["reduce"]));
        assert_eq!(
            out,
            "| key | value | default | meaning |\n|---|---|---|---|\n| `part` | string | required | the part the analysis runs on (`reduce`: a part with a `[parts.reduction]`) |\n"
        );
    }

    #[test]
    fn bad_markers_are_errors_with_their_line() {
        let e = render_doc("a\n<!-- keys:nowhere begin -->\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(e.message.contains("no table `nowhere`"));
        let e = render_doc("<!-- keys:output begin -->\n").unwrap_err();
        assert!(e.message.contains("without its end"), "{e}");
        let e = render_doc("<!-- keys:output end -->\n").unwrap_err();
        assert!(e.message.contains("without its begin"), "{e}");
        let e = render_doc("<!-- keys:analyses:nope begin -->\n").unwrap_err();
        assert!(e.message.contains("no kind 'nope'"), "{e}");
    }
}
