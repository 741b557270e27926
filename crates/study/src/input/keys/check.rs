//! The checks the registry states by itself, run on every table of a study file: a key the
//! registry marks required and the table's kind takes is there, and a number is in its key's
//! range. The validator runs this once per file and only adds the checks the registry cannot
//! express (rules between keys, references to names); where it needs to know whether a value
//! passed, it asks [`super::in_range`] (which reports nothing: the message is given here).

use super::range::{number_text, Range};
use super::{child, table, Key, Presence, Table};
use crate::input::source::{KeyPath, StudyError};

/// The errors of the registry's own checks on the document `doc` (the whole file), in the
/// order of the file's tables.
pub fn check(doc: &toml::Table) -> Vec<StudyError> {
    let mut errors = Vec::new();
    visit(table(""), doc, &KeyPath::root(), &mut errors);
    errors
}

/// The kind of the table instance `value`, when its kind key (`` `type` ``, `` `shape` ``) is
/// given and names one of the table's kinds; `None` otherwise (a table without kinds, a kind
/// told by something else than a key, or an unknown kind, which the validator reports).
fn kind_of(t: &Table, value: &toml::Table) -> Option<&'static str> {
    let kind_key = t.kinds_from.strip_prefix('`')?.strip_suffix('`')?;
    let given = value.get(kind_key)?.as_str()?;
    t.kinds.iter().copied().find(|k| *k == given)
}

/// Whether `key` concerns a table of kind `kind` (`None`: unknown, then only the keys of every
/// kind).
fn concerns(key: &Key, kind: Option<&str>) -> bool {
    match kind {
        Some(kind) => key.applies_to(kind),
        None => key.kinds.is_empty(),
    }
}

fn visit(t: &'static Table, value: &toml::Table, at: &KeyPath, errors: &mut Vec<StudyError>) {
    let kind = kind_of(t, value);
    for key in t.keys {
        let here = at.key(key.name);
        let Some(v) = value.get(key.name) else {
            if key.presence == Presence::Required && concerns(key, kind) {
                errors.push(StudyError::at(at, missing(t, key, kind)));
            }
            continue;
        };
        // A key the kind does not take is refused by the validator, once.
        if kind.is_none_or(|kind| key.applies_to(kind)) {
            numbers(key, v, &here, errors);
        }
        let Some(sub) = child(t.path, key.name) else {
            continue;
        };
        match v {
            toml::Value::Table(inner) => visit(sub, inner, &here, errors),
            toml::Value::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    if let toml::Value::Table(inner) = item {
                        visit(sub, inner, &here.index(i), errors);
                    }
                }
            }
            _ => {}
        }
    }
}

/// "missing key `h` \[m\] (with shape = \"rectangle\"): height along local z"; a doc longer
/// than a line of a terminal is left to the documentation.
fn missing(t: &Table, key: &Key, kind: Option<&str>) -> String {
    let mut m = format!("missing key `{}`", key.name);
    if !key.unit.is_empty() {
        m += &format!(" [{}]", key.unit);
    }
    if let (Some(kind), false) = (kind, key.kinds.is_empty()) {
        m += &format!(" (with {} = \"{kind}\")", t.kinds_from.trim_matches('`'));
    }
    if key.doc.chars().count() <= 80 {
        m += &format!(": {}", key.doc);
    }
    m
}

/// The range errors of the value `v` of `key`: a number, or each number of a list.
fn numbers(key: &Key, v: &toml::Value, at: &KeyPath, errors: &mut Vec<StudyError>) {
    let range = key.range();
    if matches!(range, Range::Any | Range::Names(_)) {
        return;
    }
    let mut one = |x: f64, at: &KeyPath| {
        if !range.admits(x) {
            errors.push(StudyError::at(at, out_of_range(key, &range, x)));
        }
    };
    match v {
        toml::Value::Integer(n) => one(*n as f64, at),
        toml::Value::Float(x) => one(*x, at),
        toml::Value::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                match item {
                    toml::Value::Integer(n) => one(*n as f64, &at.index(i)),
                    toml::Value::Float(x) => one(*x, &at.index(i)),
                    _ => {}
                }
            }
        }
        _ => {}
    }
}

/// "E \[Pa\] must be positive and finite, got -7", "nu must lie in (-1, 0.5), got 0.5".
fn out_of_range(key: &Key, range: &Range, x: f64) -> String {
    let unit = if key.unit.is_empty() {
        String::new()
    } else {
        format!(" [{}]", key.unit)
    };
    format!("{}{unit} {range}, got {}", key.name, number_text(x))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(text: &str) -> Vec<String> {
        let doc: toml::Table = text.parse().unwrap();
        check(&doc)
            .into_iter()
            .map(|e| format!("{}: {}", e.path, e.message))
            .collect()
    }

    #[test]
    fn required_keys_follow_the_kind_and_ranges_every_table() {
        let found = errors(
            r#"
            [[materials]]
            name = "m"
            E = -1
            nu = 0.5
            rho = 1

            [[sections]]
            name = "s"
            shape = "rectangle"
            b = 0.01

            [[sections]]
            name = "t"
            shape = "values"
            A = 1
            Iy = 1
            Iz = 1
            J = 1
            ky = 2

            [[parts]]
            name = "p"
            box = { size = [1, 0, 1], divisions = [1, 1, 1], element = "hex8" }

            [[drivers]]
            name = "d"
            joint = "j"
            function = { type = "ramp", to = 1 }

            [[analyses]]
            type = "static"
            modes = 0
            "#,
        );
        assert_eq!(
            found,
            [
                "materials[0].E: E [Pa] must be positive and finite, got -1",
                "materials[0].nu: nu must lie in (-1, 0.5), got 0.5",
                "sections[0]: missing key `h` [m] (with shape = \"rectangle\"): height along local z",
                "sections[1].ky: ky must lie in (0, 1], got 2",
                "parts[0].box.size[1]: size [m] must be positive and finite, got 0",
                "drivers[0].function: missing key `t_end` [s] (with type = \"ramp\"): when the ramp ends (after `t_start`)",
                "analyses[0]: missing key `part` (with type = \"static\"): the part the analysis runs on (`reduce`: a part with a `[parts.reduction]`)",
                "analyses[0]: missing key `loads` (with type = \"static\")",
            ],
            "`modes` of a static analysis is refused by the validator, not range-checked"
        );
    }

    #[test]
    fn a_table_of_unknown_kind_is_checked_for_the_keys_of_every_kind_only() {
        assert!(errors("[[sections]]\nname = \"s\"\nshape = \"hexagon\"\n").is_empty());
        assert_eq!(
            errors("[[analyses]]\ntype = \"dynamic\"\nt_end = 0\n"),
            ["analyses[0].t_end: t_end [s] must be positive and finite, got 0"]
        );
    }

    #[test]
    fn a_function_of_time_is_checked_wherever_it_appears() {
        let found = errors(
            r#"
            [[actuators]]
            name = "a"
            joint = "j"
            pid = { kp = -1, setpoint = { type = "spin-up", speed = 1, ramp_time = 0 } }
            "#,
        );
        assert_eq!(
            found,
            [
                "actuators[0].pid.kp: kp must be non-negative and finite, got -1",
                "actuators[0].pid.setpoint.ramp_time: ramp_time [s] must be positive and finite, got 0",
            ]
        );
    }
}
