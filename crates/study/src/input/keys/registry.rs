//! The registry's data, `registry.toml`: every table of a study file and its keys, in the order
//! the doc lists them. A key's kinds, when given, are the only kinds of its table that take it.
//!
//! The file is compiled in and read once, on first use, into the `'static` [`Table`] and
//! [`Key`] values the rest of `keys` works with (the strings live as long as the program, as
//! they would as literals).

use super::{Key, Presence, Table};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::sync::LazyLock;

/// Every table of a study file, read from `registry.toml`.
///
/// # Panics
/// On first use, when `registry.toml` does not parse: the file is compiled in, so any test
/// that reaches the registry catches it.
pub static TABLES: LazyLock<Vec<Table>> =
    LazyLock::new(|| parse(include_str!("registry.toml")).unwrap_or_else(|e| panic!("keys/registry.toml: {e}")));

/// The file: shared kinds lists, then the tables.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RegistryFile {
    #[serde(default)]
    lists: BTreeMap<String, Vec<String>>,
    tables: Vec<TableEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TableEntry {
    path: String,
    header: String,
    #[serde(default)]
    kinds_from: String,
    #[serde(default)]
    kinds: Vec<String>,
    keys: Vec<KeyEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KeyEntry {
    name: String,
    #[serde(rename = "type")]
    ty: String,
    #[serde(default)]
    unit: String,
    presence: Option<PresenceEntry>,
    default: Option<String>,
    #[serde(default)]
    kinds: Vec<String>,
    #[serde(default)]
    range: String,
    doc: String,
}

#[derive(Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum PresenceEntry {
    Required,
    Optional,
}

/// The tables of the registry file `text`, or what is wrong with it (naming the table and key).
fn parse(text: &str) -> Result<Vec<Table>, String> {
    let file: RegistryFile = toml::from_str(text).map_err(|e| e.to_string())?;
    let lists = &file.lists;
    file.tables
        .into_iter()
        .map(|t| {
            let in_table = |e: String| format!("table `{}`: {e}", t.path);
            let keys = t
                .keys
                .into_iter()
                .map(|k| key(k, lists))
                .collect::<Result<Vec<Key>, String>>();
            let kinds = kinds(t.kinds, lists).map_err(in_table)?;
            let keys = keys.map_err(in_table)?;
            Ok(Table {
                path: leak(t.path),
                header: leak(t.header),
                kinds_from: leak(t.kinds_from),
                kinds,
                keys: Vec::leak(keys),
            })
        })
        .collect()
}

fn key(k: KeyEntry, lists: &BTreeMap<String, Vec<String>>) -> Result<Key, String> {
    let presence = match (k.presence, k.default) {
        (Some(PresenceEntry::Required), None) => Presence::Required,
        (Some(PresenceEntry::Optional), None) => Presence::Optional,
        (None, Some(value)) => Presence::Default(leak(value)),
        _ => return Err(format!("key `{}`: give `presence` or `default`, one of them", k.name)),
    };
    Ok(Key {
        kinds: kinds(k.kinds, lists).map_err(|e| format!("key `{}`: {e}", k.name))?,
        name: leak(k.name),
        ty: leak(k.ty),
        unit: leak(k.unit),
        presence,
        range: leak(k.range),
        doc: leak(k.doc),
    })
}

/// `names` with every name of a shared list (in capitals) replaced by the list's kinds.
fn kinds(names: Vec<String>, lists: &BTreeMap<String, Vec<String>>) -> Result<&'static [&'static str], String> {
    Ok(Vec::leak(spliced(names, lists, 0)?.into_iter().map(leak).collect()))
}

fn spliced(names: Vec<String>, lists: &BTreeMap<String, Vec<String>>, depth: usize) -> Result<Vec<String>, String> {
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        if !name.starts_with(|c: char| c.is_ascii_uppercase()) {
            out.push(name);
            continue;
        }
        let list = lists.get(&name).ok_or_else(|| format!("no list `{name}` in [lists]"))?;
        if depth > lists.len() {
            return Err(format!("the list `{name}` contains itself"));
        }
        out.extend(spliced(list.clone(), lists, depth + 1)?);
    }
    Ok(out)
}

fn leak(s: String) -> &'static str {
    String::leak(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_registry_parses_and_every_key_has_type_presence_and_doc() {
        assert!(!TABLES.is_empty());
        for t in TABLES.iter() {
            assert!(!t.keys.is_empty(), "table `{}` has no keys", t.path);
            for k in t.keys {
                assert!(!k.ty.is_empty(), "`{}.{}` has no type", t.path, k.name);
                assert!(!k.doc.is_empty(), "`{}.{}` has no doc", t.path, k.name);
                if let Presence::Default(v) = k.presence {
                    assert!(!v.is_empty(), "`{}.{}` has an empty default", t.path, k.name);
                }
            }
        }
    }

    #[test]
    fn shared_lists_are_spliced_into_kinds() {
        let sensors = super::super::table("sensors");
        assert_eq!(sensors.kinds.len(), 19);
        assert_eq!(sensors.kinds[..2], ["position", "displacement"]);
        assert_eq!(sensors.kinds[16..], ["energy", "momentum", "energy-balance"]);
        let of = sensors.key("of").expect("sensors take `of`");
        assert_eq!(of.kinds, &sensors.kinds[..16]);
    }

    #[test]
    fn a_bad_entry_is_refused_with_its_table_and_key() {
        let table = |key: &str| format!("[[tables]]\npath = \"t\"\nheader = \"[t]\"\nkeys = [{key}]\n");
        let e = parse(&table(r#"{ name = "k", type = "string", doc = "d" }"#)).unwrap_err();
        assert!(e.contains("table `t`: key `k`: give `presence` or `default`"), "{e}");
        let e = parse(&table(
            r#"{ name = "k", type = "string", presence = "optional", default = "1", doc = "d" }"#,
        ))
        .unwrap_err();
        assert!(e.contains("key `k`"), "{e}");
        let e = parse(&table(
            r#"{ name = "k", type = "string", presence = "optional", kinds = ["NONE"], doc = "d" }"#,
        ))
        .unwrap_err();
        assert!(e.contains("no list `NONE`"), "{e}");
        let e = parse(&table(r#"{ name = "k", presence = "optional", doc = "d" }"#)).unwrap_err();
        assert!(e.contains("type"), "{e}");
        let cycle = format!(
            "[lists]\nA = [\"A\"]\n{}",
            table(r#"{ name = "k", type = "t", presence = "optional", kinds = ["A"], doc = "d" }"#)
        );
        assert!(parse(&cycle).unwrap_err().contains("contains itself"));
    }
}
