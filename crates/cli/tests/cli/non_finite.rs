//! Values that are not finite stop static analyses the way they stop dynamic runs.

use crate::support::*;

/// The cart of the study crate's `pendulum_cart.toml`, started at the post (`initial = 1` m of
/// its rail, so the `gap` sensor is 0/0), in an `equilibrium` analysis: the run stops with
/// exit code 2, the sensor named at its line with the load factor, and `summary.json` says
/// `failed`; no row of the sensor is written.
#[test]
fn an_equilibrium_whose_sensor_is_not_finite_fails_with_the_sensor_named() {
    let dir = scratch("non-finite-equilibrium");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../study/tests/studies/pendulum_cart.toml"),
    )
    .unwrap();
    let head = &text[..text.find("[[analyses]]").unwrap()];
    let text = format!(
        "{}[[analyses]]\ntype = \"equilibrium\"\nname = \"at-rest\"\n",
        head.replace("speed = 10.0 }", "speed = 10.0, initial = 1.0 }")
    );
    assert!(text.contains("initial = 1.0"));
    std::fs::write(dir.join("cart.toml"), &text).unwrap();
    let out = flexmbs(&dir, &["run", "cart.toml"]);
    assert_eq!(out.code, 2, "{}\n{}", out.stdout, out.stderr);
    assert!(
        out.stderr.contains("sensors[1]")
            && out.stderr.contains("sensor 'gap'")
            && out.stderr.contains("load factor 1.000000"),
        "{}",
        out.stderr
    );
    let results = dir.join("cart-results");
    let summary = std::fs::read_to_string(results.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"failed\""), "{summary}");
    assert!(summary.contains("sensor 'gap'"), "{summary}");
    if let Ok(csv) = std::fs::read_to_string(results.join("at-rest/gap.csv")) {
        assert!(!csv.to_lowercase().contains("nan"), "{csv}");
    }
}
