#![allow(non_snake_case)]

//! Linearised verdicts at every size and in any units, and values that are not finite stopping
//! the static analyses: study files run in memory.

use nalgebra::DMatrix;
use reduction::ReducedBody;
use study::output::observer::Recorder;
use study::output::summary::Summary;

/// `text` run in memory in a scratch folder `name` (`setup::run`): the recorder and the summary.
fn run(name: &str, text: &str) -> (Recorder, Result<Summary, String>) {
    let (rec, summary, _) = crate::setup::run(name, text);
    (rec, summary)
}

/// The modal analysis of the reduced body with its interface `clamped` removed: the
/// frequencies \[Hz\] of the generalised symmetric eigenproblem K q = w^2 M q of its
/// Craig-Bampton matrices without that interface's six coordinates (Cholesky M = L L^T, the
/// symmetric eigenvalues of L^-1 K L^-T), ascending. Independent of the mechanism: no
/// frames, no joints, no state-space form.
fn reduced_modal_frequencies(body: &ReducedBody, clamped: usize) -> Vec<f64> {
    let n = body.K_CB.nrows;
    let kept: Vec<usize> = (0..n)
        .filter(|i| i / 6 != clamped || *i >= 6 * body.interfaces.len())
        .collect();
    let sub =
        |A: &reduction::DenseMatrix| DMatrix::from_fn(kept.len(), kept.len(), |i, j| A.data[kept[j] * n + kept[i]]);
    let (K, M) = (sub(&body.K_CB), sub(&body.M_CB));
    let L = M.cholesky().expect("the reduced mass is positive definite").l();
    let Li = L.try_inverse().expect("the Cholesky factor is invertible");
    let B = &Li * K * Li.transpose();
    let B = (&B + B.transpose()) * 0.5;
    let mut f: Vec<f64> = B
        .symmetric_eigenvalues()
        .iter()
        .map(|w2| w2.sqrt() / (2.0 * std::f64::consts::PI))
        .collect();
    f.sort_by(f64::total_cmp);
    f
}

fn results(rec: &Recorder, analysis: &str) -> serde_json::Value {
    let a = rec
        .analysis(analysis)
        .unwrap_or_else(|| panic!("no analysis {analysis}"));
    a.summary.as_ref().unwrap().results.clone()
}

fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// The steel cantilever of `examples/cantilever.toml` (20 x 40 mm, 2 m, Euler-Bernoulli, 20
/// elements) scaled geometrically by `scale` and written in units where lengths are `unit`
/// metres (1: SI; 1e-3: mm-tonne-second, E in MPa, rho in t/mm^3): a flexible body of the
/// part reduced with 4 modes, clamped at its root; the clamped part's FE modes and the
/// linearised spectrum of the mechanism.
fn cantilever(scale: f64, unit: f64) -> String {
    let L = 2.0 * scale / unit;
    let (b, h) = (0.02 * scale / unit, 0.04 * scale / unit);
    // Forces stay in N, so the mass unit is 1/unit kg (mm: the tonne): Pa -> N/unit^2 (mm:
    // MPa), kg/m^3 -> unit^4 of them (mm: t/mm^3).
    let (E, rho) = (210e9 * unit * unit, 7850.0 * unit.powi(4));
    format!(
        r#"
[study]
title = "steel cantilever, {scale} x the example, lengths in {unit} m"

[[materials]]
name = "steel"
E = {E:e}
nu = 0.3
rho = {rho:e}

[[sections]]
name = "bar"
shape = "rectangle"
b = {b:e}
h = {h:e}

[[parts]]
name = "beam"
material = "steel"
[parts.beam]
kind = "straight"
from = [0.0, 0.0, 0.0]
to = [{L:e}, 0.0, 0.0]
elements = 20
section = "bar"
orientation = [0.0, 1.0, 0.0]
theory = "euler-bernoulli"
[[parts.interfaces]]
name = "root"
set = "beam.start"
[[parts.interfaces]]
name = "tip"
set = "beam.end"
[parts.reduction]
modes = 4

[[bodies]]
name = "c"
part = "beam"
position = [0.0, 0.0, 0.0]

[[supports]]
at = "c.root"
type = "clamp"

[[analyses]]
type = "modal"
name = "clamped"
part = "beam"
modes = 4
supports = [{{ at = "root" }}]

[[analyses]]
type = "linearized"
name = "linearized"
modes = 10
"#
    )
}

