//! The key registry (`study::input::keys`) against the two other places that name keys: the
//! serde schema, whose fields must be the registry's keys table by table, and
//! `docs/study-file.md`, whose key tables must be the ones the registry renders.

use serde::de::DeserializeOwned;
use std::collections::BTreeSet;
use std::path::PathBuf;
use study::input::keys::{self, TABLES};
use study::input::schema::*;

/// The serde fields of `T`, from the message of its `deny_unknown_fields` on a key it lacks:
/// "unknown field `zz`, expected one of `a`, `b`" (or "expected `a` or `b`", "expected `a`").
fn fields<T: DeserializeOwned + std::fmt::Debug>() -> BTreeSet<String> {
    let e = toml::from_str::<T>("zz_not_a_key = 0").expect_err("an unknown key is refused");
    let message = e.to_string();
    let (_, expected) = message
        .split_once("expected")
        .unwrap_or_else(|| panic!("no list of fields in: {message}"));
    expected.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// Every table of the schema: the registry's path and the serde fields of its struct.
fn schema_tables() -> Vec<(&'static str, BTreeSet<String>)> {
    vec![
        ("", fields::<StudyFile>()),
        ("study", fields::<StudyInfo>()),
        ("materials", fields::<MaterialFile>()),
        ("sections", fields::<SectionFile>()),
        ("parts", fields::<PartFile>()),
        ("parts.beam", fields::<BeamFile>()),
        ("parts.beam.members", fields::<MemberFile>()),
        ("parts.box", fields::<BoxFile>()),
        ("parts.mesh", fields::<MeshFile>()),
        ("parts.interfaces", fields::<InterfaceFile>()),
        ("parts.reduction", fields::<ReductionFile>()),
        ("parts.reduction.load_points", fields::<LoadPointFile>()),
        ("analyses", fields::<AnalysisFile>()),
        ("analyses.supports", fields::<SupportFile>()),
        ("analyses.loads", fields::<NodalLoadFile>()),
        ("bodies", fields::<BodyFile>()),
        ("bodies.matrices", fields::<MatricesFile>()),
        ("bodies.rotation", fields::<RotationFile>()),
        ("bodies.damping", fields::<DampingFile>()),
        ("rigid_bodies", fields::<RigidBodyFile>()),
        ("point_masses", fields::<PointMassFile>()),
        ("springs", fields::<SpringFile>()),
        ("supports", fields::<MbsSupportFile>()),
        ("joints", fields::<JointFile>()),
        ("drivers", fields::<DriverFile>()),
        ("function", fields::<TimeFunctionFile>()),
        ("loads", fields::<LoadFile>()),
        ("sensors", fields::<SensorFile>()),
        ("initial", fields::<InitialFile>()),
        ("joint_springs", fields::<JointSpringFile>()),
        ("joint_limits", fields::<JointLimitFile>()),
        ("actuators", fields::<ActuatorFile>()),
        ("actuators.pid", fields::<PidFile>()),
        ("output", fields::<OutputFile>()),
        ("fmu", fields::<FmuFile>()),
    ]
}

#[test]
fn every_schema_field_has_a_registry_entry_and_every_entry_a_field() {
    let schema = schema_tables();
    let mut problems = Vec::new();
    for (path, fields) in &schema {
        let Some(table) = TABLES.iter().find(|t| t.path == *path) else {
            problems.push(format!("table `{path}` of the schema is not in the registry"));
            continue;
        };
        let registered: BTreeSet<String> = table.keys.iter().map(|k| k.name.to_string()).collect();
        for missing in fields.difference(&registered) {
            problems.push(format!(
                "`{path}`: the schema reads `{missing}`, the registry has no entry"
            ));
        }
        for extra in registered.difference(fields) {
            problems.push(format!(
                "`{path}`: the registry declares `{extra}`, the schema reads no such field"
            ));
        }
    }
    for t in TABLES.iter() {
        if !schema.iter().any(|(path, _)| *path == t.path) {
            problems.push(format!(
                "table `{}` of the registry is not a table of the schema",
                t.path
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "schema and key registry differ:\n{}",
        problems.join("\n")
    );
}

#[test]
fn entries_list_every_key_once_per_table() {
    let entries = keys::entries();
    let total: usize = TABLES.iter().map(|t| t.keys.len()).sum();
    assert_eq!(entries.len(), total);
    let e = entries
        .iter()
        .find(|e| e.table == "materials" && e.name == "E")
        .expect("materials.E");
    assert_eq!((e.ty, e.unit, e.required, e.range), ("number", "Pa", true, "> 0"));
}

fn doc_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/study-file.md")
}

/// A line diff (longest common subsequence) of `old` and `new`: the lines only in `old`
/// prefixed `-`, only in `new` `+`, with their line numbers, and nothing else.
fn diff(old: &str, new: &str) -> String {
    let a: Vec<&str> = old.lines().collect();
    let b: Vec<&str> = new.lines().collect();
    let mut lcs = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for i in (0..a.len()).rev() {
        for j in (0..b.len()).rev() {
            lcs[i][j] = if a[i] == b[j] {
                lcs[i + 1][j + 1] + 1
            } else {
                lcs[i + 1][j].max(lcs[i][j + 1])
            };
        }
    }
    let (mut i, mut j, mut out) = (0, 0, String::new());
    while i < a.len() || j < b.len() {
        if i < a.len() && j < b.len() && a[i] == b[j] {
            i += 1;
            j += 1;
        } else if j < b.len() && (i == a.len() || lcs[i][j + 1] >= lcs[i + 1][j]) {
            out.push_str(&format!("+{:>4}: {}\n", j + 1, b[j]));
            j += 1;
        } else {
            out.push_str(&format!("-{:>4}: {}\n", i + 1, a[i]));
            i += 1;
        }
    }
    out
}

#[test]
fn the_key_tables_of_the_study_file_doc_are_the_registry_s() {
    let path = doc_path();
    let doc = std::fs::read_to_string(&path).expect("docs/study-file.md");
    let rendered = keys::render_doc(&doc).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    if rendered == doc {
        return;
    }
    if std::env::var_os("FLEXMBS_BLESS").is_some_and(|v| v == "1") {
        std::fs::write(&path, &rendered).expect("write docs/study-file.md");
        return;
    }
    panic!(
        "the key tables of {} differ from the key registry (crates/study/src/input/keys/registry.toml); \
         change the registry, not the tables, and run `FLEXMBS_BLESS=1 cargo test -p study --test keys` \
         to rewrite them (- the doc, + the registry):\n{}",
        path.display(),
        diff(&doc, &rendered)
    );
}

#[test]
fn every_table_of_the_registry_is_in_the_doc() {
    let doc = std::fs::read_to_string(doc_path()).expect("docs/study-file.md");
    let missing: Vec<&str> = TABLES
        .iter()
        .filter(|t| !t.path.is_empty())
        .filter(|t| {
            !doc.contains(&format!("<!-- keys:{} begin -->", t.path))
                && !doc.contains(&format!("<!-- keys:{}:", t.path))
        })
        .map(|t| t.path)
        .collect();
    assert!(
        missing.is_empty(),
        "docs/study-file.md has no generated key table for: {}",
        missing.join(", ")
    );
}
