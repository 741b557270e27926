//! The keys of a study file, each declared once: its table, name, value type, unit, default,
//! range and meaning ([`TABLES`], read from `keys/registry.toml`).
//!
//! Everything else that lists keys derives from here:
//!
//! - the validator asks [`allowed`] which keys a kind of a table takes (a `'ramp'` function,
//!   an `'equilibrium'` analysis, a beam part's interface), so a key misplaced in a table that
//!   serde accepts (the schema's flat structs take the union of every kind's keys) is refused
//!   with the kind's own list;
//! - the key tables of `docs/study-file.md` are rendered by [`markdown_table`] between marker
//!   comments (`<!-- keys:joints begin -->` ... `<!-- keys:joints end -->`);
//!   [`render_doc`] rewrites every marked table of a document, and `tests/keys.rs` fails when
//!   the doc differs from what the registry renders (`FLEXMBS_BLESS=1` rewrites it);
//! - `tests/keys.rs` also checks that every serde field of [`crate::input::schema`] has an
//!   entry here and every entry a field, so the two cannot drift;
//! - the Python face lists the keys through [`entries`].

mod check;
mod markdown;
mod range;
mod registry;

pub use check::check;
pub use markdown::{markdown_table, render_doc, MarkerError};
pub use range::{Limit, Range, RangeError};
pub use registry::TABLES;

/// Whether a key must be given, and what it is when it is not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presence {
    /// The key must be given (for the kinds that take it).
    Required,
    /// The key may be left out; its absence means what the doc says (another key is used, or
    /// the feature is off).
    Optional,
    /// The key may be left out; this is the value then (as the doc writes it, e.g. `"0"`,
    /// `"true"`, `"the initial length"`).
    Default(&'static str),
}

impl Presence {
    /// `required`, the default value, or an empty string for an optional key.
    pub fn text(self) -> &'static str {
        match self {
            Presence::Required => "required",
            Presence::Optional => "",
            Presence::Default(v) => v,
        }
    }
}

/// One key of a table.
#[derive(Clone, Copy, Debug)]
pub struct Key {
    /// The key as written in the file (`angle_deg`, `E`, `type`).
    pub name: &'static str,
    /// The kinds of its table that take it (values of the table's kind key, or the cases the
    /// table's [`Table::kinds_from`] names); empty: every kind, or a table without kinds.
    pub kinds: &'static [&'static str],
    /// The value's TOML type, as users read it: `string`, `integer`, `number`, `bool`,
    /// `[x, y, z]`, `table`, `list of tables`, ...
    pub ty: &'static str,
    /// SI unit of the value (`m`, `Pa`, `kg m²`); empty when it has none or depends on the
    /// kind (the doc then says).
    pub unit: &'static str,
    pub presence: Presence,
    /// The values it may take (`> 0`, `[0, 1]`, or the names of a choice); empty: any of its
    /// type.
    pub range: &'static str,
    /// What it means (Markdown, one line).
    pub doc: &'static str,
}

impl Key {
    /// Whether the kind `kind` of its table takes this key.
    pub fn applies_to(&self, kind: &str) -> bool {
        self.kinds.is_empty() || self.kinds.contains(&kind)
    }

    /// Its range in typed form ([`Range::Any`] for a text the parser does not read, which the
    /// registry's tests refuse).
    pub fn range(&self) -> Range {
        Range::parse(self.range).unwrap_or(Range::Any)
    }
}

/// A table of a study file: a section (`[[joints]]`), a sub-table (`[parts.beam]`) or an inline
/// table that several sections share (a function of time).
#[derive(Clone, Copy, Debug)]
pub struct Table {
    /// Dotted path from the file's root (`parts.beam`, `bodies.matrices`); `function` for a
    /// function of time wherever it appears; the empty string for the file's root, whose keys
    /// are the sections.
    pub path: &'static str,
    /// Where it appears, as the doc writes it (`[[joints]]`, `[parts.beam]`,
    /// `function = { ... }`).
    pub header: &'static str,
    /// What selects the kind (`` `type` ``, `` `shape` ``, `the part's geometry`); empty for a
    /// table without kinds.
    pub kinds_from: &'static str,
    /// Its kinds, in the order the doc lists them.
    pub kinds: &'static [&'static str],
    pub keys: &'static [Key],
}

impl Table {
    /// A table without kinds.
    pub const fn plain(path: &'static str, header: &'static str, keys: &'static [Key]) -> Table {
        Table {
            path,
            header,
            kinds_from: "",
            kinds: &[],
            keys,
        }
    }

    /// The keys the kind `kind` takes, in the registry's order.
    pub fn keys_of(&self, kind: &str) -> Vec<&'static str> {
        self.keys
            .iter()
            .filter(|k| k.applies_to(kind))
            .map(|k| k.name)
            .collect()
    }

    /// The key called `name`.
    pub fn key(&self, name: &str) -> Option<&'static Key> {
        self.keys.iter().find(|k| k.name == name)
    }
}

/// The table at `path` (`parts.beam`, `analyses`, `function`).
///
/// # Panics
/// When the registry has no such table: a typo in the code, caught by any test that reaches it.
pub fn table(path: &str) -> &'static Table {
    TABLES
        .iter()
        .find(|t| t.path == path)
        .unwrap_or_else(|| panic!("the key registry has no table `{path}`"))
}