/// The cantilever at 20 mm, 2 m and 200 m, and at 2 m in mm-tonne-second units: every
/// linearised spectrum is stable (no growing eigenvalue), its frequencies scale as 1/L (the
/// same geometry) and do not depend on the units, to 1e-6 relative; every one is the modal
/// analysis of the same reduced body clamped at its root to 1e-6 (the solver's error, not
/// the reduction's), and the lowest pair (the first bending mode in each plane) is the
/// clamped part's FE one within the reduction's error (4 fixed-interface modes and the tip's
/// static modes).
#[test]
fn a_clamped_cantilever_is_stable_at_every_size_and_in_any_units() {
    let mut spectra = Vec::new();
    for (tag, scale, unit) in [
        ("cantilever-20mm", 0.01, 1.0),
        ("cantilever-2m", 1.0, 1.0),
        ("cantilever-200m", 100.0, 1.0),
        ("cantilever-2m-in-mm", 1.0, 1e-3),
    ] {
        let (rec, summary, file) = crate::setup::run(tag, &cantilever(scale, unit));
        summary.unwrap_or_else(|e| panic!("{tag}: {e}"));
        let r = results(&rec, "linearized");
        assert_eq!(r["stable"], serde_json::json!(true), "{tag}: {r}");
        // No real part above the round-off bound (mbs::GROWTH_TOLERANCE of the spectrum's
        // scale): nothing grows, so no growth rate is reported.
        assert!(r["growing_eigenvalues"].as_array().unwrap().is_empty(), "{tag}: {r}");
        assert!(r["largest_growth_rate"].is_null(), "{tag}: {r}");
        let linearized = numbers(&r["frequencies_hz"]);
        let fe = numbers(&results(&rec, "clamped")["frequencies_hz"]);
        eprintln!("{tag}: linearized {linearized:?}\n  FE {fe:?}");
        let (body, _) = crate::setup::first_body(&file);
        let root = body
            .interfaces
            .iter()
            .position(|i| i.name == "root")
            .expect("interface root");
        let reduced = reduced_modal_frequencies(&body, root);
        assert_eq!(linearized.len(), reduced.len(), "{tag}: {linearized:?} vs {reduced:?}");
        for (k, (f, r)) in linearized.iter().zip(&reduced).enumerate() {
            assert!((f - r).abs() <= 1e-6 * r, "{tag}, mode {k}: {f} vs reduced modal {r}");
        }
        let worst = linearized
            .iter()
            .zip(&reduced)
            .map(|(f, r)| (f - r).abs() / r)
            .fold(0.0, f64::max);
        eprintln!("{tag}: largest relative difference to the reduced modal analysis {worst:.2e}");
        // The reduced body is stiffer than the FE beam by 1.55e-5 in its first mode (the
        // reduction's error: 4 fixed-interface modes; 3.5e-4 in the second).
        let (f, exact) = (linearized[0], fe[0]);
        assert!(f >= exact && f - exact <= 2e-5 * exact, "{tag}: {f} vs FE {exact}");
        spectra.push((tag, scale, linearized));
    }
    let (_, _, reference) = &spectra[1];
    for (tag, scale, f) in &spectra {
        assert_eq!(f.len(), reference.len(), "{tag}");
        for (k, (a, b)) in f.iter().zip(reference).enumerate() {
            assert!(
                (a * scale - b).abs() <= 1e-6 * b,
                "{tag}, mode {k}: {a} x {scale} vs 2 m {b}"
            );
        }
    }
}

/// The cart of `pendulum_cart.toml` starting at the post (`initial = 1` m of its rail), so
/// the `gap` sensor (the deflection of post.R from the line through cart.P and post.Q) is
/// 0/0 from the start, with a torsional spring on the pendulum's pivot (the stiffness an
/// arc-length step needs at load factor 0) and `analysis` instead of the file's dynamic one.
fn cart_at_the_post(analysis: &str) -> String {
    let text = include_str!("../studies/pendulum_cart.toml");
    let head = &text[..text.find("[[analyses]]").unwrap()];
    let head = head.replace("speed = 10.0 }", "speed = 10.0, initial = 1.0 }");
    assert!(head.contains("initial = 1.0"));
    let spring = "[[joint_springs]]\nname = \"hold\"\njoint = \"pivot\"\nstiffness = 10.0\n";
    format!("{head}{spring}[[analyses]]\n{analysis}\n")
}

/// Static analyses stop on a sensor that is not finite, as dynamic runs do: the equilibrium
/// (load stepping and arc length), the buckling analysis (its equilibrium under the full
/// load) and a linearised analysis about the equilibrium fail with the sensor named, its key
/// located and the load factor said; the equilibrium writes no row of it.
#[test]
fn a_sensor_that_is_not_finite_stops_the_static_analyses() {
    for (tag, analysis) in [
        ("nan-equilibrium", "type = \"equilibrium\"\nname = \"eq\""),
        (
            "nan-arc-length",
            "type = \"equilibrium\"\nname = \"eq\"\nmethod = \"arc-length\"",
        ),
        ("nan-buckling", "type = \"buckling\"\nname = \"eq\""),
        (
            "nan-linearized",
            "type = \"linearized\"\nname = \"eq\"\nabout = \"equilibrium\"",
        ),
    ] {
        let (rec, summary) = run(tag, &cart_at_the_post(analysis));
        let stopped = summary.expect_err(tag);
        assert!(stopped.contains("analysis 'eq'"), "{tag}: {stopped}");
        let recorded = rec.analysis("eq").unwrap_or_else(|| panic!("{tag}: not recorded"));
        let s = recorded.summary.as_ref().unwrap();
        assert!(s.status.to_string().contains("failed"), "{tag}: {:?}", s.status);
        let e = s.error.clone().unwrap_or_default();
        assert!(
            e.contains("sensor 'gap'") && e.contains("no longer finite"),
            "{tag}: {e}"
        );
        if tag != "nan-linearized" {
            assert!(
                e.contains("load factor 1.000000") && e.contains("sensors[1]"),
                "{tag}: {e}"
            );
        }
        if let Some(sensors) = &recorded.sensors {
            let gap = sensors.column("gap", 0).unwrap();
            assert!(gap.iter().all(|x| x.is_finite()), "{tag}: {gap:?}");
        }
    }
    // The same cart 1 m before the post: every analysis completes.
    let text = cart_at_the_post("type = \"equilibrium\"\nname = \"eq\"").replace(", initial = 1.0", "");
    run("finite-equilibrium", &text).1.unwrap();
}
