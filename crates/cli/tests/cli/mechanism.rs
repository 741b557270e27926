//! The mechanism in study files: the examples against their references (B1, B3), the results
//! a dynamic run streams (sensor CSV files with units, VTU/PVD, summary statistics), a solver
//! failure that keeps its partial results, and the errors only the assembled mechanism shows
//! (`tests/mechanism/*.toml`: a rigid loop, a coordinate held by nothing); a column as one
//! superelement with and without `geometric_stiffening` against the beam-column amplification;
//! the `newton = "modified"` option against full Newton.

use crate::support::*;
use std::path::Path;

/// The last row of a sensor CSV file, as numbers.
fn last_row(path: &Path) -> Vec<f64> {
    let (_, rows) = read_csv(path);
    rows.last().unwrap().iter().map(|c| c.parse().unwrap()).collect()
}

/// B1, a = 3 (Mattiasson 1981): w/L = 0.60325, u/L = 0.25442, tip rotation 0.98602.
#[test]
fn elastica_example_matches_mattiasson() {
    let dir = examples_copy("mech-elastica");
    let out = flexmbs(&dir, &["run", "elastica.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let results = dir.join("elastica-results/equilibrium");
    let (header, _) = read_csv(&results.join("tip.csv"));
    assert_eq!(
        header,
        [
            "load factor [-]",
            "displacement_x [m]",
            "displacement_y [m]",
            "displacement_z [m]"
        ]
    );
    let d = last_row(&results.join("tip.csv"));
    let r = last_row(&results.join("tip-rotation.csv"));
    assert_eq!(d[0], 1.0, "the full load is reached");
    // Discretisation: four superelements of three cubic beam elements each, static modes only;
    // the mbs convergence study puts the error of four segments below 1 % (measured 0.6 %).
    let tol = 1.5e-2;
    assert_close(d[2], 0.60325, tol, "w/L");
    assert_close(-d[1], 0.25442, tol, "u/L");
    assert_close(r[3], 0.98602, tol, "tip rotation");
}

/// `method = "arc-length"` follows the same path to the same equilibrium as load stepping: the
/// converged tip at load factor 1 agrees to the Newton tolerance, and the path has more points.
#[test]
fn elastica_by_arc_length_reaches_the_same_tip() {
    let dir = examples_copy("mech-elastica-arc");
    let study = std::fs::read_to_string(dir.join("elastica.toml")).unwrap();
    assert!(
        study.contains("steps = 4"),
        "the example's equilibrium analysis changed"
    );
    std::fs::write(
        dir.join("elastica.toml"),
        study.replace("steps = 4", "steps = 4\nmethod = \"arc-length\""),
    )
    .unwrap();
    let out = flexmbs(&dir, &["run", "elastica.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let (_, rows) = read_csv(&dir.join("elastica-results/equilibrium/tip.csv"));
    assert!(rows.len() > 2, "a path of several arcs, got {} rows", rows.len());
    let d = last_row(&dir.join("elastica-results/equilibrium/tip.csv"));
    assert!((d[0] - 1.0).abs() < 1e-12, "ends at load factor 1, got {}", d[0]);
    // Same discretisation as `elastica_example_matches_mattiasson` (0.6 % from Mattiasson).
    assert_close(d[2], 0.60325, 1.5e-2, "w/L");
    assert_close(-d[1], 0.25442, 1.5e-2, "u/L");
}

/// B3 (Simo & Vu-Quoc 1986, P = 300): tip at (58.84, 22.33, 40.08).
#[test]
fn bend45_example_matches_simo_vu_quoc() {
    let dir = examples_copy("mech-bend45");
    let out = flexmbs(&dir, &["run", "bend45.toml"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let p = last_row(&dir.join("bend45-results/equilibrium/tip.csv"));
    // Published solutions scatter by 0.5 %; four static-only superelements add about 1 %
    // (measured 1.1 % on z).
    let tol = 2e-2;
    for (k, reference) in [58.84, 22.33, 40.08].iter().enumerate() {
        assert_close(p[k + 1], *reference, tol, &format!("tip coordinate {k}"));
    }
    // The clamp's reaction balances the load P = 300 along z (equilibrium to the solver's
    // tolerance, 1e-10 relative).
    let r = last_row(&dir.join("bend45-results/equilibrium/root.csv"));
    assert_close(r[3], -300.0, 1e-8, "reaction Fz");
}

/// A short run of the slider-crank: sensor files stream with units, meshes and the summary.
#[test]
fn slider_crank_streams_sensors_meshes_and_statistics() {
    let dir = examples_copy("mech-slider");
    let out = flexmbs(&dir, &["run", "slider_crank.toml", "--t-end", "0.01"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let results = dir.join("slider_crank-results/run-up");
    let (header, rows) = read_csv(&results.join("rod-mid.csv"));
    assert_eq!(header, ["t [s]", "deflection [m]"]);
    assert_eq!(rows.len(), 101, "t = 0 and 100 steps of 1e-4 s");
    let (header, _) = read_csv(&results.join("energy.csv"));
    assert_eq!(header, ["t [s]", "kinetic [J]", "strain [J]", "gravity potential [J]"]);
    let angle = last_row(&results.join("crank-angle.csv"));
    // The driver prescribes the crank angle exactly: 150 rad/s * 0.01 s (round-off of t).
    assert!((angle[1] - 1.5).abs() < 1e-9, "crank angle {}", angle[1]);
    // vtu_every = 20: t = 0 and steps 20, 40, ..., 100.
    for k in 0..6 {
        assert!(results.join(format!("mechanism_{k:05}.vtu")).is_file(), "mesh {k}");
    }
    let pvd = std::fs::read_to_string(results.join("mechanism.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), 6, "{pvd}");
    assert!(results.join("rod-mid.png").is_file());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("slider_crank-results/summary.json")).unwrap()).unwrap();
    let r = &summary["analyses"][0]["results"];
    assert_eq!(r["steps"], 100);
    assert_eq!(r["rejected_steps"], 0);
    assert!(r["newton_iterations"].as_u64().unwrap() >= 100);
    // Crank driven; the rod as four welded superelements: 2 planar-revolute angles, 3 junction
    // nodes x 6, 4 bodies x 2 modes, and the slider's position along its guide = 29.
    assert_eq!(r["model"]["unknowns"], 29);
    assert_eq!(r["model"]["flexible_bodies"], 4);
    assert_eq!(r["model"]["modes_kept"][0]["modes"], 2);
}

/// A dynamic run whose Newton cannot converge (one iteration allowed, far too tight a
/// tolerance, no retry with smaller steps: `dt_min = dt`) stops with exit code 2 and keeps
/// what it computed.
#[test]
fn a_solver_failure_keeps_partial_results_and_fails() {
    let dir = examples_copy("mech-failure");
    let text = std::fs::read_to_string(dir.join("slider_crank.toml")).unwrap().replace(
        "rho_inf = 0.9",
        "rho_inf = 0.9\nmax_iterations = 1\ntolerance = 1e-14\ndt_min = 1e-4",
    );
    std::fs::write(dir.join("failing.toml"), text).unwrap();
    let out = flexmbs(&dir, &["run", "failing.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("Newton did not converge at t = 0.000100 (step 1)"),
        "{}",
        out.stderr
    );
    assert!(out.stderr.contains("relative residual"), "{}", out.stderr);
    let results = dir.join("failing-results");
    let (_, rows) = read_csv(&results.join("run-up/rod-mid.csv"));
    assert_eq!(rows.len(), 1, "the initial state is written");
    let summary = std::fs::read_to_string(results.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"failed\""), "{summary}");
    assert!(summary.contains("Newton did not converge"), "{summary}");
}

/// Ctrl-C during a dynamic run: the run stops at its next output step, keeps the rows it
/// wrote, says so, and `summary.json` says `interrupted`, not `running`.
#[test]
fn an_interrupted_run_keeps_its_rows_and_its_summary_says_interrupted() {
    let dir = examples_copy("mech-interrupt");
    // A run far too long to finish: only the interrupt ends it.
    let text = std::fs::read_to_string(dir.join("slider_crank.toml"))
        .unwrap()
        .replace("t_end = 0.126", "t_end = 1000.0");
    std::fs::write(dir.join("long.toml"), text).unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_flexmbs"))
        .args(["run", "long.toml"])
        .current_dir(&dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let results = dir.join("long-results");
    let csv = results.join("run-up/rod-mid.csv");
    let rows = |p: &Path| std::fs::read_to_string(p).map(|t| t.lines().count()).unwrap_or(0);
    // Wait (at most five minutes, a slow shared machine) until the dynamic run has written
    // a few rows: the interrupt then arrives mid-run.
    let start = std::time::Instant::now();
    while rows(&csv) < 5 {
        assert!(child.try_wait().unwrap().is_none(), "the run ended by itself");
        assert!(start.elapsed().as_secs() < 300, "no rows after five minutes");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let running = std::fs::read_to_string(results.join("summary.json")).unwrap();
    assert!(running.contains("\"status\": \"running\""), "{running}");
    let kill = std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("interrupted by the user"), "{stderr}");
    let summary = std::fs::read_to_string(results.join("summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"interrupted\""), "{summary}");
    assert!(!summary.contains("\"running\""), "{summary}");
    // Every row written is kept, each complete (header plus rows, all of one width).
    let (header, kept) = read_csv(&csv);
    assert!(kept.len() >= 4, "{} rows kept", kept.len());
    assert!(kept.iter().all(|r| r.len() == header.len()), "a partial row was kept");
}

/// A solver that fails at a body (the elastica under 1e10 times its load: the clamped
/// segment's floating frame is lost in Newton's first correction, its frame residual 1.2
/// after 30 iterations) is reported at that body's entry in the study file, as
/// `file:line:col: bodies[i]:` in front of what stopped, and the converged steps (none here)
/// are kept. (Under 1e6 times the load the frame solve follows the segments and the
/// equilibrium converges, stretched 24-fold: a load that cannot be carried has to be larger.)
#[test]
fn a_solver_failure_at_a_body_names_its_line_in_the_study_file() {
    let dir = examples_copy("mech-located-failure");
    let text = std::fs::read_to_string(dir.join("elastica.toml"))
        .unwrap()
        .replace("force = [0.0, 3.0, 0.0]", "force = [0.0, 3.0e10, 0.0]");
    std::fs::write(dir.join("overloaded.toml"), &text).unwrap();
    let out = flexmbs(&dir, &["run", "overloaded.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    // The body the solver names, and its entry: `[[bodies]]`, then its name (1-based lines
    // `name_line` and `name_line + 1`).
    let body = out
        .stderr
        .split("body '")
        .nth(1)
        .and_then(|s| s.split('\'').next())
        .unwrap_or_else(|| panic!("no body named: {}", out.stderr));
    let lines: Vec<&str> = text.lines().collect();
    let name_line = lines
        .iter()
        .position(|l| l.trim() == format!("name = \"{body}\""))
        .unwrap();
    assert_eq!(lines[name_line - 1].trim(), "[[bodies]]");
    let index = lines[..name_line].iter().filter(|l| l.trim() == "[[bodies]]").count() - 1;
    let located = [name_line, name_line + 1].iter().any(|l| {
        out.stderr
            .contains(&format!("overloaded.toml:{l}:1: bodies[{index}]: equilibrium stopped"))
    });
    assert!(located, "{}", out.stderr);
    assert!(out.stderr.contains("floating frame"), "{}", out.stderr);
    let summary = std::fs::read_to_string(dir.join("overloaded-results/summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"failed\""), "{summary}");
    assert!(summary.contains(&format!("bodies[{index}]")), "{summary}");
}

/// `newton = "modified"` in a dynamic analysis: the slider-crank follows the full-Newton run
/// with fewer factorisations (reported in the summary); an unknown strategy is refused at its
/// key.
#[test]
fn modified_newton_option_follows_full_newton() {
    let dir = examples_copy("mech-newton");
    let text = std::fs::read_to_string(dir.join("slider_crank.toml")).unwrap();
    std::fs::write(
        dir.join("modified.toml"),
        text.replace("rho_inf = 0.9", "rho_inf = 0.9\nnewton = \"modified\""),
    )
    .unwrap();
    std::fs::write(
        dir.join("typo.toml"),
        text.replace("rho_inf = 0.9", "rho_inf = 0.9\nnewton = \"modifed\""),
    )
    .unwrap();
    let summary = |name: &str| -> serde_json::Value {
        let path = dir.join(format!("{name}-results/summary.json"));
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    };
    for name in ["slider_crank", "modified"] {
        let out = flexmbs(&dir, &["run", &format!("{name}.toml"), "--t-end", "0.01"]);
        assert_eq!(out.code, 0, "{}", out.stderr);
    }
    let (full, modified) = (summary("slider_crank"), summary("modified"));
    let (f, m) = (&full["analyses"][0]["results"], &modified["analyses"][0]["results"]);
    assert_eq!(
        (f["newton"].as_str(), m["newton"].as_str()),
        (Some("full"), Some("modified"))
    );
    assert_eq!(m["steps"], 100);
    // Full Newton factorises at every correction, modified Newton keeps its matrix.
    assert_eq!(f["jacobians"], f["newton_iterations"]);
    assert!(
        m["jacobians"].as_u64().unwrap() < f["jacobians"].as_u64().unwrap() / 2,
        "{m}"
    );
    let deflection = |name: &str| last_row(&dir.join(format!("{name}-results/run-up/rod-mid.csv")))[1];
    let (wf, wm) = (deflection("slider_crank"), deflection("modified"));
    // Both stop each step at a relative residual of 1e-9: 100 steps differ by at most
    // 100 x 1e-9 of the deflection (plus the CSV's printed digits).
    assert!((wf - wm).abs() <= 1e-7 * wf.abs() + 1e-12, "{wf} vs {wm}");
    let out = flexmbs(&dir, &["check", "typo.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr
            .contains("analyses[0].newton: unknown Newton strategy 'modifed'"),
        "{}",
        out.stderr
    );
}

/// Errors that need the assembled mechanism: reported at the entity named, exit code 2.
#[test]
fn mechanism_errors_found_at_run_time_are_located() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mechanism");
    let dir = scratch("mech-errors");
    copy_dir(&src, &dir);
    let out = flexmbs(&dir, &["run", "rigid_loop.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("rigid_loop.toml:1:1: rigid_bodies[0]: the mechanism cannot be assembled: closed loop of rigid bodies and joints"),
        "{}",
        out.stderr
    );
    assert!(out.stderr.contains("joints [elbow, pivot]"), "{}", out.stderr);
    let out = flexmbs(&dir, &["run", "unheld.toml"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains(
            "unheld.toml:8:1: joints[0]: the mechanism cannot be assembled: joint 'pivot' angle is held by nothing"
        ),
        "{}",
        out.stderr
    );
}

/// `flexmbs validate` forwards to the validation suite's command line.
#[cfg(feature = "validate")]
#[test]
fn validate_forwards_its_arguments() {
    let dir = scratch("mech-validate");
    let out = flexmbs(&dir, &["validate", "--help"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(out.stdout.contains("[--quick]"), "{}", out.stdout);
    let out = flexmbs(&dir, &["validate", "--no-such-option"]);
    assert_eq!(out.code, 2, "{}", out.stderr);
    assert!(
        out.stderr.contains("unknown argument '--no-such-option'"),
        "{}",
        out.stderr
    );
}

/// A linearized analysis writes each mode's frequency, damping ratio and the body and node
/// that carry its energy (`modes.csv`, `mbs::mode_energies`): in the four-bar the coupler is
/// the only flexible body, so it carries the strain energy of every elastic mode. The
/// linearized analysis runs alone (`--analysis`): the equilibrium its `start` names runs
/// first, the dynamic run not at all.
#[test]
fn linearized_modes_are_labelled_by_body_and_node() {
    let dir = examples_copy("mech-four-bar-modes");
    let out = flexmbs(&dir, &["run", "four_bar.toml", "--analysis", "nowhere"]);
    assert_eq!(out.code, 2);
    assert!(
        out.stderr.contains("nowhere") && out.stderr.contains("linearized"),
        "{}",
        out.stderr
    );
    let out = flexmbs(&dir, &["run", "four_bar.toml", "--analysis", "linearized"]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let results = dir.join("four_bar-results");
    assert!(results.join("at-rest").is_dir(), "the equilibrium ran first");
    assert!(!results.join("dynamic").exists(), "only the chain of `start` runs");
    let found: Vec<_> = std::fs::read_dir(dir.join("four_bar-results"))
        .unwrap()
        .map(|e| e.unwrap().path().join("modes.csv"))
        .filter(|p| p.is_file())
        .collect();
    assert_eq!(found.len(), 1, "one linearized analysis");
    let (header, rows) = read_csv(&found[0]);
    assert_eq!(
        header,
        [
            "mode",
            "frequency [Hz]",
            "damping ratio [-]",
            "rigid body [-]",
            "carried by",
            "growth rate [1/s]"
        ]
    );
    assert!(!rows.is_empty());
    let mut last = 0.0;
    for r in &rows {
        let f: f64 = r[1].parse().unwrap();
        assert!(f >= last, "ascending frequencies");
        last = f;
        // The label holds a comma, so the writer quotes it; `read_csv` splits at every comma.
        let label = r[4..r.len() - 1].join(",");
        let label = label.trim_matches('"');
        assert!(label.starts_with("coupler ("), "label {label:?}");
        assert!(label.contains("), node coupler."), "label {label:?}");
    }
    assert!(out.stdout.contains("mode 1: "), "{}", out.stdout);
}

/// A clamped-free column (EI = 1 N m^2, L = 1 m) as ONE superelement under the axial load
/// P = 0.4 P_cr and a small lateral tip force H, with and without `geometric_stiffening = true`
/// in `[parts.reduction]`: with it the lateral tip deflection is the beam-column one,
/// H L^3/(3 EI) times the exact amplification 3 (tan kL - kL)/(kL)^3 (k^2 = P/EI), within
/// 1 %; without it the amplification is visibly smaller.
#[test]
fn geometric_stiffening_option_amplifies_a_column_deflection() {
    let pi2 = std::f64::consts::PI.powi(2);
    let (p, h) = (0.4 * pi2 / 4.0, 1e-3);
    let study = |geometric: bool| {
        format!(
            r#"
[study]
title = "column under axial load, one superelement"

[[materials]]
name = "m"
E = 1.2e9
nu = 0.3
rho = 1000.0

[[sections]]
name = "square"
shape = "rectangle"
b = 0.01
h = 0.01

[[parts]]
name = "column"
material = "m"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [1.0, 0.0, 0.0]
elements = 8
section = "square"
theory = "euler-bernoulli"
[[parts.interfaces]]
name = "a"
set = "column.start"
[[parts.interfaces]]
name = "b"
set = "column.end"
[parts.reduction]
modes = 4
geometric_stiffening = {geometric}

[[bodies]]
name = "c"
part = "column"
position = [0.0, 0.0, 0.0]

[[supports]]
at = "c.a"
type = "clamp"

[[loads]]
name = "P"
type = "point"
at = "c.b"
force = [{fx}, {h}, 0.0]

[[sensors]]
name = "tip"
type = "displacement"
of = "c.b"

[[analyses]]
type = "equilibrium"
steps = 2
"#,
            fx = -p
        )
    };
    let kl = p.sqrt();
    let exact = 3.0 * (kl.tan() - kl) / kl.powi(3);
    let d0 = h / 3.0;
    let mut amplification = Vec::new();
    for geometric in [true, false] {
        let dir = scratch(&format!("mech-geometric-{geometric}"));
        std::fs::write(dir.join("column.toml"), study(geometric)).unwrap();
        let out = flexmbs(&dir, &["run", "column.toml"]);
        assert_eq!(out.code, 0, "{}", out.stderr);
        assert_eq!(
            out.stderr.contains("with geometric stiffening"),
            geometric,
            "{}",
            out.stderr
        );
        let d = last_row(&dir.join("column-results/equilibrium/tip.csv"));
        amplification.push(d[2] / d0);
    }
    eprintln!(
        "amplification with G {}, without {}, exact {exact}",
        amplification[0], amplification[1]
    );
    assert_close(amplification[0], exact, 1e-2, "amplification with geometric stiffening");
    assert!(amplification[1] < exact - 0.1, "{amplification:?} vs {exact}");
}
