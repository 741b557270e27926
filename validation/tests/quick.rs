//! The quick subset of the validation suite, run by `cargo test`: every row within the
//! tolerance its table states (each table's note says why that tolerance).

use validation::{run_all, Extent};

#[test]
fn quick_subset_within_tolerances() {
    let tables = run_all(Extent::Quick).expect("every quick benchmark runs");
    let mut failures = Vec::new();
    for t in &tables {
        for r in &t.rows {
            if !r.passes() {
                failures.push(format!(
                    "{}: {}: {} vs {} ({:.2e} > {:.0e})",
                    t.title,
                    r.quantity,
                    r.ours,
                    r.reference,
                    r.relative_error(),
                    r.tolerance
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