/// Where a function of time (the registry's table `function`) appears: its parent table and
/// key.
const FUNCTIONS: &[(&str, &str)] = &[
    ("drivers", "function"),
    ("loads", "function"),
    ("actuators", "function"),
    ("actuators.pid", "setpoint"),
];

/// The registry's table under the key `key` of the table at `parent` (`parts` and `beam`:
/// `parts.beam`; a function of time wherever it appears: `function`).
pub fn child(parent: &str, key: &str) -> Option<&'static Table> {
    if FUNCTIONS.contains(&(parent, key)) {
        return Some(table("function"));
    }
    let path = if parent.is_empty() {
        key.to_string()
    } else {
        format!("{parent}.{key}")
    };
    TABLES.iter().find(|t| t.path == path)
}

/// The keys that the kind `kind` of the table at `path` takes (every key of a table without
/// kinds: pass `""`), in the registry's order.
pub fn allowed(path: &str, kind: &str) -> Vec<&'static str> {
    table(path).keys_of(kind)
}

/// Whether the number `x` given for `key` of the table at `path` is in the key's range. Reports
/// nothing: [`check()`] gave the message for the file; the validator asks this to know whether
/// to build with the value.
pub fn in_range(path: &str, key: &str, x: f64) -> bool {
    table(path).key(key).is_none_or(|k| k.range().admits(x))
}

/// `x` when it is in the range of `key` of the table at `path` ([`in_range`]).
pub fn ranged(path: &str, key: &str, x: f64) -> Option<f64> {
    in_range(path, key, x).then_some(x)
}

/// The names a choice key takes, from its range (`` `auto`, `dense`, `sparse` ``).
///
/// # Panics
/// When the key is not in the registry or its range is no list of names: a typo in the code,
/// caught by any test that reaches it.
pub fn names(path: &str, key: &str) -> Vec<&'static str> {
    let k = table(path)
        .key(key)
        .unwrap_or_else(|| panic!("the key registry has no key `{key}` in `{path}`"));
    let names = k.range().names().to_vec();
    assert!(!names.is_empty(), "the range of `{path}.{key}` is no list of names");
    names
}

/// One key with its table, flat, for faces that list the keys (Python stubs, completion).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Entry {
    /// Dotted path of the table (`parts.beam`; `function`: a function of time).
    pub table: &'static str,
    pub name: &'static str,
    /// The kinds of the table that take it (empty: all).
    pub kinds: Vec<&'static str>,
    pub ty: &'static str,
    pub unit: &'static str,
    /// `true` when the key must be given.
    pub required: bool,
    /// The default value as the doc writes it; empty when none.
    pub default: &'static str,
    pub range: &'static str,
    pub doc: &'static str,
}

/// Every key of every table, in the registry's order.
pub fn entries() -> Vec<Entry> {
    TABLES
        .iter()
        .flat_map(|t| {
            t.keys.iter().map(move |k| Entry {
                table: t.path,
                name: k.name,
                kinds: k.kinds.to_vec(),
                ty: k.ty,
                unit: k.unit,
                required: k.presence == Presence::Required,
                default: match k.presence {
                    Presence::Default(v) => v,
                    _ => "",
                },
                range: k.range,
                doc: k.doc,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn tables_and_keys_are_unique_and_kinds_declared() {
        let mut paths = HashSet::new();
        for t in TABLES.iter() {
            assert!(paths.insert(t.path), "table `{}` declared twice", t.path);
            let mut names = HashSet::new();
            for k in t.keys {
                assert!(names.insert(k.name), "key `{}` declared twice in `{}`", k.name, t.path);
                for kind in k.kinds {
                    assert!(
                        t.kinds.contains(kind),
                        "key `{}` of `{}` names kind '{kind}', which the table does not declare",
                        k.name,
                        t.path
                    );
                }
                assert!(!k.doc.contains('\n'), "the doc of `{}.{}` spans lines", t.path, k.name);
            }
            assert_eq!(t.kinds.is_empty(), t.kinds_from.is_empty(), "table `{}`", t.path);
        }
    }

    #[test]
    fn every_range_of_the_registry_parses() {
        let unread: Vec<String> = TABLES
            .iter()
            .flat_map(|t| t.keys.iter().map(move |k| (t.path, k)))
            .filter_map(|(path, k)| Range::parse(k.range).err().map(|e| format!("`{path}.{}`: {e}", k.name)))
            .collect();
        assert!(unread.is_empty(), "{unread:#?}");
        // And a numeric range only on a number (or numbers), a choice only on a string.
        for t in TABLES.iter() {
            for k in t.keys {
                match k.range() {
                    Range::Between { .. } | Range::Numbers(_) => assert!(
                        ["number", "integer"].contains(&k.ty) || k.ty.starts_with('['),
                        "`{}.{}` ({}) has the numeric range `{}`",
                        t.path,
                        k.name,
                        k.ty,
                        k.range
                    ),
                    Range::Names(_) => assert!(k.ty.starts_with("string"), "`{}.{}`", t.path, k.name),
                    Range::Any => {}
                }
            }
        }
    }

    #[test]
    fn kinds_take_the_keys_the_validator_listed() {
        assert_eq!(allowed("loads", "gravity"), ["name", "type", "g"]);
        assert_eq!(
            allowed("function", "ramp"),
            ["type", "t_start", "t_end", "from", "to", "smooth"]
        );
        assert_eq!(allowed("sensors", "energy"), ["name", "type"]);
        assert_eq!(allowed("analyses", "reduce"), ["type", "name", "part"]);
    }
}
