//! The command line of `flexmbs validate` (and of the `validation` binary): ids are checked
//! before anything runs, `--only` stops at the next option, the report goes to the current
//! folder unless told otherwise, and the usage names the program it was called as.

use std::path::Path;
use validation::{check_ids, parse_args, selects, usage, Extent, DEFAULT_REPORT_DIR};

fn args(s: &str) -> Vec<String> {
    s.split_whitespace().map(String::from).collect()
}

#[test]
fn an_unknown_id_is_an_error_naming_the_ids_there_are() {
    let e = parse_args(&args("--only Z")).unwrap_err();
    assert!(e.contains("'Z'") && e.contains("B1") && e.contains("C4"), "{e}");
    let e = check_ids(&["C2".into(), "D7".into(), "x".into()]).unwrap_err();
    assert!(e.contains("'D7', 'x'") && !e.contains("'C2'"), "{e}");
}

#[test]
fn only_stops_at_the_next_option() {
    let o = parse_args(&args("--only B1 C2 --quick --no-report")).unwrap();
    assert_eq!(o.only, ["B1", "C2"]);
    assert_eq!(o.extent, Extent::Quick);
    assert!(!o.write);
    let o = parse_args(&args("--only b1,C2")).unwrap();
    assert_eq!(o.only, ["b1", "C2"]);
    assert!(parse_args(&args("--only --quick")).is_err());
}

#[test]
fn grouped_problems_are_selected_one_by_one_too() {
    for id in ["A1", "a2", "A3", "A4", "A1-A4"] {
        assert!(selects(id, "A1-A4"), "{id}");
    }
    for id in ["A5", "B1", "A", "A0", ""] {
        assert!(!selects(id, "A1-A4"), "{id}");
    }
    assert!(selects("v", "V") && selects("C3", "C3") && !selects("C3", "C4"));
}

#[test]
fn the_default_report_folder_is_in_the_current_folder_not_the_source_tree() {
    let o = parse_args(&[]).unwrap();
    assert_eq!(o.dir, Path::new(DEFAULT_REPORT_DIR));
    assert!(o.dir.is_relative());
    assert!(!o.dir.starts_with(env!("CARGO_MANIFEST_DIR")));
    let o = parse_args(&args("--report-dir /tmp/somewhere")).unwrap();
    assert_eq!(o.dir, Path::new("/tmp/somewhere"));
    assert!(parse_args(&args("--report-dir")).is_err());
    assert!(parse_args(&args("--report-dir --quick")).is_err());
}

#[test]
fn full_precision_prints_tables_to_round_trip_digits() {
    assert!(!parse_args(&[]).unwrap().full_precision);
    assert!(parse_args(&args("--full-precision --quick")).unwrap().full_precision);
    let table = validation::Table {
        title: "T".into(),
        note: String::new(),
        rows: vec![validation::Row::new("q", 1.0 / 3.0, 0.1 + 0.2, 1.0)],
    };
    assert!(table.markdown().contains("| q | 3.333333e-1 | 3.000000e-1 |"));
    validation::set_full_precision(true);
    let precise = table.markdown();
    let sci = validation::sci(0.1 + 0.2);
    validation::set_full_precision(false);
    // 17 significant digits read back to the same f64.
    assert!(
        precise.contains("| q | 3.3333333333333331e-1 | 3.0000000000000004e-1 |"),
        "{precise}"
    );
    assert_eq!(sci.parse::<f64>().unwrap(), 0.1 + 0.2);
}

#[test]
fn the_usage_names_the_program_and_every_id() {
    let u = usage("flexmbs validate");
    assert!(u.starts_with("usage: flexmbs validate "), "{u}");
    assert!(!u.contains("usage: validation"), "{u}");
    for id in ["A1-A4", "A5", "B3", "C4", "V"] {
        assert!(u.contains(id), "{id} missing from:\n{u}");
    }
    assert!(parse_args(&args("--help")).unwrap().help);
}
